//! Tests of the light fields: against a naive fixed-point reference, closed rooms,
//! filters, chunk borders, and incremental updates against full recomputes.

// Channels of parallel arrays (filters, colours, levels) are compared by index.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;
use std::sync::Arc;

use super::props::{self, linear};
use super::*;
use crate::{CHUNK_SIZE, Face, blocks, light_blocks};

const TORCH: BlockId = light_blocks::TORCH;
const F: i32 = LIGHT_FALLOFF as i32;

fn world() -> World {
    World::new(Arc::new(BlockRegistry::with_lights()))
}

fn fill(w: &mut World, min: [i32; 3], max: [i32; 3], id: BlockId) {
    w.fill_box(
        WorldPos::new(min[0], min[1], min[2]),
        WorldPos::new(max[0], max[1], max[2]),
        id,
    )
    .unwrap();
}

fn at(f: &LightField, p: [i32; 3]) -> Light {
    f.get(WorldPos::new(p[0], p[1], p[2])).expect("lit")
}

/// Loads every chunk of the box `min..=max` (chunk coordinates), as air where empty.
fn load(w: &mut World, min: [i32; 3], max: [i32; 3]) {
    for x in min[0]..=max[0] {
        for y in min[1]..=max[1] {
            for z in min[2]..=max[2] {
                let p = ChunkPos::new(x, y, z);
                if w.chunk(p).is_none() {
                    w.insert_chunk(p, crate::Chunk::default()).unwrap();
                }
            }
        }
    }
}

/// Every level of every lit cell, by world position.
fn all_levels(f: &LightField, w: &World) -> HashMap<[i32; 3], Light> {
    let mut out = HashMap::new();
    for (pos, _) in w.iter() {
        let o = pos.origin().map(|v| v as i32);
        let c = f.chunk(pos).expect("every loaded chunk is lit");
        for x in 0..CHUNK_SIZE {
            for y in 0..CHUNK_SIZE {
                for z in 0..CHUNK_SIZE {
                    let p = [o[0] + x as i32, o[1] + y as i32, o[2] + z as i32];
                    out.insert(p, c.get(x, y, z).unwrap());
                }
            }
        }
    }
    out
}

/// The model computed the slow way, independently of the engine: the beam down each
/// column (no gaps), then sweeps of `v = max(source, round(v_n · f) − falloff)` over every
/// cell of the loaded chunks' bounding box until nothing changes.
fn reference(w: &World) -> HashMap<[i32; 3], Light> {
    let table = props::table(w.registry());
    let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
    for (pos, _) in w.iter() {
        let o = pos.origin().map(|v| v as i32);
        for a in 0..3 {
            lo[a] = lo[a].min(o[a]);
            hi[a] = hi[a].max(o[a] + 31);
        }
    }
    let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
    let index = |p: [i32; 3]| -> Option<usize> {
        let ok = (0..3).all(|a| p[a] >= lo[a] && p[a] <= hi[a]);
        ok.then(|| {
            let q = [0, 1, 2].map(|a| (p[a] - lo[a]) as usize);
            (q[0] * size[1] + q[1]) * size[2] + q[2]
        })
    };
    let n = size[0] * size[1] * size[2];
    let mut loaded = vec![false; n];
    let mut pr = vec![table[0]; n];
    let mut level = vec![[0u8; 6]; n];
    let mut cells = Vec::new();
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                let pos = WorldPos::new(x, y, z);
                if w.chunk(pos.split().0).is_some() {
                    let i = index([x, y, z]).unwrap();
                    loaded[i] = true;
                    pr[i] = table[w.get_block(pos).index()];
                    cells.push((i, [x, y, z]));
                }
            }
        }
    }
    // The beam, from above the top of the box (tests load whole columns of chunks).
    for x in lo[0]..=hi[0] {
        for z in lo[2]..=hi[2] {
            let (mut b, mut kind) = ([1.0f32; 3], 0u16);
            for y in (lo[1]..=hi[1]).rev() {
                let i = index([x, y, z]).unwrap();
                if !loaded[i] {
                    // Above the top, or a gap: air.
                    kind = 0;
                    continue;
                }
                let q = pr[i];
                if !q.beam {
                    b = [0.0; 3];
                } else {
                    let f = if q.kind == kind { q.within } else { q.enter };
                    b = [b[0] * f[0], b[1] * f[1], b[2] * f[2]];
                }
                kind = q.kind;
                let s = b.map(|b| (b * 255.0).round() as u8);
                level[i] = [s[0], s[1], s[2], q.emit[0], q.emit[1], q.emit[2]];
            }
        }
    }
    let mut forward = true;
    loop {
        let mut changed = false;
        let order: Box<dyn Iterator<Item = &(usize, [i32; 3])>> = if forward {
            Box::new(cells.iter())
        } else {
            Box::new(cells.iter().rev())
        };
        for &(i, c) in order {
            let q = pr[i];
            if !q.open {
                continue;
            }
            let mut v = level[i];
            for d in Face::ALL.map(Face::normal) {
                let Some(j) = index([c[0] + d[0], c[1] + d[1], c[2] + d[2]]) else {
                    continue;
                };
                if !loaded[j] {
                    continue;
                }
                let vn = level[j];
                for ch in 0..6 {
                    let f = if q.kind == pr[j].kind {
                        q.within_fx
                    } else {
                        q.enter_fx
                    }[ch % 3];
                    let cand = ((u32::from(vn[ch]) * f + (1 << 15)) >> 16) as i32 - F;
                    v[ch] = v[ch].max(cand.max(0) as u8);
                }
            }
            if v != level[i] {
                level[i] = v;
                changed = true;
            }
        }
        forward = !forward;
        if !changed {
            break;
        }
    }
    cells
        .into_iter()
        .map(|(i, c)| (c, Light::from_levels(level[i])))
        .collect()
}

