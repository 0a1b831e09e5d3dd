#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test
use super::*;
use crate::{BlockRegistry, Error, Pattern, RenderClass, World, WorldPos};

/// A chunk: id, content, children bytes.
fn chunk(id: &[u8; 4], content: &[u8], children: &[u8]) -> Vec<u8> {
    let mut v = id.to_vec();
    v.extend((content.len() as u32).to_le_bytes());
    v.extend((children.len() as u32).to_le_bytes());
    v.extend(content);
    v.extend(children);
    v
}

fn file(chunks: &[Vec<u8>]) -> Vec<u8> {
    let mut v = b"VOX ".to_vec();
    v.extend(200u32.to_le_bytes());
    v.extend(chunk(b"MAIN", &[], &chunks.concat()));
    v
}

fn words(w: &[u32]) -> Vec<u8> {
    w.iter().flat_map(|w| w.to_le_bytes()).collect()
}

fn size(x: u32, y: u32, z: u32) -> Vec<u8> {
    chunk(b"SIZE", &words(&[x, y, z]), &[])
}

fn xyzi(voxels: &[[u8; 4]]) -> Vec<u8> {
    let mut c = words(&[voxels.len() as u32]);
    c.extend(voxels.concat());
    chunk(b"XYZI", &c, &[])
}

fn dict(entries: &[(&str, &str)]) -> Vec<u8> {
    let mut v = words(&[entries.len() as u32]);
    for (k, val) in entries {
        for s in [k, val] {
            v.extend(words(&[s.len() as u32]));
            v.extend(s.as_bytes());
        }
    }
    v
}

fn trn(id: u32, child: u32, frame: &[(&str, &str)]) -> Vec<u8> {
    let mut c = words(&[id]);
    c.extend(dict(&[]));
    c.extend(words(&[child, u32::MAX, 0, 1]));
    c.extend(dict(frame));
    chunk(b"nTRN", &c, &[])
}

fn grp(id: u32, children: &[u32]) -> Vec<u8> {
    let mut c = words(&[id]);
    c.extend(dict(&[]));
    c.extend(words(&[children.len() as u32]));
    c.extend(words(children));
    chunk(b"nGRP", &c, &[])
}

fn shp(id: u32, model: u32) -> Vec<u8> {
    let mut c = words(&[id]);
    c.extend(dict(&[]));
    c.extend(words(&[1, model]));
    c.extend(dict(&[]));
    chunk(b"nSHP", &c, &[])
}

fn parse(bytes: &[u8]) -> Result<VoxFile, VoxError> {
    VoxFile::parse(bytes, DEFAULT_MAX_VOXELS)
}

fn one_voxel() -> Vec<Vec<u8>> {
    vec![size(2, 2, 2), xyzi(&[[1, 0, 1, 5]])]
}

#[test]
fn the_default_palette_is_magicavoxels() {
    let ours = default_palette();
    for (k, c) in dot_vox::DEFAULT_PALETTE.iter().take(255).enumerate() {
        assert_eq!(ours[k + 1], [c.r, c.g, c.b], "colour index {}", k + 1);
    }
}

#[test]
fn rotations_decode_as_dot_vox_does_and_compose_as_matrices() {
    let matrix = |r: &VoxRotation| -> [[i64; 3]; 3] {
        std::array::from_fn(|row| std::array::from_fn(|col| r.apply(unit(col))[row]))
    };
    fn unit(i: usize) -> [i64; 3] {
        std::array::from_fn(|j| i64::from(i == j))
    }
    let mut valid = Vec::new();
    for b in 0..=255u8 {
        let (a0, a1) = (b & 3, (b >> 2) & 3);
        let ok = b < 128 && a0 < 3 && a1 < 3 && a0 != a1;
        let r = VoxRotation::from_byte(b);
        assert_eq!(r.is_some(), ok, "byte {b}");
        if let Some(r) = r {
            // dot_vox's matrix, independently decoded: cols[c][r].
            let cols = dot_vox::Rotation::from_byte(b).to_cols_array_2d();
            let m = matrix(&r);
            for (row, m_row) in m.iter().enumerate() {
                for (col, v) in m_row.iter().enumerate() {
                    assert_eq!(*v as f32, cols[col][row], "byte {b} ({row}, {col})");
                }
            }
            valid.push(r);
        }
    }
    assert_eq!(valid.len(), 48, "every signed permutation of three axes");
    for a in &valid {
        for b in &valid {
            let (ma, mb, mc) = (matrix(a), matrix(b), matrix(&a.then_after(b)));
            for r in 0..3 {
                for c in 0..3 {
                    let p: i64 = (0..3).map(|k| ma[r][k] * mb[k][c]).sum();
                    assert_eq!(mc[r][c], p);
                }
            }
        }
    }
}

