//! MagicaVoxel models: files written by `dot_vox` import to exactly the blocks an
//! independent float-matrix placement predicts; the committed models are what their
//! builders write; every kind of broken file is an error naming the file; the lab evaluates
//! the `.vox` scenes and the two exact references agree on them.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use dot_vox::{DotVoxData, SceneNode};
use glam::{DMat3, DMat4, DVec3};
use tests::vox_models::{self, Builder, glass, group, shape, transform};
use voxel_core::vox::{DEFAULT_MAX_VOXELS, world_from_vox};
use voxel_core::{CHUNK_SIZE, RenderClass, VoxFile, World};
use voxel_lab::EvalOptions;
use voxel_lab::scene::{Scene, scene_files};
use voxel_render::Technique;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every block of a world that is not air: position and block name.
fn blocks_of(world: &World) -> HashMap<[i64; 3], String> {
    let registry = world.registry();
    let mut out = HashMap::new();
    for (pos, chunk) in world.iter() {
        let o = pos.origin();
        for x in 0..CHUNK_SIZE {
            for y in 0..CHUNK_SIZE {
                for z in 0..CHUNK_SIZE {
                    let id = chunk.get(x, y, z).unwrap();
                    if id != voxel_core::BlockId::AIR {
                        let p = [o[0] + x as i64, o[1] + y as i64, o[2] + z as i64];
                        out.insert(p, registry.get(id).unwrap().name.clone());
                    }
                }
            }
        }
    }
    out
}