fn assert_same(a: &HashMap<[i32; 3], Light>, b: &HashMap<[i32; 3], Light>, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: cell count");
    let mut bad: Vec<_> = a.iter().filter(|(k, v)| b.get(*k) != Some(v)).collect();
    bad.sort_by_key(|(k, _)| **k);
    assert!(
        bad.is_empty(),
        "{what}: {} cells differ, first {:?} vs {:?}",
        bad.len(),
        bad[0],
        b.get(bad[0].0)
    );
}

/// A tiny deterministic generator (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

#[test]
fn light_source_blocks_have_their_ids() {
    let r = BlockRegistry::with_lights();
    assert_eq!(r.id("torch").unwrap(), light_blocks::TORCH);
    assert_eq!(r.id("lava").unwrap(), light_blocks::LAVA);
    assert_eq!(r.id("glow_glass").unwrap(), light_blocks::GLOW_GLASS);
    assert_eq!(r.get(TORCH).unwrap().emission, [255, 170, 90]);
    assert_eq!(r.get(blocks::STONE).unwrap().emission, [0; 3]);
}

/// The filters come from the numbers the renderer draws the blocks with.
#[test]
fn filters_follow_colour_opacity_and_absorption() {
    let r = BlockRegistry::default();
    let t = props::table(&r);
    let red = r.get(blocks::RED_GLASS).unwrap();
    let c = red.color.map(linear);
    for i in 0..3 {
        let want = (1.0 - red.opacity) + red.opacity * c[i];
        assert!((t[blocks::RED_GLASS.index()].enter[i] - want).abs() < 1e-6);
        assert_eq!(
            t[blocks::RED_GLASS.index()].within[i],
            1.0,
            "thin glass: no volume"
        );
    }
    let water = &t[blocks::WATER.index()];
    let keep = (-crate::WATER_ABSORPTION).exp();
    let wc = r.get(blocks::WATER).unwrap().color.map(linear);
    for i in 0..3 {
        assert!((water.within[i] - (keep + (1.0 - keep) * wc[i])).abs() < 1e-6);
        assert!(water.enter[i] < water.within[i], "the surface filters too");
    }
    assert!(!t[blocks::STONE.index()].open);
    assert!(t[blocks::LEAVES.index()].open && !t[blocks::LEAVES.index()].beam);
}