#[test]
fn a_model_without_scene_graph_is_placed_about_its_centre_voxel() {
    let f = parse(&file(&one_voxel())).unwrap();
    assert_eq!(f.instances.len(), 1);
    // Voxel (1, 0, 1) of a 2x2x2 model: MagicaVoxel cell (0, -1, 0), our (0, 0, 0).
    assert_eq!(f.voxels().collect::<Vec<_>>(), vec![([0, 0, 0], 5)]);
    assert_eq!(f.bounds(), Some(([-1, -1, -1], [0, 0, 0])));
    assert_eq!(f.palette_len, 255);
    assert_eq!(f.palette[5], default_palette()[5]);
}

#[test]
fn glass_materials_map_to_opacities() {
    let mat = |id: u32, props: &[(&str, &str)]| {
        let mut c = words(&[id]);
        c.extend(dict(props));
        chunk(b"MATL", &c, &[])
    };
    let mut chunks = one_voxel();
    chunks.extend([
        mat(1, &[("_type", "_glass"), ("_trans", "0.25")]),
        mat(2, &[("_type", "_glass"), ("_alpha", "0.5")]),
        mat(3, &[("_type", "_glass")]),
        mat(4, &[("_type", "_glass"), ("_trans", "1")]),
        mat(5, &[("_type", "_metal"), ("_trans", "0.5")]),
        mat(6, &[("_type", "_glass"), ("_trans", "0")]),
        mat(256, &[("_type", "_glass")]),
        mat(0, &[("_type", "_glass")]),
    ]);
    let f = parse(&file(&chunks)).unwrap();
    assert_eq!(f.materials[1], VoxMaterial::Glass(0.75));
    assert_eq!(f.materials[2], VoxMaterial::Glass(0.5));
    assert_eq!(f.materials[3], VoxMaterial::Glass(0.5));
    assert_eq!(f.materials[4], VoxMaterial::Glass(MIN_OPACITY));
    assert_eq!(f.materials[5], VoxMaterial::Opaque);
    assert_eq!(f.materials[6], VoxMaterial::Opaque);
    assert_eq!(f.materials[0], VoxMaterial::Opaque);

    let bad = file(&[mat(1, &[("_type", "_glass"), ("_trans", "lots")])]);
    assert!(matches!(
        parse(&bad),
        Err(VoxError::MaterialValue { index: 1, .. })
    ));
    let bad = file(&[mat(300, &[])]);
    assert!(matches!(
        parse(&bad),
        Err(VoxError::MaterialId { id: 300, .. })
    ));
}

#[test]
fn the_scene_graph_places_groups_translations_and_rotations() {
    // Root -> group -> two transforms: one moved, one turned a quarter about z.
    // Row 0 takes axis 1 (y) negated, row 1 axis 0 (x): rows (-y, x, z).
    let turn_z: u8 = 1 | (1 << 4);
    let chunks = [
        size(3, 1, 1),
        xyzi(&[[0, 0, 0, 1], [2, 0, 0, 2]]),
        trn(0, 1, &[]),
        grp(1, &[2, 4]),
        trn(2, 3, &[("_t", "10 20 30")]),
        shp(3, 0),
        trn(4, 5, &[("_r", &turn_z.to_string())]),
        shp(5, 0),
    ];
    let f = parse(&file(&chunks)).unwrap();
    assert_eq!(f.instances.len(), 2);
    let got: Vec<_> = f.voxels().collect();
    // Moved: centre voxel (1, 0, 0) sits at the translation; MV (9, 20, 30) and
    // (11, 20, 30) become ours (x, z, -y - 1).
    assert_eq!(got[0], ([9, 30, -21], 1));
    assert_eq!(got[1], ([11, 30, -21], 2));
    // Turned: R (x, y, z) = (-y, x, z) on the doubled centres (-1, 1, 1) and (3, 1, 1):
    // (-1, -1, 1) -> MV cell (-1, -1, 0); (-1, 3, 1) -> (-1, 1, 0).
    assert_eq!(got[2], ([-1, 0, 0], 1));
    assert_eq!(got[3], ([-1, 0, -2], 2));
}

