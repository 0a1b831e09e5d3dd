use std::collections::HashMap;

use voxel_core::{Face, TerrainConfig, blocks};

use super::*;

/// `n` eyes spread over a square `spread` blocks wide (a fixed lattice stepped by a prime,
/// off whole blocks), 30 blocks up.
fn eyes(n: usize, spread: f64) -> Vec<[f64; 3]> {
    let at = |i: usize, k: usize| ((i * k) % 1000) as f64 / 1000.0 - 0.5;
    (0..n)
        .map(|i| {
            [
                at(i, 7919) * spread + 0.37,
                30.0,
                at(i, 104_729) * spread - 0.61,
            ]
        })
        .collect()
}

#[test]
fn the_levels_tile_the_view_once_and_reach_the_view_distance() {
    let rings = LevelRings {
        radius: 4,
        coarsest: 3,
        finest: 0,
        y: 0..=0,
    };
    assert_eq!(rings.view_distance(), 32);
    for eye in eyes(40, 4000.0)
        .into_iter()
        .chain([[0.5, 1.0, -0.5], [-33.0, 0.0, 64.0]])
    {
        // Every full-detail chunk column within the coarsest square is covered by exactly
        // one chunk of one level, in the finished view and in each coarse-first one.
        for finest in (0..=rings.coarsest).rev() {
            let plan = rings.coarse_first(finest);
            let mut cover: HashMap<[i64; 2], u32> = HashMap::new();
            for (l, p) in plan.all(eye) {
                let s = level_scale(l);
                for dx in 0..s {
                    for dz in 0..s {
                        *cover
                            .entry([i64::from(p.x) * s + dx, i64::from(p.z) * s + dz])
                            .or_default() += 1;
                    }
                }
            }
            assert!(
                cover.values().all(|&n| n == 1),
                "a column drawn twice, eye {eye:?}"
            );
            let c = [eye[0], eye[2]].map(|v| (v / 32.0).floor() as i64);
            // No hole: the square of the view distance around the eye's chunk is covered.
            let r = rings.view_distance();
            for x in c[0] - r..=c[0] + r {
                for z in c[1] - r..=c[1] + r {
                    assert!(cover.contains_key(&[x, z]), "hole at {x},{z} eye {eye:?}");
                }
            }
        }
        // Each level starts at least its radius in its own chunks from the eye, past the
        // level inside it: full detail holds the eye's chunk and `radius` chunks each way.
        let c = [eye[0], eye[2]].map(|v| (v / 32.0).floor() as i64);
        for x in c[0] - 4..=c[0] + 4 {
            for z in c[1] - 4..=c[1] + 4 {
                let p = ChunkPos::new(x as i32, 0, z as i32);
                assert!(
                    rings.contains(0, p, eye),
                    "{p:?} not full detail, eye {eye:?}"
                );
            }
        }
        // Coarsest first, and each level nearest first.
        let all = rings.all(eye);
        assert!(all.windows(2).all(|w| w[0].0 >= w[1].0));
    }
    // Chunk heights outside the rings' are never drawn.
    assert!(!rings.contains(0, ChunkPos::new(0, 1, 0), [0.0; 3]));
    assert!(rings.validate().is_ok());
    for bad in [
        LevelRings {
            radius: 3,
            ..rings.clone()
        },
        LevelRings {
            radius: 0,
            ..rings.clone()
        },
        LevelRings {
            coarsest: 9,
            ..rings.clone()
        },
        LevelRings {
            finest: 4,
            ..rings.clone()
        },
        LevelRings {
            #[allow(clippy::reversed_empty_ranges)]
            y: 1..=0,
            ..rings.clone()
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
    let r = LevelRings::reaching(32, 512);
    assert_eq!((r.radius, r.coarsest, r.view_distance()), (32, 4, 512));
    assert_eq!(LevelRings::reaching(31, 10).coarsest, 0);
}

/// A flat sea floor 6 blocks under the surface everywhere (no trees, no structures), three
/// levels in rings two chunks wide, and an eye above it.
fn flat_sea() -> (TerrainGenerator, BlockRegistry, LevelRings, [f64; 3]) {
    let generator = TerrainGenerator::new(TerrainConfig {
        base_height: 18,
        amplitude: 0.0,
        tree_density: 0.0,
        structures: false,
        ..TerrainConfig::default()
    });
    let rings = LevelRings {
        radius: 2,
        coarsest: 2,
        finest: 0,
        y: 0..=0,
    };
    (
        generator,
        BlockRegistry::default(),
        rings,
        [40.0, 30.0, -20.0],
    )
}

#[test]
fn a_flat_sea_meets_itself_across_level_borders_and_the_ground_is_skirted() {
    // A flat sea floor 6 blocks under the surface everywhere: the only faces are the sea's
    // surface, the floor's top, and the ground's walls toward another level.
    let (generator, registry, rings, eye) = flat_sea();
    let chunks = rings.all(eye);
    let meshes = mesh_level_chunks(&generator, &registry, &rings, eye, &chunks).unwrap();
    assert_eq!(meshes.len(), chunks.len());
    let mut walls = 0;
    for (l, p, m) in &meshes {
        assert!(m.cutout.is_empty());
        for q in &m.translucent {
            let q = q.unpack().unwrap();
            assert_eq!(q.block, blocks::WATER);
            assert_eq!(q.face, Face::PosY, "a water wall in level {l} chunk {p:?}");
            assert_eq!(q.pos[1], 24, "the surface at the sea level");
        }
        for q in &m.opaque {
            let q = q.unpack().unwrap();
            if matches!(q.face, Face::PosY | Face::NegY) {
                continue;
            }
            // A wall: on the chunk's border, toward a chunk of another level.
            let axis = q.face.axis();
            let at = i64::from(q.pos[axis]);
            let out = if q.face.is_positive() { 1 } else { -1 };
            assert!(
                (q.face.is_positive() && at == 31) || (!q.face.is_positive() && at == 0),
                "a wall inside level {l} chunk {p:?}"
            );
            let mut d = [0; 3];
            d[axis] = out;
            let n = p.offset(d).unwrap();
            assert!(
                !rings.contains(*l, n, eye),
                "a wall between two chunks of level {l}"
            );
            walls += 1;
        }
    }
    assert!(walls > 0, "no skirt where levels meet");
}

#[test]
fn an_edit_reaches_every_level_that_holds_the_block() {
    let (generator, registry, rings, eye) = flat_sea();
    // Above the sea, on a sample column of levels 0 and 2 (not 1), on no chunk border.
    let block = [38, 28, -18];
    let changed = chunks_an_edit_changes(block);
    let levels: Vec<u8> = changed.iter().map(|&(l, _)| l).collect();
    assert_eq!(levels, [0, 2], "{changed:?}");
    // Each level meshed in a view that draws it (a column lies in one level of a view).
    let views = [rings.clone(), rings.coarse_first(2)];
    let chunks: Vec<Vec<(u8, ChunkPos)>> = [0, 2]
        .map(|level| {
            let control = (level, ChunkPos::new(3, 0, 3));
            let mut c: Vec<_> = changed.iter().filter(|c| c.0 == level).copied().collect();
            c.push(control);
            c
        })
        .into();
    let mut cache = LevelCache::default();
    let mesh = |cache: &mut LevelCache| {
        views
            .iter()
            .zip(&chunks)
            .flat_map(|(view, c)| {
                mesh_level_chunks_with(cache, &generator, &registry, view, eye, c).unwrap()
            })
            .collect::<Vec<_>>()
    };
    let before = mesh(&mut cache);
    assert_eq!(cache.edit_count(), 0);
    cache.edit(block, blocks::STONE);
    assert_eq!(cache.edit_count(), 1);
    let after = mesh(&mut cache);
    for ((l, p, a), (_, _, b)) in before.iter().zip(&after) {
        if changed.contains(&(*l, *p)) {
            // A stone cell floating over the sea: its six faces (at level 2 a 4-block-wide
            // cell, one high), its top over the block's column.
            assert_eq!(b.opaque.len(), a.opaque.len() + 6, "level {l} chunk {p:?}");
            let top = b
                .opaque
                .iter()
                .map(|q| q.unpack().unwrap())
                .find(|q| q.block == blocks::STONE && q.face == Face::PosY)
                .expect("the stone's top");
            let s = level_scale(*l);
            let o = voxel_core::level_origin(*l, *p);
            let at = [0, 2].map(|k| o[k] + i64::from(top.pos[k]) * s + s / 2);
            assert_eq!(at, [block[0], block[2]], "level {l}");
        } else {
            assert_eq!(a, b, "level {l} chunk {p:?} changed");
        }
    }
    // A second edit of the block puts the sea's air back.
    cache.edit(block, voxel_core::BlockId::AIR);
    assert_eq!(mesh(&mut cache), before);
}