/// A torch in a closed stone room: the level falls 16 a block, nothing passes the walls,
/// and nothing crosses where two walls meet at a corner.
#[test]
fn a_torch_in_a_closed_room() {
    let mut w = world();
    // Two rooms 7×5×7 inside, sharing only the edge where their walls meet.
    fill(&mut w, [0, 0, 0], [8, 6, 8], blocks::STONE);
    fill(&mut w, [1, 1, 1], [7, 5, 7], BlockId::AIR);
    fill(&mut w, [8, 0, 8], [16, 6, 16], blocks::STONE);
    fill(&mut w, [9, 1, 9], [15, 5, 15], BlockId::AIR);
    // A stone roof high above keeps the sky out.
    fill(&mut w, [-20, 30, -20], [40, 30, 40], blocks::STONE);
    w.set_block(WorldPos::new(4, 3, 4), TORCH).unwrap();
    let f = LightField::new(&w);
    assert_eq!(at(&f, [4, 3, 4]).block, [255, 170, 90]);
    assert_eq!(at(&f, [5, 3, 4]).block, [239, 154, 74]);
    assert_eq!(at(&f, [7, 3, 4]).block, [207, 122, 42]);
    // Manhattan distance 3 + 2 + 3 = 8.
    assert_eq!(at(&f, [7, 1, 7]).block[0], 255 - 8 * 16);
    // Behind the wall, and in the room across the corner: dark.
    assert_eq!(at(&f, [9, 3, 4]).block, [0; 3]);
    for p in [[9, 3, 9], [10, 3, 10], [12, 3, 12]] {
        assert_eq!(at(&f, p).block, [0; 3], "{p:?}: through the corner");
    }
    assert_eq!(at(&f, [4, 3, 4]).sky, [0; 3]);
    assert_same(&all_levels(&f, &w), &reference(&w), "closed rooms");
}

/// Sky light through a red glass roof tints the floor under it by the glass's filter; a
/// torch behind a red glass pane lights the far side red.
#[test]
fn red_glass_tints_the_light_behind_it() {
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 0, 0], [31, 0, 31], blocks::STONE);
    // A roof over the whole (only) chunk: no light comes in from the sides.
    fill(&mut w, [0, 10, 0], [31, 10, 31], blocks::RED_GLASS);
    let f = LightField::new(&w);
    let t = props::table(w.registry())[blocks::RED_GLASS.index()].enter;
    let want = t.map(|t| (t * 255.0).round() as u8);
    assert_eq!(at(&f, [15, 1, 15]).sky, want, "straight down, no falloff");
    assert_eq!(at(&f, [15, 9, 15]).sky, want);
    assert!(want[0] > 200 && want[1] < 140 && want[2] < 140, "{want:?}");
    assert_eq!(at(&f, [15, 11, 15]).sky, [255; 3]);
    // A torch in a closed box with one red glass wall.
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 20, 0], [31, 20, 31], blocks::STONE);
    fill(&mut w, [2, 2, 2], [8, 8, 8], blocks::STONE);
    fill(&mut w, [3, 3, 3], [7, 7, 7], BlockId::AIR);
    fill(&mut w, [8, 3, 3], [8, 7, 7], blocks::RED_GLASS);
    w.set_block(WorldPos::new(5, 5, 5), TORCH).unwrap();
    let f = LightField::new(&w);
    let inside = at(&f, [7, 5, 5]).block;
    let glass = at(&f, [8, 5, 5]).block;
    let beyond = at(&f, [9, 5, 5]).block;
    let rt = props::table(w.registry())[blocks::RED_GLASS.index()].enter_fx;
    for i in 0..3 {
        let g = ((u32::from(inside[i]) * rt[i] + (1 << 15)) >> 16) as u8;
        assert_eq!(glass[i], g.saturating_sub(LIGHT_FALLOFF));
        assert_eq!(beyond[i], glass[i].saturating_sub(LIGHT_FALLOFF));
    }
    assert!(beyond[0] > 140 && beyond[1] < 50, "{beyond:?}: red");
    assert_same(&all_levels(&f, &w), &reference(&w), "red glass");
}