#[test]
fn hidden_transforms_and_layers_are_left_out() {
    let mut layr = words(&[1]);
    layr.extend(dict(&[("_hidden", "1")]));
    layr.extend(words(&[u32::MAX]));
    let mut hidden_trn = words(&[4]);
    hidden_trn.extend(dict(&[("_hidden", "1")]));
    hidden_trn.extend(words(&[5, u32::MAX, 0, 1]));
    hidden_trn.extend(dict(&[]));
    let mut in_layer = words(&[6]);
    in_layer.extend(dict(&[]));
    in_layer.extend(words(&[7, u32::MAX, 1, 1]));
    in_layer.extend(dict(&[]));
    let chunks = [
        size(1, 1, 1),
        xyzi(&[[0, 0, 0, 1]]),
        trn(0, 1, &[]),
        grp(1, &[2, 4, 6]),
        trn(2, 3, &[]),
        shp(3, 0),
        chunk(b"nTRN", &hidden_trn, &[]),
        shp(5, 0),
        chunk(b"nTRN", &in_layer, &[]),
        shp(7, 0),
        chunk(b"LAYR", &layr, &[]),
    ];
    let f = parse(&file(&chunks)).unwrap();
    assert_eq!(f.instances.len(), 1);
}

#[test]
fn every_bad_file_row_is_its_error() {
    let e = |bytes: Vec<u8>| parse(&bytes).unwrap_err();
    // Wrong magic, and a file too short for one.
    assert!(matches!(e(b"PNG\x89....".to_vec()), VoxError::Magic(_)));
    assert!(matches!(e(b"VO".to_vec()), VoxError::Magic(_)));
    assert!(matches!(
        e(b"VOX \xc8\0\0\0NOPE\0\0\0\0\0\0\0\0".to_vec()),
        VoxError::NoMain(_)
    ));
    // Truncated: cut anywhere, a good file is an error, never a panic.
    let good = file(&one_voxel());
    for cut in 0..good.len() {
        assert!(parse(&good[..cut]).is_err(), "cut at {cut}");
    }
    assert!(matches!(
        e(good[..good.len() - 2].to_vec()),
        VoxError::ChunkPastEnd { .. }
    ));
    // Chunk sizes past the end, in MAIN and inside it.
    let mut past = good.clone();
    past[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(e(past), VoxError::ChunkPastEnd { ref id, .. } if id == "MAIN"));
    let mut past = good.clone();
    past[24..28].copy_from_slice(&1000u32.to_le_bytes());
    assert!(matches!(e(past), VoxError::ChunkPastEnd { ref id, .. } if id == "SIZE"));
    // Counts larger than the bytes: found before allocating.
    let mut huge = words(&[u32::MAX]);
    huge.extend([0, 0, 0, 1]);
    assert!(matches!(
        e(file(&[size(1, 1, 1), chunk(b"XYZI", &huge, &[])])),
        VoxError::Truncated {
            what: "XYZI voxels",
            ..
        }
    ));
    // Model sizes 0 and above 256.
    for s in [[0, 1, 1], [1, 257, 1], [1, 1, u32::MAX]] {
        assert!(matches!(
            e(file(&[size(s[0], s[1], s[2])])),
            VoxError::ModelSize { model: 0, .. }
        ));
    }
    assert!(parse(&file(&[size(256, 256, 256), xyzi(&[[255, 255, 255, 1]])])).is_ok());
    // Voxels outside the size, or without one.
    assert!(matches!(
        e(file(&[size(2, 2, 2), xyzi(&[[2, 0, 0, 1]])])),
        VoxError::VoxelOutside { x: 2, .. }
    ));
    assert!(matches!(
        e(file(&[xyzi(&[[0, 0, 0, 1]])])),
        VoxError::VoxelsWithoutSize(_)
    ));
    // Palette indices out of range: 0, and past a short palette.
    assert!(matches!(
        e(file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 0]])])),
        VoxError::PaletteIndex { index: 0, .. }
    ));
    let short = chunk(b"RGBA", &[255; 16], &[]);
    assert!(matches!(
        e(file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 5]]), short.clone()])),
        VoxError::PaletteIndex {
            index: 5,
            len: 4,
            ..
        }
    ));
    assert!(parse(&file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 4]]), short])).is_ok());
    assert!(matches!(
        e(file(&[chunk(b"RGBA", &[1, 2, 3], &[])])),
        VoxError::Palette { size: 3, .. }
    ));
    // Scene graphs: a cycle, a missing node, a missing model, a shared node, no root.
    let m = one_voxel();
    let graph = |nodes: Vec<Vec<u8>>| file(&[m.clone(), nodes].concat());
    assert!(matches!(
        e(graph(vec![trn(0, 1, &[]), grp(1, &[2]), trn(2, 1, &[])])),
        VoxError::Cycle(1)
    ));
    assert!(matches!(
        e(graph(vec![trn(0, 1, &[]), grp(1, &[2, 9])])),
        VoxError::MissingNode {
            from: 1,
            missing: 2
        }
    ));
    assert!(matches!(
        e(graph(vec![trn(0, 1, &[]), shp(1, 3)])),
        VoxError::MissingModel {
            model: 3,
            count: 1,
            ..
        }
    ));
    assert!(matches!(
        e(graph(vec![
            trn(0, 1, &[]),
            grp(1, &[2, 2]),
            trn(2, 3, &[]),
            shp(3, 0)
        ])),
        VoxError::SharedNode(2)
    ));
    assert!(matches!(
        e(graph(vec![grp(1, &[])])),
        VoxError::MissingNode {
            from: -1,
            missing: 0
        }
    ));
    assert!(matches!(
        e(graph(vec![trn(0, 1, &[]), grp(1, &[]), grp(1, &[])])),
        VoxError::DuplicateNode(1)
    ));
    // Bad rotations and translations.
    for r in ["3", "15", "128", "-1", "x"] {
        assert!(
            matches!(
                e(graph(vec![trn(0, 1, &[("_r", r)]), shp(1, 0)])),
                VoxError::Rotation { node: 0, .. }
            ),
            "{r}"
        );
    }
    for t in ["1 2", "1 2 3 4", "a b c", "99999999999 0 0"] {
        assert!(
            matches!(
                e(graph(vec![trn(0, 1, &[("_t", t)]), shp(1, 0)])),
                VoxError::Translation { node: 0, .. }
            ),
            "{t}"
        );
    }
    // Placed too far, and deep chains of far translations.
    let far = i32::MAX.to_string();
    let t = format!("{far} 0 0");
    assert!(matches!(
        e(graph(vec![trn(0, 1, &[("_t", &t)]), shp(1, 0)])),
        VoxError::OutsideWorld(_)
    ));
    let mut chain = Vec::new();
    for i in 0..600u32 {
        chain.push(trn(2 * i, 2 * i + 1, &[("_t", &t)]));
        chain.push(grp(2 * i + 1, &[2 * i + 2]));
    }
    chain.push(trn(1200, 1201, &[]));
    chain.push(shp(1201, 0));
    assert!(matches!(e(graph(chain)), VoxError::OutsideWorld(_)));
    // Too many voxels: a model placed over and over.
    let many: Vec<u32> = (0..100).map(|i| 2 + 2 * i).collect();
    let mut nodes = vec![trn(0, 1, &[]), grp(1, &many)];
    for &n in &many {
        nodes.push(trn(n, n + 1, &[]));
        nodes.push(shp(n + 1, 0));
    }
    let bytes = graph(nodes);
    assert!(matches!(
        VoxFile::parse(&bytes, 99),
        Err(VoxError::TooManyVoxels {
            count: 100,
            max: 99
        })
    ));
    assert!(VoxFile::parse(&bytes, 100).is_ok());
}

