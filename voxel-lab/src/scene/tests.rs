use voxel_core::{Pattern, RenderClass};

use super::*;

const GOOD: &str = r#"
name = "test"
size = [64, 32]

[[blocks]]
name = "smoky_glass"
color = [90, 90, 100]
opacity = 0.5

[[boxes]]
block = "smoky_glass"
min = [0, 0, 0]
max = [3, 2, 0]

[[cameras]]
eye = [0.5, 1.0, 10.0]
target = [0.5, 1.0, 0.0]
path_to = [3.0, 1.0, 10.0]
"#;

#[test]
fn a_good_file_parses() {
    let s = parse(GOOD).unwrap();
    assert_eq!(s.name, "test");
    assert_eq!(s.size, Some((64, 32)));
    assert_eq!(s.cameras.len(), 1);
    assert_eq!(s.paths[0], Some(DVec3::new(3.0, 1.0, 10.0)));
    let smoky = s.world.registry().id("smoky_glass").unwrap();
    assert_eq!(s.world.get_block(WorldPos::new(3, 2, 0)), smoky);
    assert_eq!(
        s.world.get_block(WorldPos::new(4, 2, 0)),
        voxel_core::BlockId::AIR
    );
}

#[test]
fn blocks_take_textures_patterns_and_classes_from_the_file() {
    let dir = std::env::temp_dir().join(format!("voxel_scene_tex_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = |name: &str, w: u32, h: u32, rgba: [u8; 4]| {
        voxel_render::Image {
            width: w,
            height: h,
            rgba: rgba.repeat((w * h) as usize),
        }
        .save_png(&dir.join(name))
        .unwrap();
    };
    png("all.png", 8, 8, [200, 10, 10, 255]);
    png("top.png", 4, 4, [10, 200, 10, 255]);
    png("wide.png", 8, 4, [0, 0, 0, 255]);
    let text = |extra: &str| {
        format!(
            "name = \"t\"\n[[blocks]]\nname = \"b\"\ncolor = [1, 2, 3]\nopacity = 1.0\n{extra}\n\
             [[cameras]]\neye = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n"
        )
    };
    let block = |extra: &str| {
        let scene = parse_in(&text(extra), &dir).unwrap();
        let r = scene.world.registry().clone();
        r.get(r.id("b").unwrap()).unwrap().clone()
    };
    let b = block("texture = \"all.png\"\ntop = \"top.png\"\nclass = \"cutout\"");
    assert_eq!(b.class, RenderClass::Cutout);
    assert_eq!(b.pattern, Pattern::Leaves);
    let top = b.images.top.unwrap();
    assert_eq!((top.size(), top.texel(0, 0)), (4, [10, 200, 10, 255]));
    assert_eq!(b.images.side.unwrap().texel(3, 3), [200, 10, 10, 255]);
    assert_eq!(b.images.bottom.unwrap().size(), 8);
    let g = block("pattern = \"grass\"\nsoil = [9, 8, 7]");
    assert_eq!(g.pattern, Pattern::Grass { soil: [9, 8, 7] });
    assert!(g.images.is_empty());
    let err = |extra: &str| parse_in(&text(extra), &dir).unwrap_err().to_string();
    let e = err("side = \"wide.png\"");
    assert!(
        e.starts_with("6: blocks.side: ") && e.contains("wide.png") && e.contains("square"),
        "{e}"
    );
    let e = err("top = \"missing.png\"");
    assert!(
        e.starts_with("6: blocks.top: ") && e.contains("missing.png"),
        "{e}"
    );
    let e = err("pattern = \"marble\"");
    assert!(e.contains("blocks.pattern") && e.contains("marble"), "{e}");
    let e = err("pattern = \"grass\"");
    assert!(e.contains("soil"), "{e}");
    let e = err("class = \"gas\"");
    assert!(e.contains("blocks.class") && e.contains("gas"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_framing_camera_shows_the_whole_box_tightly() {
    for (min, max) in [
        ([0, 0, 0], [0, 0, 0]),
        ([0, 0, 0], [63, 23, 55]),
        ([-40, 5, 7], [300, 9, 12]),
        ([0, 0, 0], [3, 200, 3]),
    ] {
        let (lo, hi) = (
            WorldPos::new(min[0], min[1], min[2]),
            WorldPos::new(max[0], max[1], max[2]),
        );
        let (cam, path_to) = framing_camera(lo, hi).unwrap();
        // The renderer's own projection, square: every corner inside, one near an edge.
        let vp = cam.view_proj(1.0);
        let mut widest = 0.0f32;
        for k in 0..8 {
            let pick = |bit: i32, a: i32, b: i32| f64::from(if k & bit == 0 { a } else { b + 1 });
            let c = DVec3::new(
                pick(1, min[0], max[0]),
                pick(2, min[1], max[1]),
                pick(4, min[2], max[2]),
            ) - cam.eye;
            let p = vp * c.as_vec3().extend(1.0);
            let ndc = p.truncate() / p.w;
            assert!(p.w > 0.0 && ndc.z > 0.0 && ndc.z < 1.0, "{min:?}: {ndc}");
            assert!(ndc.x.abs() <= 0.93 && ndc.y.abs() <= 0.93, "{min:?}: {ndc}");
            widest = widest.max(ndc.x.abs()).max(ndc.y.abs());
        }
        assert!(widest > 0.85, "{min:?}..{max:?}: framed loosely ({widest})");
        // From above, and the flicker path stays as far from the box.
        assert!(cam.forward.y < -0.5);
        let centre = DVec3::new(
            f64::from(min[0] + max[0] + 1),
            f64::from(min[1] + max[1] + 1),
            f64::from(min[2] + max[2] + 1),
        ) * 0.5;
        let (a, b) = ((cam.eye - centre).length(), (path_to - centre).length());
        assert!((a - b).abs() < 1e-6 * a);
    }
}

#[test]
fn an_unknown_block_names_the_line_and_lists_the_known_ones() {
    let bad = GOOD.replace("block = \"smoky_glass\"", "block = \"lava\"");
    let e = parse(&bad).unwrap_err().to_string();
    assert!(
        e.starts_with("11: boxes.block: unknown block name \"lava\""),
        "{e}"
    );

    assert!(e.contains("water") && e.contains("smoky_glass"), "{e}");
}

#[test]
fn syntax_and_type_errors_name_line_and_field() {
    let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [3, 2]"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("13: boxes.max:") && e.contains("length 3"),
        "{e}"
    );

    let e = parse(&GOOD.replace("fov", "x").replace("path_to", "pathto"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("pathto"), "unknown keys are named: {e}");
    let e = parse("name = \"x\"\n[[cameras]]\neye = [0, 0, 0]\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("target"), "missing keys are named: {e}");
    let e = parse("name = \"x\"\nsize = [64, 32\n")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("2:") || e.starts_with("3:"), "{e}");
}

/// Fixed-length arrays take exactly their length (a longer list is an error naming
/// the field, not its first values), and a table missing a field names that table.
#[test]
fn arrays_of_the_wrong_length_and_missing_fields_name_their_table() {
    for (from, to, field) in [
        (
            "eye = [0.5, 1.0, 10.0]",
            "eye = [0.5, 1.0, 10.0, 4.0]",
            "cameras.eye",
        ),
        ("size = [64, 32]", "size = [64, 32, 3]", "size"),
        ("max = [3, 2, 0]", "max = [3, 2, 0, 0]", "boxes.max"),
        (
            "color = [90, 90, 100]",
            "color = [90, 90, 100, 1]",
            "blocks.color",
        ),
    ] {
        assert!(GOOD.contains(from), "{from}");
        let e = parse(&GOOD.replace(from, to)).unwrap_err().to_string();
        assert!(
            e.contains(field) && (e.contains('3') || e.contains('2')),
            "{to}: {e}"
        );
    }
    let particles = |extra: &str| {
        format!(
            "{GOOD}\n[[particles]]\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n\
             color = [1, 2, 3]\nopacity = 0.5\n{extra}"
        )
    };
    parse(&particles("count = 3")).unwrap();
    let e = parse(&particles("")).unwrap_err().to_string();
    assert!(e.contains("particles") && e.contains("count"), "{e}");
    assert!(!e.contains("boxes") && !e.contains("cameras"), "{e}");
    let e = parse(&particles("count = 3").replace("color = [1, 2, 3]", "color = [1, 2, 3, 4]"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particles.color") && e.contains("length 3"),
        "{e}"
    );
    let e = parse(&format!(
        "{GOOD}\n[[entities]]\ncenter = [0.0, 0.0, 0.0]\nsize = [1.0, 1.0]\ncolor = [1, 2, 3]\n"
    ))
    .unwrap_err()
    .to_string();
    assert!(e.contains("entities.size") && e.contains("length 3"), "{e}");
}

#[test]
fn bad_values_are_errors_not_panics() {
    let e = parse(&GOOD.replace("target = [0.5, 1.0, 0.0]", "target = [0.5, 1.0, 10.0]"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("cameras") && e.contains("zero"), "{e}");
    let e = parse(&GOOD.replace("opacity = 0.5", "opacity = 1.5"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("5: blocks:"), "{e}");
    let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [-3, 2, 0]"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("min must not exceed max"), "{e}");
    let e = parse(&GOOD.replace("size = [64, 32]", "size = [0, 32]"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("3: size"), "{e}");
    let e = parse(&format!(
        "{GOOD}\n[terrain]\nmin_chunk = [0, 0, 0]\nmax_chunk = [100, 8, 100]\n"
    ))
    .unwrap_err()
    .to_string();
    assert!(e.contains("at most 4096 chunks"), "{e}");
    let e = parse(&GOOD.replace("max = [3, 2, 0]", "max = [3000, 3000, 3000]"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("blocks in all"), "{e}");
    // Volumes whose i64 product wraps: the whole i32 range on two or three axes.
    for (min, max) in [
        (
            "[-2147483648, 0, -2147483648]",
            "[2147483647, 0, 2147483647]",
        ),
        (
            "[-2147483648, -2147483648, -2147483648]",
            "[2147483647, 2147483647, 2147483647]",
        ),
    ] {
        let text = GOOD
            .replace("min = [0, 0, 0]", &format!("min = {min}"))
            .replace("max = [3, 2, 0]", &format!("max = {max}"));
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("20000000 blocks in all"), "{e}");
    }
    let e = parse(&format!(
        "{GOOD}\n[terrain]\nmin_chunk = [-2147483648, -2147483648, -2147483648]\nmax_chunk = [2147483647, 2147483647, 2147483647]\n"
    ))
    .unwrap_err().to_string();
    assert!(e.contains("at most 4096 chunks"), "{e}");
}

/// 20 M blocks in one row pass the block count but touch 625 000 chunks:
/// an error before any chunk is made. A 4096 × 4096 floor (16 384 chunks) is fine.
#[test]
fn the_box_check_bounds_chunks_too() {
    let row = GOOD.replace("max = [3, 2, 0]", "max = [19999999, 0, 0]");
    let e = parse(&row).unwrap_err().to_string();
    assert!(e.contains("16384 chunks"), "{e}");
    let floor = GOOD.replace("max = [3, 2, 0]", "max = [4095, 0, 4095]");
    let s = parse(&floor).unwrap();
    assert_eq!(s.world.len(), 16_384);
    let beyond = GOOD.replace("max = [3, 2, 0]", "max = [4096, 0, 4095]");
    assert!(parse(&beyond).unwrap_err().to_string().contains("chunks"));
}

/// A `path_to` where no camera can be (NaN, infinite, on the target, outside
/// the world) is an error at parsing, for every command alike.
#[test]
fn a_bad_path_to_is_an_error() {
    for bad in [
        "[nan, 1.0, 10.0]",
        "[inf, 1.0, 10.0]",
        "[0.5, 1.0, 0.0]",
        "[3e10, 1.0, 0.0]",
    ] {
        let e = parse(&GOOD.replace("path_to = [3.0, 1.0, 10.0]", &format!("path_to = {bad}")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cameras.path_to"), "{bad}: {e}");
    }
}

/// Sizes past the lab's caps are errors naming the field and the cap.
#[test]
fn sizes_past_the_caps_are_errors() {
    for (size, word) in [("[16384, 16384]", "8192"), ("[8192, 8192]", "pixels")] {
        let e = parse(&GOOD.replace("size = [64, 32]", &format!("size = {size}")))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("3: size") && e.contains(word), "{e}");
    }
}

/// An endless or huge file is read only up to the limit; the error names the
/// file and the limit.
#[test]
fn scene_files_are_read_with_a_size_limit() {
    let limit = crate::limits::MAX_SCENE_FILE_BYTES;
    for endless in ["/dev/zero", "/dev/urandom"] {
        if Path::new(endless).exists() {
            let e = Scene::load(Path::new(endless)).unwrap_err().to_string();
            assert!(e.contains(endless) && e.contains(&limit.to_string()), "{e}");
        }
    }
    let dir = std::env::temp_dir().join(format!("voxel_scene_limit_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let big = dir.join("big.toml");
    let mut text = GOOD.to_owned();
    text.push_str(&"# padding\n".repeat(limit as usize / 10 + 1));
    std::fs::write(&big, &text).unwrap();
    assert!(
        Scene::load(&big)
            .unwrap_err()
            .to_string()
            .contains("larger than")
    );
    let ok = dir.join("ok.toml");
    std::fs::write(&ok, GOOD).unwrap();
    Scene::load(&ok).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, [0xffu8, 0xfe, 0x00]).unwrap();
    assert!(Scene::load(&bad).unwrap_err().to_string().contains("UTF-8"));
    let _ = std::fs::remove_dir_all(dir);
}