/// Deep water darkens with depth by exactly its surface and a block's filter per block.
#[test]
fn deep_water_darkens_with_depth() {
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 1, 0]);
    fill(&mut w, [0, 0, 0], [31, 0, 31], blocks::SAND);
    fill(&mut w, [0, 1, 0], [31, 40, 31], blocks::WATER);
    let f = LightField::new(&w);
    let t = props::table(w.registry())[blocks::WATER.index()];
    let mut last = [255u8; 3];
    for depth in 1..=40 {
        let y = 41 - depth;
        let sky = at(&f, [16, y, 16]).sky;
        for i in 0..3 {
            let want = 255.0 * t.enter[i] * t.within[i].powi(depth - 1);
            assert!(
                (f32::from(sky[i]) - want).abs() <= 0.5 + want * 1e-4,
                "depth {depth}"
            );
            assert!(sky[i] <= last[i]);
        }
        last = sky;
    }
    assert!(last[2] > last[0], "the deep floor is blue: {last:?}");
    assert!(last.iter().all(|&v| v < 40), "and dark: {last:?}");
}

/// Light crosses chunk borders as if there were none.
#[test]
fn light_is_continuous_across_chunk_borders() {
    let mut w = world();
    load(&mut w, [-1, 0, -1], [1, 1, 1]);
    fill(&mut w, [-40, 50, -40], [70, 50, 70], blocks::STONE);
    fill(&mut w, [-40, 0, -40], [70, 0, 70], blocks::STONE);
    // One torch on the corner of four chunks, one in the middle of a chunk.
    let mut f = LightField::new(&w);
    f.take_changed();
    w.set_block_lit(&mut f, WorldPos::new(0, 5, 0), TORCH)
        .unwrap();
    let around: Vec<_> = [[-1, -1], [-1, 0], [0, -1], [0, 0]]
        .map(|[x, z]| ChunkPos::new(x, 0, z))
        .into();
    assert_eq!(f.take_changed(), around, "the four chunks the torch lights");
    let mut g = world();
    load(&mut g, [-1, 0, -1], [1, 1, 1]);
    fill(&mut g, [-40, 50, -40], [70, 50, 70], blocks::STONE);
    fill(&mut g, [-40, 0, -40], [70, 0, 70], blocks::STONE);
    g.set_block(WorldPos::new(16, 5, 16), TORCH).unwrap();
    let h = LightField::new(&g);
    for dx in -15..=15 {
        for dy in -4..=15 {
            for dz in -15..=15 {
                assert_eq!(
                    at(&f, [dx, 5 + dy, dz]).block,
                    at(&h, [16 + dx, 5 + dy, 16 + dz]).block,
                    "offset ({dx}, {dy}, {dz})"
                );
            }
        }
    }
    assert_same(&all_levels(&f, &w), &reference(&w), "chunk borders");
}

/// Removing the torch of a closed room restores darkness exactly.
#[test]
fn removing_a_torch_restores_darkness() {
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 0, 0], [20, 20, 20], blocks::STONE);
    fill(&mut w, [1, 1, 1], [19, 19, 19], BlockId::AIR);
    let mut f = LightField::new(&w);
    let dark = all_levels(&f, &w);
    assert_eq!(f.take_changed(), vec![ChunkPos::new(0, 0, 0)]);
    w.set_block_lit(&mut f, WorldPos::new(10, 10, 10), TORCH)
        .unwrap();
    assert_eq!(at(&f, [10, 12, 10]).block, [223, 138, 58]);
    assert_eq!(f.take_changed(), vec![ChunkPos::new(0, 0, 0)]);
    assert!(f.take_changed().is_empty());
    assert_same(
        &all_levels(&f, &w),
        &all_levels(&LightField::new(&w), &w),
        "placed",
    );
    w.set_block_lit(&mut f, WorldPos::new(10, 10, 10), BlockId::AIR)
        .unwrap();
    assert_same(&all_levels(&f, &w), &dark, "removed");
}