#[test]
fn deep_nesting_is_no_stack_overflow() {
    // 100 000 nested chunks (dot_vox would recurse into each): children of chunks
    // other than MAIN are skipped, not read.
    let leaf = chunk(b"SIZE", &words(&[1, 1, 1]), &[]);
    let depth = 100_000;
    let mut nested = Vec::with_capacity(depth * 12 + leaf.len());
    for level in 0..depth {
        nested.extend(b"NEST");
        nested.extend(words(&[0, ((depth - 1 - level) * 12 + leaf.len()) as u32]));
    }
    nested.extend(&leaf);
    let f = parse(&file(&[nested])).unwrap();
    assert!(f.models.is_empty());
    // A chain of 100 000 transforms and groups: walked with a stack of our own.
    let mut nodes = one_voxel();
    for i in 0..50_000u32 {
        nodes.push(trn(2 * i, 2 * i + 1, &[]));
        nodes.push(grp(2 * i + 1, &[2 * i + 2]));
    }
    nodes.push(trn(100_000, 100_001, &[]));
    nodes.push(shp(100_001, 0));
    assert_eq!(parse(&file(&nodes)).unwrap().instances.len(), 1);
}

#[test]
fn blocks_are_registered_once_per_used_index_and_placed_turned() {
    let mut chunks = vec![size(3, 1, 2), xyzi(&[[0, 0, 0, 7], [2, 0, 1, 9]])];
    let mut c = words(&[9]);
    c.extend(dict(&[("_type", "_glass"), ("_trans", "0.6")]));
    chunks.push(chunk(b"MATL", &c, &[]));
    let f = parse(&file(&chunks)).unwrap();
    let mut registry = BlockRegistry::default();
    let blocks = f.register_blocks("m", &[], &mut registry).unwrap();
    assert_eq!(registry.len(), 15);
    let (a, b) = (blocks.ids[7], blocks.ids[9]);
    assert_eq!(registry.get(a).unwrap().name, "m#7");
    assert_eq!(registry.get(a).unwrap().class, RenderClass::Opaque);
    let glass = registry.get(b).unwrap();
    assert_eq!(
        (glass.name.as_str(), glass.class),
        ("m glass #9", RenderClass::Translucent)
    );
    assert!((glass.opacity - 0.4).abs() < 1e-6);
    assert_eq!(
        glass.pattern,
        Pattern::Framed,
        "glass is framed by its field"
    );
    assert_eq!(registry.get(a).unwrap().pattern, Pattern::Noise);
    // Again: the same types. With an override: a new name for the changed one.
    assert_eq!(f.register_blocks("m", &[], &mut registry).unwrap(), blocks);
    let water = PaletteOverride {
        index: 7,
        class: RenderClass::Translucent,
        opacity: 0.6,
    };
    let again = f.register_blocks("m", &[water], &mut registry).unwrap();
    assert_eq!(registry.get(again.ids[7]).unwrap().name, "m#7~2");
    assert_eq!(again.ids[9], b);
    // Overrides the registry refuses, and index 0.
    let bad = PaletteOverride {
        opacity: 1.0,
        ..water
    };
    assert!(f.register_blocks("n", &[bad], &mut registry).is_err());
    let zero = PaletteOverride { index: 0, ..water };
    assert!(f.register_blocks("n", &[zero], &mut registry).is_err());

    // MV voxels (0,0,0) and (2,0,1) of a 3x1x2 model: ours (-1,0,0) and (1,1,0); the box
    // x -1..1, y 0..1, z 0..0. One quarter turn: (x, z) -> (z, -x - 1).
    let mut world = World::new(std::sync::Arc::new(registry));
    let placed = f
        .place(
            "m",
            &blocks,
            VoxPlacement {
                at: [10, 20, 30],
                quarter_turns: 1,
            },
            &mut world,
        )
        .unwrap();
    // Turned: (-1,0,0) -> (0,0,0), (1,1,0) -> (0,1,-2); box z -2..0 -> moved to 30.
    assert_eq!(
        placed,
        Some((WorldPos::new(10, 20, 30), WorldPos::new(10, 21, 32)))
    );
    assert_eq!(world.get_block(WorldPos::new(10, 20, 32)), a);
    assert_eq!(world.get_block(WorldPos::new(10, 21, 30)), b);
    let far = VoxPlacement {
        at: [i32::MAX, 0, 0],
        quarter_turns: 0,
    };
    assert!(matches!(
        f.place("m", &blocks, far, &mut world),
        Err(Error::Vox {
            error: VoxError::OutsideWorld(_),
            ..
        })
    ));
}