/// The oracle: MagicaVoxel's placement as vengi writes it (the transform, times a shift of
/// half a voxel, times minus the pivot ⌊size/2⌋, applied to the voxel and floored), in f64
/// matrices built from `dot_vox`'s own rotation decoding; then z-up to y-up. Returns each
/// placed voxel's block (y-up) and colour index (the file's, 1 to 255).
fn oracle(data: &DotVoxData) -> Vec<([i64; 3], u8)> {
    fn walk(data: &DotVoxData, node: u32, m: DMat4, out: &mut Vec<([i64; 3], u8)>) {
        match &data.scenes[node as usize] {
            SceneNode::Transform { frames, child, .. } => {
                let f = &frames[0];
                let t = f.position().map_or(DVec3::ZERO, |p| {
                    DVec3::new(f64::from(p.x), f64::from(p.y), f64::from(p.z))
                });
                let r = f.orientation().map_or(DMat3::IDENTITY, |r| {
                    let c = r.to_cols_array_2d();
                    DMat3::from_cols_array_2d(&c.map(|col| col.map(f64::from)))
                });
                let local = DMat4::from_translation(t) * DMat4::from_mat3(r);
                walk(data, *child, m * local, out);
            }
            SceneNode::Group { children, .. } => {
                for c in children {
                    walk(data, *c, m, out);
                }
            }
            SceneNode::Shape { models, .. } => {
                let model = &data.models[models[0].model_id as usize];
                let s = model.size;
                let pivot = DVec3::new(f64::from(s.x / 2), f64::from(s.y / 2), f64::from(s.z / 2));
                let bake = m * DMat4::from_translation(DVec3::splat(0.5) - pivot);
                for v in &model.voxels {
                    let p = bake
                        .transform_point3(DVec3::new(
                            f64::from(v.x),
                            f64::from(v.y),
                            f64::from(v.z),
                        ))
                        .floor();
                    let (x, y, z) = (p.x as i64, p.y as i64, p.z as i64);
                    out.push(([x, z, -y - 1], v.i + 1));
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(data, 0, DMat4::IDENTITY, &mut out);
    out
}

/// Three models, one placed under every rotation MagicaVoxel can write (all 48 signed
/// permutations, mirrors included) in a group, one in a nested group with a quarter turn,
/// one plain; glass of two opacities and an opaque colour.
fn round_trip_data() -> DotVoxData {
    let mut a = Builder::new([3, 2, 4]);
    a.fill([0, 0, 0], [2, 0, 0], 1);
    a.set(0, 1, 1, 2);
    a.set(2, 1, 3, 3);
    a.set(1, 0, 2, 2);
    let mut b = Builder::new([1, 1, 1]);
    b.set(0, 0, 0, 1);
    let mut c = Builder::new([5, 1, 2]);
    c.fill([0, 0, 0], [4, 0, 0], 3);
    c.set(4, 0, 1, 2);

    let rotations: Vec<u8> = (0..128u8)
        .filter(|b| {
            let (a0, a1) = (b & 3, (b >> 2) & 3);
            a0 < 3 && a1 < 3 && a0 != a1
        })
        .collect();
    assert_eq!(rotations.len(), 48);
    // Node ids: 0 root, 1 top group, 2 rotation group's transform, 3 rotation group, then
    // a transform and a shape per rotation, then the nested and plain placements.
    let mut scenes = vec![transform(1, [0, 0, 0], None)];
    let first = 4 + 2 * rotations.len() as u32;
    scenes.push(group(&[2, first, first + 4]));
    scenes.push(transform(3, [5, -3, 7], None));
    let kids: Vec<u32> = (0..rotations.len() as u32).map(|i| 4 + 2 * i).collect();
    scenes.push(group(&kids));
    for (i, r) in rotations.iter().enumerate() {
        let t = [
            (i as i32 % 8) * 9 - 30,
            (i as i32 / 8) * 9 - 20,
            (i as i32 % 3) * 2,
        ];
        scenes.push(transform(5 + 2 * i as u32, t, Some(*r)));
        scenes.push(shape(0));
    }
    // Nested: a turned group holding a moved, turned shape.
    scenes.push(transform(first + 1, [40, 2, -5], Some(0b0001_0001)));
    scenes.push(group(&[first + 2]));
    scenes.push(transform(first + 3, [3, 1, 2], Some(0b0110_0110)));
    scenes.push(shape(2));
    scenes.push(transform(first + 5, [-40, 0, 0], None));
    scenes.push(shape(1));
    DotVoxData {
        version: 200,
        index_map: Vec::new(),
        models: vec![a.model(), b.model(), c.model()],
        palette: vox_models::palette(&[(1, [200, 10, 10]), (2, [10, 200, 10]), (3, [10, 10, 200])]),
        materials: vec![glass(2, 0.3), glass(3, 0.8)],
        scenes,
        layers: Vec::new(),
    }
}

#[test]
fn a_file_written_by_dot_vox_imports_to_exactly_the_expected_blocks() {
    let data = round_trip_data();
    let file = VoxFile::parse(&vox_models::bytes(&data), DEFAULT_MAX_VOXELS).unwrap();
    assert_eq!(file.models.len(), 3);
    assert_eq!(file.instances.len(), 48 + 2);

    let expected = oracle(&data);
    let mut got: Vec<_> = file.voxels().collect();
    let mut want = expected.clone();
    got.sort();
    want.sort();
    assert_eq!(got, want, "placed voxels against the float-matrix oracle");
    // No two placements overlap, so the world holds each voxel once.
    let mut unique = want.iter().map(|(p, _)| *p).collect::<Vec<_>>();
    unique.dedup();
    assert_eq!(unique.len(), want.len());

    // A few by hand. The plain single voxel: model 1x1x1 under t = (-40, 0, 0), its centre
    // at the translation: MagicaVoxel cell (-40, 0, 0), ours (-40, 0, -1).
    assert!(want.contains(&([-40, 0, -1], 1)));
    // Rotation byte 4 (identity) is the 3rd signed permutation in byte order (1, 2, 4, ...)
    // and sits at t = (5, -3, 7) + (2*9 - 30, -20, 4): voxel (0, 0, 0) of the 3x2x4 model
    // (pivot (1, 1, 2)) lands at MagicaVoxel (-8, -24, 9), ours (-8, 9, 23).
    assert!(want.contains(&([-8, 9, 23], 1)));

    // In a world, at the origin: every block where the oracle puts it, with its type.
    let world = world_from_vox(&file, "rt", &[]).unwrap();
    let min: [i64; 3] = std::array::from_fn(|i| want.iter().map(|(p, _)| p[i]).min().unwrap());
    let blocks = blocks_of(&world);
    assert_eq!(blocks.len(), want.len());
    for (p, index) in &want {
        let at = std::array::from_fn(|i| p[i] - min[i]);
        let name = match index {
            1 => "rt#1",
            2 => "rt glass #2",
            _ => "rt glass #3",
        };
        assert_eq!(blocks.get(&at).map(String::as_str), Some(name), "at {at:?}");
    }
    let registry = world.registry();
    let def = |name: &str| registry.get(registry.id(name).unwrap()).unwrap().clone();
    assert_eq!(def("rt#1").class, RenderClass::Opaque);
    assert_eq!(def("rt#1").color, [200, 10, 10]);
    for (name, opacity) in [("rt glass #2", 0.7), ("rt glass #3", 0.2)] {
        let d = def(name);
        assert_eq!(d.class, RenderClass::Translucent, "{name}");
        assert!((d.opacity - opacity).abs() < 1e-6, "{name}: {}", d.opacity);
    }
}

#[test]
fn the_committed_models_are_what_their_builders_write() {
    let update = std::env::var_os("VOX_UPDATE").is_some();
    for (path, data) in vox_models::committed() {
        let bytes = vox_models::bytes(&data);
        let path = repo().join(path);
        if update {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
        }
        // dot_vox writes dictionaries in hash order, so compare what the files hold.
        let fresh = VoxFile::parse(&bytes, DEFAULT_MAX_VOXELS).unwrap();
        let committed = VoxFile::load(&path).unwrap_or_else(|e| {
            panic!("{e} (VOX_UPDATE=1 cargo test -p tests --test vox rewrites it)")
        });
        assert!(
            committed == fresh,
            "{} differs from what tests/src/vox_models.rs writes (VOX_UPDATE=1 rewrites it)",
            path.display()
        );
    }
    // What the README and the scenes promise of them.
    let chapel = VoxFile::load(&repo().join("scenes/vox/chapel.vox")).unwrap();
    assert!(
        chapel.models[0].size.iter().all(|s| *s > 32),
        "a model larger than a chunk"
    );
    let glass: Vec<f32> = chapel
        .materials
        .iter()
        .filter_map(|m| match m {
            voxel_core::vox::VoxMaterial::Glass(a) => Some(*a),
            _ => None,
        })
        .collect();
    assert!(glass.len() >= 5, "glass of several opacities: {glass:?}");
    assert!(
        chapel
            .instances
            .iter()
            .any(|i| i.rotation != voxel_core::vox::VoxRotation::IDENTITY)
    );
    let harbour = VoxFile::load(&repo().join("scenes/vox/models/harbour.vox")).unwrap();
    assert_eq!(harbour.version, 150);
    assert!(
        harbour
            .materials
            .iter()
            .all(|m| *m == voxel_core::vox::VoxMaterial::Opaque)
    );
}

/// A good small file to break: one model, a palette, a scene graph.
fn good_bytes() -> Vec<u8> {
    let mut m = Builder::new([2, 2, 2]);
    m.set(0, 0, 0, 1);
    let data = DotVoxData {
        version: 200,
        index_map: Vec::new(),
        models: vec![m.model()],
        palette: vox_models::palette(&[]),
        materials: Vec::new(),
        scenes: vec![transform(1, [0, 0, 0], None), shape(0)],
        layers: Vec::new(),
    };
    vox_models::bytes(&data)
}

#[test]
fn every_broken_file_is_an_error_naming_the_file_and_the_fault() {
    let dir = tests::out_dir("vox/bad");
    let good = good_bytes();
    // Offsets: "VOX " version, MAIN header (20 bytes), then SIZE (id, sizes, x y z).
    let with = |at: usize, word: u32| {
        let mut b = good.clone();
        b[at..at + 4].copy_from_slice(&word.to_le_bytes());
        b
    };
    let xyzi = 20 + 24; // the XYZI chunk: after SIZE's 12-byte header and 12 bytes
    let graph = |nodes: Vec<SceneNode>| {
        let mut m = Builder::new([2, 2, 2]);
        m.set(0, 0, 0, 1);
        vox_models::bytes(&DotVoxData {
            version: 200,
            index_map: Vec::new(),
            models: vec![m.model()],
            palette: vox_models::palette(&[]),
            materials: Vec::new(),
            scenes: nodes,
            layers: Vec::new(),
        })
    };
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "magic",
            b"PK\x03\x04 not a vox".to_vec(),
            "not a MagicaVoxel file",
        ),
        ("truncated", good[..good.len() / 2].to_vec(), "past the end"),
        ("header_only", good[..10].to_vec(), "truncated"),
        (
            "past_end",
            with(16, 1 << 30),
            "chunk MAIN at offset 8 declares",
        ),
        ("size_zero", with(32, 0), "size 0x2x2"),
        ("size_big", with(36, 300), "size 2x300x2"),
        (
            "xyzi_count",
            with(xyzi + 12, u32::MAX),
            "truncated: XYZI voxels",
        ),
        (
            "cycle",
            graph(vec![
                transform(1, [0; 3], None),
                group(&[2]),
                transform(1, [0; 3], None),
            ]),
            "cycle",
        ),
        (
            "missing_node",
            graph(vec![transform(1, [0; 3], None), group(&[7])]),
            "refers to node 7, which the file does not hold",
        ),
        (
            "missing_model",
            graph(vec![transform(1, [0; 3], None), shape(4)]),
            "refers to model 4; the file holds 1 models",
        ),
    ];
    let mut palette_index = good.clone();
    let voxel = xyzi + 16; // the first voxel's x, y, z, i
    palette_index[voxel + 3] = 0;
    let mut cases = cases;
    cases.push(("palette_index", palette_index, "colour index 0"));
    for (name, bytes, want) in cases {
        let path = dir.join(format!("{name}.vox"));
        std::fs::write(&path, &bytes).unwrap();
        let e = Scene::load(&path).unwrap_err().to_string();
        assert!(
            e.contains(&path.display().to_string()) && e.contains(want),
            "{name}: {e}"
        );
    }
    // Through a scene file: its line, the model's file, and the fault.
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "name = \"bad\"\n\n[[models]]\nfile = \"cycle.vox\"\n",
    )
    .unwrap();
    let e = Scene::load(&scene).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}:4: models.file: ", scene.display()))
            && e.contains("cycle.vox")
            && e.contains("cycle"),
        "{e}"
    );
    let e = Scene::load(&dir.join("no_such.vox"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no_such.vox") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn scene_files_place_models_with_overrides_among_boxes() {
    let dir = repo().join("scenes/vox");
    let text = r#"
name = "mixed"

[[boxes]]
block = "stone"
min = [-5, -1, -5]
max = [100, -1, 100]

[[models]]
file = "models/harbour.vox"
at = [0, 0, 0]
rotate = 90
[[models.palette]]
index = WATER
class = "translucent"
opacity = 0.6

[[boxes]]
block = "red_glass"
min = [0, 0, 0]
max = [0, 0, 0]
"#;
    let c = vox_models::harbour_colors();
    let text = text.replace("WATER", &c.water.to_string());
    let s = voxel_lab::scene::parse_in(&text, &dir).unwrap();
    let r = s.world.registry();
    let water = r.id(&format!("harbour#{}", c.water)).unwrap();
    assert_eq!(r.class(water).unwrap(), RenderClass::Translucent);
    assert!((r.get(water).unwrap().opacity - 0.6).abs() < 1e-6);
    let glass = r.id(&format!("harbour#{}", c.glass)).unwrap();
    assert_eq!(
        r.class(glass).unwrap(),
        RenderClass::Opaque,
        "not overridden"
    );
    // Turned a quarter (x -> -z), the 64 x 56 x 24 model covers x 0..55, z 0..63.
    let blocks = blocks_of(&s.world);
    let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
    for (p, name) in &blocks {
        if name.starts_with("harbour") {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
    }
    assert_eq!((lo, hi), ([0, 0, 0], [55, 23, 63]));
    // In file order: the red glass box came after the model and replaced its corner.
    assert_eq!(
        blocks.get(&[0, 0, 0]).map(String::as_str),
        Some("red_glass")
    );
    assert_eq!(blocks.get(&[-5, -1, -5]).map(String::as_str), Some("stone"));
    // No cameras: the framing view of the model, looking at its centre.
    let cam = s.cameras[0];
    assert!(
        cam.eye.y > 23.0 && cam.eye.x > 55.0 && cam.eye.z > 63.0,
        "{cam:?}"
    );

    for (bad, want) in [
        ("index = WATER", "index = 0"),
        ("index = WATER", "index = 256"),
        ("class = \"translucent\"", "class = \"glass\""),
        ("opacity = 0.6", "opacity = 1.0"),
        ("rotate = 90", "rotate = 45"),
        (
            "file = \"models/harbour.vox\"",
            "file = \"models/none.vox\"",
        ),
    ] {
        let e = voxel_lab::scene::parse_in(
            &text.replace(&bad.replace("WATER", &c.water.to_string()), want),
            &dir,
        )
        .unwrap_err()
        .to_string();
        let expect = match want {
            "index = 0" | "index = 256" => "models.palette.index",
            "class = \"glass\"" => "models.palette.class",
            "opacity = 1.0" => "models.palette.opacity",
            "rotate = 45" => "models.rotate",
            _ => "models/none.vox",
        };
        assert!(e.contains(expect), "{want}: {e}");
    }
}

#[test]
fn the_lab_evaluates_the_vox_scenes_and_the_exact_references_agree() {
    let Some(ctx) = tests::gpu() else { return };
    let out = tests::out_dir("vox/lab");
    let _ = std::fs::remove_dir_all(&out);
    let scenes = scene_files(&repo().join("scenes/vox")).unwrap();
    assert!(
        scenes.iter().any(|p| voxel_lab::scene::is_vox(p)),
        "a bare .vox among the scenes: {scenes:?}"
    );
    let opts = EvalOptions {
        scenes: scenes.clone(),
        techniques: Technique::ALL.to_vec(),
        weights: Vec::new(),
        size: Some((128, 72)),
        frames: 1,
        warmup: 1,
        out: out.clone(),
        stability: false,
        flicker_frames: 0,
        sweep_points: 0,
        command: "cargo test -p tests --test vox".into(),
        heatmap_width: None,
        random: None,
        checks: Default::default(),
    };
    let summary = voxel_lab::evaluate(&ctx, &opts).unwrap();
    assert_eq!(summary.reference_checks.len(), scenes.len());
    for c in &summary.reference_checks {
        // Exact as the lab counts it (the CPU ray march agrees with the A-buffer off
        // geometric edges, no crack, nothing lost), and the two GPU methods agree within
        // 2/255 (rounding of two blend orders and of the A-buffer's half floats).
        assert!(
            c.exact && c.max_abs_err <= 2 && c.lost_fragments == 0,
            "{}: the exact methods differ by {}/255 ({c:?})",
            c.scene,
            c.max_abs_err
        );
        // Glass in front of glass or water: translucency is really there.
        assert!(c.depth_complexity >= 3, "{}: {c:?}", c.scene);
    }
    assert_eq!(summary.records.len(), scenes.len() * Technique::ALL.len());
    for r in &summary.records {
        assert_eq!(r.nan_px, 0, "{} {}", r.scene, r.technique);
        if r.technique == "opaque-only" {
            assert!(r.max_abs_err > 10, "{}: translucency visible", r.scene);
        }
    }
}

#[test]
fn the_gallery_shows_every_technique_with_its_error() {
    let Some(ctx) = tests::gpu() else { return };
    let out = tests::out_dir("vox/gallery");
    let scene = Scene::load(&repo().join("scenes/vox/harbour.toml")).unwrap();
    let entries = voxel_lab::gallery::render(&ctx, &scene, (96, 54)).unwrap();
    assert_eq!(entries.len(), Technique::ALL.len());
    let get = |t: Technique| entries.iter().find(|e| e.technique == t).unwrap();
    assert_eq!(get(Technique::Reference).metrics.max_abs_err, 0);
    assert!(
        get(Technique::OpaqueOnly).metrics.max_abs_err > 10,
        "the water shows"
    );
    voxel_lab::gallery::write(&out, &entries, 3).unwrap();
    let sheet = voxel_render::Image::load_png(&out.join("gallery.png")).unwrap();
    // Three tiles a row, a row per three techniques: each 8 px wider than a picture, a
    // label line and two pictures high.
    let rows = Technique::ALL.len().div_ceil(3) as u32;
    assert_eq!(
        (sheet.width, sheet.height),
        (3 * 104, rows * (26 + 2 * 54 + 12))
    );
    assert!(out.join("sorted-quads_flip.png").is_file());
}