/// Random edits (torches, glass, water, stone, air, leaves, lava) in a generated terrain,
/// each applied incrementally: the field equals a full recompute, which equals the
/// reference.
#[test]
fn incremental_edits_equal_a_full_recompute() {
    let terrain = crate::TerrainGenerator::new(crate::TerrainConfig::default());
    let registry = Arc::new(BlockRegistry::with_lights());
    let mut w = terrain
        .generate_world(registry, ChunkPos::new(0, 0, 0), ChunkPos::new(1, 1, 1))
        .unwrap();
    let mut f = LightField::new(&w);
    assert_same(&all_levels(&f, &w), &reference(&w), "generated terrain");
    let palette = [
        BlockId::AIR,
        BlockId::AIR,
        TORCH,
        TORCH,
        light_blocks::LAVA,
        light_blocks::GLOW_GLASS,
        blocks::STONE,
        blocks::RED_GLASS,
        blocks::BLUE_GLASS,
        blocks::WATER,
        blocks::LEAVES,
        blocks::ICE,
    ];
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let mut placed = Vec::new();
    for i in 0..400 {
        // Near the ground, with some edits on chunk borders.
        let mut p = [
            rng.below(64) as i32,
            10 + rng.below(40) as i32,
            rng.below(64) as i32,
        ];
        if i % 5 == 0 {
            p[(i / 5) % 3] = [31, 32][rng.below(2) as usize];
        }
        let id = if i % 3 == 2 && !placed.is_empty() {
            // Take back an earlier edit.
            let (q, _) = placed.swap_remove(rng.below(placed.len() as u64) as usize);
            p = q;
            BlockId::AIR
        } else {
            palette[rng.below(palette.len() as u64) as usize]
        };
        let pos = WorldPos::new(p[0], p[1], p[2]);
        w.set_block_lit(&mut f, pos, id).unwrap();
        placed.push((p, id));
        if i % 50 == 49 {
            assert_same(
                &all_levels(&f, &w),
                &all_levels(&LightField::new(&w), &w),
                &format!("after edit {i}"),
            );
        }
    }
    assert_same(&all_levels(&f, &w), &reference(&w), "after the edits");
}

/// Chunks lit as they stream in and unlit as they go give what lighting the whole world
/// gives; the beam passes down through a gap of unlit chunks.
#[test]
fn chunks_lit_as_they_stream_equal_a_full_light() {
    let terrain = crate::TerrainGenerator::new(crate::TerrainConfig::default());
    let registry = Arc::new(BlockRegistry::with_lights());
    let full = terrain
        .generate_world(
            registry.clone(),
            ChunkPos::new(0, 0, 0),
            ChunkPos::new(1, 1, 1),
        )
        .unwrap();
    let mut w = World::new(registry.clone());
    let mut f = LightField::empty(registry);
    // Bottom chunks first, so that each top chunk shades the one below as it comes.
    let mut order: Vec<ChunkPos> = full.iter().map(|(p, _)| p).collect();
    order.sort_by_key(|p| (p.y, p.x, p.z));
    for p in order {
        w.insert_chunk(p, full.chunk(p).unwrap().clone()).unwrap();
        w.set_block(
            WorldPos::new(p.x * 32 + 7, p.y * 32 + 30, p.z * 32 + 9),
            TORCH,
        )
        .unwrap();
        assert!(f.add_chunk(&w, p).unwrap());
        assert_same(
            &all_levels(&f, &w),
            &all_levels(&LightField::new(&w), &w),
            &format!("add {p:?}"),
        );
    }
    for p in [ChunkPos::new(0, 1, 0), ChunkPos::new(1, 0, 1)] {
        assert!(f.remove_chunk(&w, p).unwrap());
        w.remove_chunk(p);
        assert_same(
            &all_levels(&f, &w),
            &all_levels(&LightField::new(&w), &w),
            &format!("remove {p:?}"),
        );
    }
    assert!(!f.remove_chunk(&w, ChunkPos::new(0, 1, 0)).unwrap());
    // A chunk replaced in place (its old light and bottom blocks gone) is relit.
    let mut hollow = w.chunk(ChunkPos::new(1, 1, 0)).unwrap().clone();
    hollow
        .fill_box([0, 0, 0], [31, 20, 31], BlockId::AIR)
        .unwrap();
    hollow.set(5, 5, 5, light_blocks::LAVA).unwrap();
    w.insert_chunk(ChunkPos::new(1, 1, 0), hollow).unwrap();
    assert!(f.add_chunk(&w, ChunkPos::new(1, 1, 0)).unwrap());
    assert_same(
        &all_levels(&f, &w),
        &all_levels(&LightField::new(&w), &w),
        "replaced",
    );
    // A chunk high above with a gap between: its shade falls through the gap.
    let high = ChunkPos::new(1, 3, 1);
    w.insert_chunk(high, crate::Chunk::uniform(blocks::STONE))
        .unwrap();
    f.add_chunk(&w, high).unwrap();
    assert_same(
        &all_levels(&f, &w),
        &all_levels(&LightField::new(&w), &w),
        "high chunk",
    );
    assert_eq!(at(&f, [48, 63, 48]).sky, [0; 3], "under the stone chunk");
}

#[test]
fn a_world_over_another_registry_is_an_error() {
    let mut w = world();
    let mut f = LightField::empty(Arc::new(BlockRegistry::default()));
    assert_eq!(
        f.set_block(&mut w, WorldPos::new(0, 0, 0), TORCH),
        Err(Error::LightRegistry)
    );
    let mut f = LightField::new(&w);
    let err = f.set_block(&mut w, WorldPos::new(0, 0, 0), BlockId(999));
    assert!(matches!(err, Err(Error::UnknownBlock(..))));
    assert_eq!(w.get_block(WorldPos::new(0, 0, 0)), BlockId::AIR);
}

#[test]
fn storage_is_six_bytes_a_block_where_layers_vary() {
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 1, 0]);
    fill(&mut w, [0, 0, 0], [31, 15, 31], blocks::STONE);
    let f = LightField::new(&w);
    // Open sky above the ground, dark below: no layer varies but where the sky spreads.
    let top = f.chunk(ChunkPos::new(0, 1, 0)).unwrap();
    assert_eq!(top.dense_layers(), 0);
    let ground = f.chunk(ChunkPos::new(0, 0, 0)).unwrap();
    assert_eq!(ground.dense_layers(), 0, "flat ground: every layer uniform");
    assert!(f.memory_bytes() < 4096, "{}", f.memory_bytes());
}

/// Every dense layer's odd cells are the cells holding other levels than its reference,
/// made anew after an edit writes the layer.
#[test]
fn odd_cells_follow_the_edits() {
    let mut w = world();
    load(&mut w, [0, 0, 0], [0, 0, 0]);
    fill(&mut w, [0, 0, 0], [31, 4, 31], blocks::STONE);
    fill(&mut w, [4, 5, 4], [12, 9, 12], blocks::WATER);
    let mut f = LightField::new(&w);
    let p = ChunkPos::new(0, 0, 0);
    let check = |f: &LightField| {
        let c = f.chunk(p).expect("lit");
        let mut dense = 0;
        for y in 0..CHUNK_SIZE {
            let (LightLayer::Dense(d), Some(odd)) = (c.layer(y), c.odd_cells(y)) else {
                assert!(c.odd_cells(y).is_none(), "a uniform layer has none");
                continue;
            };
            dense += 1;
            for x in 0..CHUNK_SIZE {
                for z in 0..CHUNK_SIZE {
                    let want = d[x << 5 | z] != odd.reference;
                    assert_eq!(odd.rows[z] >> x & 1 != 0, want, "({x}, {y}, {z})");
                }
            }
        }
        dense
    };
    assert!(check(&f) > 0, "water makes dense layers");
    for (q, id) in [
        ([8, 7, 20], TORCH),
        ([20, 6, 8], TORCH),
        ([8, 7, 20], BlockId::AIR),
        ([6, 5, 6], blocks::STONE),
    ] {
        w.set_block_lit(&mut f, WorldPos::new(q[0], q[1], q[2]), id)
            .unwrap();
        check(&f);
    }
}

/// Chunks lit in batches ([`LightField::add_chunks`]: some stacked in one column, some
/// beside lit ones, some above and below lit ones, one lit already) give what lighting
/// the whole world gives.
#[test]
fn chunks_lit_in_batches_equal_a_full_light() {
    let terrain = crate::TerrainGenerator::new(crate::TerrainConfig::default());
    let registry = Arc::new(BlockRegistry::with_lights());
    let full = terrain
        .generate_world(
            registry.clone(),
            ChunkPos::new(0, -1, 0),
            ChunkPos::new(2, 2, 1),
        )
        .unwrap();
    let mut w = World::new(registry.clone());
    let mut f = LightField::empty(registry);
    let mut all: Vec<ChunkPos> = full.iter().map(|(p, _)| p).collect();
    all.sort_by_key(|p| (p.x * 7 + p.y * 3 + p.z * 5) % 4);
    let batches: Vec<Vec<ChunkPos>> = all.chunks(all.len() / 3 + 1).map(<[_]>::to_vec).collect();
    for (i, batch) in batches.iter().enumerate() {
        for &p in batch {
            let mut c = full.chunk(p).unwrap().clone();
            c.set(7, 30, 9, TORCH).unwrap();
            c.set(20, 3, 20, blocks::RED_GLASS).unwrap();
            w.insert_chunk(p, c).unwrap();
        }
        // One lit already comes again, its blocks changed.
        let mut positions = batch.clone();
        if i > 0 {
            let again = batches[0][0];
            let mut c = w.chunk(again).unwrap().clone();
            c.fill_box([0, 10, 0], [31, 12, 31], BlockId::AIR).unwrap();
            w.insert_chunk(again, c).unwrap();
            positions.push(again);
        }
        f.add_chunks(&w, &positions).unwrap();
        assert_same(
            &all_levels(&f, &w),
            &all_levels(&LightField::new(&w), &w),
            &format!("batch {i} of {}", batch.len()),
        );
    }
    assert_eq!(f.len(), full.len());
}

/// Chunks of air unlit at the top of a column and between lit chunks (the beam passes
/// down as through a gap) give what lighting the rest gives.
#[test]
fn air_chunks_unlit_equal_a_full_light() {
    let registry = Arc::new(BlockRegistry::with_lights());
    let mut w = World::new(registry);
    for y in -1..=3 {
        for x in 0..2 {
            w.insert_chunk(ChunkPos::new(x, y, 0), crate::Chunk::default())
                .unwrap();
        }
    }
    // Ground with a pool and red glass in chunk row 0, stone at row 2 over half of it.
    fill(&mut w, [0, -32, 0], [63, 4, 31], blocks::STONE);
    fill(&mut w, [5, 2, 5], [20, 4, 20], blocks::WATER);
    fill(&mut w, [30, 5, 3], [40, 5, 12], blocks::RED_GLASS);
    fill(&mut w, [0, 70, 0], [31, 72, 31], blocks::STONE);
    w.set_block(WorldPos::new(40, 8, 20), TORCH).unwrap();
    let mut f = LightField::new(&w);
    for p in [
        ChunkPos::new(0, 3, 0),
        ChunkPos::new(1, 1, 0),
        ChunkPos::new(0, 1, 0),
        ChunkPos::new(1, 3, 0),
    ] {
        assert_eq!(
            w.chunk(p).unwrap().as_uniform(),
            Some(BlockId::AIR),
            "{p:?}"
        );
        assert!(f.remove_chunk(&w, p).unwrap());
        w.remove_chunk(p);
        assert_same(
            &all_levels(&f, &w),
            &all_levels(&LightField::new(&w), &w),
            &format!("remove {p:?}"),
        );
    }
}
