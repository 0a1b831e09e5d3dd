//! Mesher, storage and terrain benchmarks. Prints figures; asserts nothing about time.
//!
//! `cargo bench -p voxel-mesh` measures, on the same terrain chunks (with water, glass and
//! leaves), our mesher against binary-greedy-meshing 0.5 and block-mesh 0.2 in one run, and
//! reports medians of interleaved rounds so that machine noise hits every mesher alike.
//!
//! Fairness: binary-greedy-meshing gets its input ready-made (the padded 34³ array and the
//! opaque/transparent column masks its `fast_mesh` expects a chunk to maintain), outside the
//! timed region. Ours is timed from our chunk storage and the 26 neighbour chunks, with all
//! neighbour lookups inside the timed region, and it produces three meshes instead of one,
//! with per-vertex ambient occlusion (which binary-greedy-meshing does not compute); ours
//! without ambient occlusion is timed in the same rounds.
//!
//! Ours is timed twice in the same rounds: from the mask form (the mesher's input, as
//! stored), and from the packed form (the compact resident form: the mesher builds the
//! centre's masks into its scratch memory and reads the neighbours' touching layers from
//! their bit planes). The storage section reports the memory of both forms against a
//! packed-index palette, and the cost of converting between them.
//!
//! The lit section times the lit mesher (`Mesher::mesh_lit`, smooth light per vertex from
//! a `LightField`) against ours with AO on the same chunks in the same interleaved rounds,
//! and counts what light costs in quads and stream bytes. `cargo bench -p voxel-mesh
//! --bench mesher -- lit` runs that section alone.

use std::collections::BTreeSet;
use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use binary_greedy_meshing as bgm;
use block_mesh::ndshape::{ConstShape, ConstShape3u32};
use block_mesh::{
    GreedyQuadsBuffer, MergeVoxel, RIGHT_HANDED_Y_UP_CONFIG, Voxel, VoxelVisibility, greedy_quads,
};
use voxel_core::Neighbourhood;
use voxel_core::blocks::{GLASS, LEAVES, WATER};
use voxel_core::{
    BlockId, BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, Face, LightField, MaskBuffer, RenderClass,
    TerrainConfig, TerrainGenerator, World, blocks,
};
use voxel_mesh::{ChunkMeshes, MeshOptions, Mesher, mesh_chunks};

#[path = "../tests/common/exact_merge.rs"]
mod exact_merge;

/// The mesher without ambient occlusion (the peer of "ours" with it).
fn without_ao(reg: &BlockRegistry) -> Mesher {
    Mesher::with_options(
        reg,
        MeshOptions {
            ambient_occlusion: false,
            ..MeshOptions::default()
        },
    )
}

const CS: usize = 32;
type Bgm = bgm::Mesher<CS>;
type Padded = ConstShape3u32<34, 34, 34>;

#[derive(Clone, Copy, PartialEq, Eq)]
struct BmVoxel(u16, VoxelVisibility);

impl Voxel for BmVoxel {
    fn get_visibility(&self) -> VoxelVisibility {
        self.1
    }
}

impl MergeVoxel for BmVoxel {
    type MergeValue = u16;
    fn merge_value(&self) -> u16 {
        self.0
    }
}

/// One chunk with what each peer needs, prepared outside the timed regions. Ours reads
/// the chunk and its neighbours from the shared world, as `mesh_chunks` does.
struct Case {
    pos: ChunkPos,
    bgm_voxels: Vec<u16>,
    bgm_opaque: Box<[u64]>,
    bgm_trans: Box<[u64]>,
    bm_voxels: Vec<BmVoxel>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

/// The block at padded coordinates `p` (each -1..=32) of a chunk with its neighbours.
fn padded_block(c: &Chunk, nb: &[Option<Chunk>], p: [i32; 3]) -> BlockId {
    let outside: Vec<Face> = Face::ALL
        .into_iter()
        .filter(|f| {
            let v = p[f.axis()];
            if f.is_positive() { v == 32 } else { v == -1 }
        })
        .collect();
    let l = p.map(|v| v.rem_euclid(32) as usize);
    let get = |c: &Chunk| c.get(l[0], l[1], l[2]).expect("in range");
    match outside.as_slice() {
        [] => get(c),
        [f] => nb[*f as usize].as_ref().map_or(BlockId::AIR, get),
        _ => BlockId::AIR,
    }
}

fn prepare(reg: &BlockRegistry, world: &World, pos: ChunkPos) -> Case {
    let chunk = world.chunk(pos).expect("generated").clone();
    let neighbours: Vec<Option<Chunk>> = Face::ALL
        .iter()
        .map(|f| world.neighbourhood(pos).face(*f).cloned())
        .collect();
    let _ = &chunk;
    let transparents: BTreeSet<u16> = reg
        .iter()
        .filter(|(_, d)| matches!(d.class, RenderClass::Cutout | RenderClass::Translucent))
        .map(|(id, _)| id.0)
        .collect();
    let mut bgm_voxels = vec![0u16; Bgm::CS_P3];
    let mut bm_voxels = vec![BmVoxel(0, VoxelVisibility::Empty); Padded::SIZE as usize];
    for px in 0..34 {
        for py in 0..34 {
            for pz in 0..34 {
                let id = padded_block(&chunk, &neighbours, [px - 1, py - 1, pz - 1]);
                let (px, py, pz) = (px as usize, py as usize, pz as usize);
                // binary-greedy-meshing's padded layout: z fastest, then x, then y.
                bgm_voxels[pz + px * Bgm::CS_P + py * Bgm::CS_P2] = id.0;
                let vis = match reg.class(id).expect("known") {
                    RenderClass::Air => VoxelVisibility::Empty,
                    RenderClass::Opaque => VoxelVisibility::Opaque,
                    _ => VoxelVisibility::Translucent,
                };
                bm_voxels[Padded::linearize([px as u32, py as u32, pz as u32]) as usize] =
                    BmVoxel(id.0, vis);
            }
        }
    }
    let bgm_opaque = bgm::compute_opaque_mask::<CS>(&bgm_voxels, &transparents);
    let bgm_trans = bgm::compute_transparent_mask::<CS>(&bgm_voxels, &transparents);
    Case {
        pos,
        bgm_voxels,
        bgm_opaque,
        bgm_trans,
        bm_voxels,
    }
}

/// Terrain chunks around shore structures: non-uniform, holding water, and as a set holding
/// glass and leaves too.
fn pick_cases(reg: &BlockRegistry, generator: &TerrainGenerator) -> (World, Vec<Case>) {
    let sites = generator.sites_in(-512, -512, 512, 512);
    let mut positions = Vec::new();
    for s in &sites {
        let c = [s.center[0], s.center[2]].map(|v| v.div_euclid(CHUNK_SIZE as i64) as i32);
        for dx in -1..=1 {
            for dz in -1..=1 {
                for y in 0..2 {
                    let p = ChunkPos::new(c[0] + dx, y, c[1] + dz);
                    if !positions.contains(&p) {
                        positions.push(p);
                    }
                }
            }
        }
    }
    let registry = Arc::new(reg.clone());
    let mut world = World::new(registry);
    for p in &positions {
        for q in Neighbourhood::OFFSETS
            .iter()
            .filter_map(|d| p.offset(*d))
            .chain([*p])
        {
            if world.chunk(q).is_none() {
                world
                    .insert_chunk(q, generator.generate_chunk(q))
                    .expect("valid");
            }
        }
    }
    let cases = positions
        .into_iter()
        .filter(|p| {
            let c = world.chunk(*p).expect("generated");
            c.as_uniform().is_none() && c.count(WATER) > 0
        })
        .take(32)
        .map(|p| prepare(reg, &world, p))
        .collect();
    (world, cases)
}

fn main() {
    let reg = BlockRegistry::default();
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let (world, cases) = pick_cases(&reg, &generator);
    let chunk = |c: &Case| world.chunk(c.pos).expect("generated");
    let has = |id| cases.iter().filter(|c| chunk(c).count(id) > 0).count();
    println!("# voxel-mesh benchmark");
    println!(
        "cases: {} terrain chunks of 32^3 around shore structures; with water {}, glass {}, leaves {}; mean block types per chunk {:.1}",
        cases.len(),
        has(WATER),
        has(GLASS),
        has(LEAVES),
        cases.iter().map(|c| chunk(c).palette_len()).sum::<usize>() as f64 / cases.len() as f64
    );
    assert!(
        has(GLASS) > 0 && has(LEAVES) > 0,
        "bench chunks must hold glass and leaves"
    );
    if std::env::args().skip(1).any(|a| a == "lit") {
        lit_section(&reg, &world, &cases, &generator);
        return;
    }
    let mut packed = world.clone();
    packed.pack_all();
    mesher_section(&reg, &world, &packed, &cases);
    lit_section(&reg, &world, &cases, &generator);
    storage_and_terrain_section(&reg, &generator);
}

/// The lit mesher against ours with AO (the same options, ambient occlusion on) on the
/// bench chunks, lit by one `LightField` over the chunks and their neighbours, in
/// interleaved rounds; then quads with and without light on a terrain world.
fn lit_section(reg: &BlockRegistry, world: &World, cases: &[Case], generator: &TerrainGenerator) {
    let t = Instant::now();
    let light = LightField::new(world);
    let light_s = secs(t.elapsed());
    let mut ours = Mesher::new(reg);
    let mut lit = Mesher::new(reg);
    let mut out = ChunkMeshes::default();
    let n = cases.len() as f64;
    let (mut q_plain, mut q_lit, mut split, mut bytes, mut palette, mut palette_max) =
        (0, 0, [0; 3], 0, 0, 0);
    for c in cases {
        let chunk = world.chunk(c.pos).expect("generated");
        ours.mesh_into(chunk, world.neighbourhood(c.pos), &mut out)
            .expect("known blocks");
        q_plain += out.len();
        lit.mesh_lit_into(chunk, world.neighbourhood(c.pos), &light, c.pos, &mut out)
            .expect("meshes");
        q_lit += out.len();
        split[0] += out.opaque.len();
        split[1] += out.cutout.len();
        split[2] += out.translucent.len();
        bytes += out.light.bytes();
        palette += out.light.palette.len();
        palette_max = palette_max.max(out.light.palette.len());
    }
    println!(
        "\n## lit mesher ({} chunks lit by LightField::new over {} chunks in {:.0} ms, one thread)",
        cases.len(),
        world.len(),
        light_s * 1e3
    );
    println!(
        "quads per chunk: with AO {:.0}, lit {:.0} (opaque {:.0} / cutout {:.0} / translucent {:.0}) = {:.3}x",
        q_plain as f64 / n,
        q_lit as f64 / n,
        split[0] as f64 / n,
        split[1] as f64 / n,
        split[2] as f64 / n,
        q_lit as f64 / q_plain as f64
    );
    println!(
        "light streams per chunk: {:.0} bytes ({:.2} bytes a quad: 8 a quad + 8 a palette entry; palette mean {:.1}, max {palette_max} entries); quads {:.0} bytes",
        bytes as f64 / n,
        bytes as f64 / q_lit as f64,
        palette as f64 / n,
        (q_lit * 8) as f64 / n
    );

    const ROUNDS: usize = 61;
    let mut times: [Vec<f64>; 2] = Default::default();
    for round in 0..ROUNDS {
        for k in 0..2 {
            let method = (round + k) % 2;
            let t = Instant::now();
            for c in cases {
                let chunk = world.chunk(c.pos).expect("generated");
                if method == 0 {
                    ours.mesh_into(black_box(chunk), world.neighbourhood(c.pos), &mut out)
                        .expect("known blocks");
                } else {
                    lit.mesh_lit_into(
                        black_box(chunk),
                        world.neighbourhood(c.pos),
                        &light,
                        c.pos,
                        &mut out,
                    )
                    .expect("meshes");
                }
                black_box(&out);
            }
            times[method].push(secs(t.elapsed()) / n);
        }
    }
    let [t_ao, t_lit] = times.map(|t| median(t) * 1e6);
    println!("µs per chunk, median of {ROUNDS} interleaved rounds:");
    println!("ours with AO                                          {t_ao:9.1}");
    println!("lit (AO and smooth light, light streams)              {t_lit:9.1}");
    println!(
        "ratio lit / ours with AO = {:.3} (target <= 1.3)",
        t_lit / t_ao
    );

    // A terrain world: what light costs in quads.
    let registry = Arc::new(reg.clone());
    let terrain = generator
        .generate_world(registry, ChunkPos::new(-8, 0, -8), ChunkPos::new(7, 1, 7))
        .expect("valid world");
    let t = Instant::now();
    let light = LightField::new(&terrain);
    let light_s = secs(t.elapsed());
    // The first lit pass over a field just lit makes each dense layer's odd cells
    // (`LightChunk::odd_cells`), as the first mesh after an edit does for the layers the
    // edit wrote; the interleaved rounds below find them made. Timed once, cold, beside a
    // pass with AO.
    let cold_lit = {
        let t = Instant::now();
        for (p, chunk) in terrain.iter() {
            lit.mesh_lit_into(chunk, terrain.neighbourhood(p), &light, p, &mut out)
                .expect("meshes");
            black_box(&out);
        }
        secs(t.elapsed()) / terrain.len() as f64 * 1e6
    };
    let cold_ao = {
        let t = Instant::now();
        for (p, chunk) in terrain.iter() {
            ours.mesh_into(chunk, terrain.neighbourhood(p), &mut out)
                .expect("known blocks");
            black_box(&out);
        }
        secs(t.elapsed()) / terrain.len() as f64 * 1e6
    };
    println!(
        "the terrain world's first lit pass (odd cells made as it reads them), µs per chunk: lit {cold_lit:.1}, then with AO {cold_ao:.1}, ratio {:.3}",
        cold_lit / cold_ao
    );
    let (mut plain, mut with, mut bytes, mut quad_bytes) = (0, 0, 0, 0);
    for (p, chunk) in terrain.iter() {
        ours.mesh_into(chunk, terrain.neighbourhood(p), &mut out)
            .expect("known blocks");
        plain += out.len();
        lit.mesh_lit_into(chunk, terrain.neighbourhood(p), &light, p, &mut out)
            .expect("meshes");
        with += out.len();
        bytes += out.light.bytes();
        quad_bytes += out.len() * std::mem::size_of::<voxel_mesh::PackedQuad>();
    }
    println!(
        "terrain world of {} chunks (lit in {:.0} ms, one thread): quads lit / with AO = {with} / {plain} = {:.3}; light streams {:.2} MiB beside {:.2} MiB of quads",
        terrain.len(),
        light_s * 1e3,
        with as f64 / plain as f64,
        bytes as f64 / (1 << 20) as f64,
        quad_bytes as f64 / (1 << 20) as f64
    );
    // The same world's chunks timed, one thread, interleaved rounds.
    let all: Vec<ChunkPos> = terrain.iter().map(|(p, _)| p).collect();
    const WORLD_ROUNDS: usize = 7;
    let mut times: [Vec<f64>; 2] = Default::default();
    for round in 0..WORLD_ROUNDS {
        for k in 0..2 {
            let method = (round + k) % 2;
            let t = Instant::now();
            for &p in &all {
                let chunk = terrain.chunk(p).expect("generated");
                if method == 0 {
                    ours.mesh_into(black_box(chunk), terrain.neighbourhood(p), &mut out)
                        .expect("known blocks");
                } else {
                    lit.mesh_lit_into(
                        black_box(chunk),
                        terrain.neighbourhood(p),
                        &light,
                        p,
                        &mut out,
                    )
                    .expect("meshes");
                }
                black_box(&out);
            }
            times[method].push(secs(t.elapsed()) / all.len() as f64);
        }
    }
    let [w_ao, w_lit] = times.map(|t| median(t) * 1e6);
    println!(
        "the terrain world's chunks, µs per chunk (median of {WORLD_ROUNDS} interleaved rounds): with AO {w_ao:.1}, lit {w_lit:.1}, ratio {:.3}",
        w_lit / w_ao
    );
}

fn mesher_section(reg: &BlockRegistry, world: &World, packed: &World, cases: &[Case]) {
    let mut ours = Mesher::new(reg);
    let mut plain = without_ao(reg);
    let mut out = ChunkMeshes::default();
    let mut theirs = Bgm::new();
    let mut bm_buf = GreedyQuadsBuffer::new(Padded::SIZE as usize);
    let n = cases.len() as f64;

    // Output sizes, once.
    let (mut q_ours, mut q_split, mut q_bgm, mut q_bm, mut q_plain) = (0, [0; 3], 0, 0, 0);
    for c in cases {
        let chunk = world.chunk(c.pos).expect("generated");
        plain
            .mesh_into(chunk, world.neighbourhood(c.pos), &mut out)
            .expect("known blocks");
        q_plain += out.len();
        ours.mesh_into(chunk, world.neighbourhood(c.pos), &mut out)
            .expect("known blocks");
        q_ours += out.len();
        let from_masks = out.clone();
        ours.mesh_into(
            packed.chunk(c.pos).expect("generated"),
            packed.neighbourhood(c.pos),
            &mut out,
        )
        .expect("known blocks");
        assert_eq!(out, from_masks, "packed chunks mesh like mask chunks");
        q_split[0] += out.opaque.len();
        q_split[1] += out.cutout.len();
        q_split[2] += out.translucent.len();
        theirs.clear();
        theirs.fast_mesh(&c.bgm_voxels, &c.bgm_opaque, &c.bgm_trans);
        q_bgm += theirs.quads.iter().map(Vec::len).sum::<usize>();
        bm_buf.reset(Padded::SIZE as usize);
        greedy_quads(
            &c.bm_voxels,
            &Padded {},
            [0; 3],
            [33; 3],
            &RIGHT_HANDED_Y_UP_CONFIG.faces,
            &mut bm_buf,
        );
        q_bm += bm_buf.quads.num_quads();
    }
    println!(
        "quads per chunk: ours {:.0} (opaque {:.0} / cutout {:.0} / translucent {:.0}; without AO {:.0}), binary-greedy-meshing {:.0}, block-mesh {:.0}",
        q_ours as f64 / n,
        q_split[0] as f64 / n,
        q_split[1] as f64 / n,
        q_split[2] as f64 / n,
        q_plain as f64 / n,
        q_bgm as f64 / n,
        q_bm as f64 / n
    );

    const ROUNDS: usize = 41;
    let transparents: BTreeSet<u16> = reg
        .iter()
        .filter(|(_, d)| matches!(d.class, RenderClass::Cutout | RenderClass::Translucent))
        .map(|(id, _)| id.0)
        .collect();
    const METHODS: usize = 6;
    let mut times: [Vec<f64>; METHODS] = Default::default();
    for round in 0..ROUNDS {
        // The order rotates every round, so that no mesher always runs cold right after
        // another one's sweep through memory.
        for k in 0..METHODS {
            let method = (round + k) % METHODS;
            // block-mesh is ~20× slower: a third of the rounds is plenty.
            if method == 3 && round % 3 != 0 {
                continue;
            }
            let t = Instant::now();
            for c in cases {
                match method {
                    0 => {
                        let chunk = world.chunk(c.pos).expect("generated");
                        ours.mesh_into(black_box(chunk), world.neighbourhood(c.pos), &mut out)
                            .expect("known blocks");
                        black_box(&out);
                    }
                    4 => {
                        let chunk = packed.chunk(c.pos).expect("generated");
                        ours.mesh_into(black_box(chunk), packed.neighbourhood(c.pos), &mut out)
                            .expect("known blocks");
                        black_box(&out);
                    }
                    5 => {
                        let chunk = world.chunk(c.pos).expect("generated");
                        plain
                            .mesh_into(black_box(chunk), world.neighbourhood(c.pos), &mut out)
                            .expect("known blocks");
                        black_box(&out);
                    }
                    1 => {
                        theirs.clear();
                        theirs.fast_mesh(
                            black_box(&c.bgm_voxels),
                            black_box(&c.bgm_opaque),
                            black_box(&c.bgm_trans),
                        );
                        black_box(&theirs.quads);
                    }
                    2 => {
                        theirs.clear();
                        theirs.mesh(black_box(&c.bgm_voxels), black_box(&transparents));
                        black_box(&theirs.quads);
                    }
                    _ => {
                        bm_buf.reset(Padded::SIZE as usize);
                        greedy_quads(
                            black_box(&c.bm_voxels),
                            &Padded {},
                            [0; 3],
                            [33; 3],
                            &RIGHT_HANDED_Y_UP_CONFIG.faces,
                            &mut bm_buf,
                        );
                        black_box(&bm_buf.quads);
                    }
                }
            }
            times[method].push(secs(t.elapsed()) / n);
        }
    }
    let [t_ours, t_bgm_fast, t_bgm_mesh, t_bm, t_packed, t_plain] = times;
    let us = |v: Vec<f64>| median(v) * 1e6;
    let (ours_us, fast_us, mesh_us, bm_us) = (us(t_ours), us(t_bgm_fast), us(t_bgm_mesh), us(t_bm));
    let (packed_us, plain_us) = (us(t_packed), us(t_plain));
    println!("\n## mesher (µs per 32^3 chunk, median of {ROUNDS} interleaved rounds)");
    println!("ours with AO (three meshes, chunk storage + 26 neighbours) {ours_us:5.1}");
    println!("ours without AO                                       {plain_us:9.1}");
    println!("binary-greedy-meshing 0.5 fast_mesh (input prepared)  {fast_us:9.1}");
    println!("binary-greedy-meshing 0.5 mesh (BTreeSet transparents) {mesh_us:8.1}");
    println!("block-mesh 0.2 greedy_quads                           {bm_us:9.1}");
    println!("ours with AO, packed chunk + packed neighbours (masks built) {packed_us:3.1}");
    println!(
        "ratio ours with AO / binary-greedy-meshing fast_mesh = {:.3} (target <= 1.0)",
        ours_us / fast_us
    );
    println!(
        "ratio ours without AO / binary-greedy-meshing fast_mesh = {:.3}",
        plain_us / fast_us
    );
    println!(
        "ratio ours packed / binary-greedy-meshing fast_mesh = {:.3}",
        packed_us / fast_us
    );
    println!(
        "ratio block-mesh greedy_quads / ours = {:.1}x (target >= 10x)",
        bm_us / ours_us
    );
    uniform_section(reg, ours_us);
    packed_section(reg, world, packed, cases);
}

/// What meshing a packed chunk costs, part by part, on the same cases and in rounds of
/// their own (the peers' sweeps through memory make the section above slower for every
/// mesher): building the masks of its non-air types (what the mesher does first for a
/// packed centre), meshes with the centre and the neighbours in each form, and the
/// alternative where the caller unpacks the chunk, meshes it and packs it again.
fn packed_section(reg: &BlockRegistry, world: &World, packed: &World, cases: &[Case]) {
    const ROUNDS: usize = 41;
    const METHODS: usize = 5;
    let mut ours = Mesher::new(reg);
    let mut out = ChunkMeshes::default();
    let mut buf = MaskBuffer::new();
    let not_air = |id: BlockId| reg.class(id).is_ok_and(|c| c != RenderClass::Air);
    let mut chunks: Vec<Chunk> = cases
        .iter()
        .map(|c| packed.chunk(c.pos).expect("generated").clone())
        .collect();
    let n = cases.len() as f64;
    let mut times: [Vec<f64>; METHODS] = Default::default();
    for round in 0..ROUNDS {
        for k in 0..METHODS {
            let method = (round + k) % METHODS;
            let t = Instant::now();
            for (c, chunk) in cases.iter().zip(&mut chunks) {
                let (centre, nb) = match method {
                    0 => {
                        black_box(&*chunk).build_masks(&mut buf, not_air);
                        black_box(&buf);
                        continue;
                    }
                    4 => {
                        chunk.unpack();
                        ours.mesh_into(black_box(&*chunk), packed.neighbourhood(c.pos), &mut out)
                            .expect("known blocks");
                        chunk.pack();
                        black_box(&out);
                        continue;
                    }
                    1 => (packed, packed),
                    2 => (world, packed),
                    _ => (world, world),
                };
                let chunk = centre.chunk(c.pos).expect("generated");
                ours.mesh_into(black_box(chunk), nb.neighbourhood(c.pos), &mut out)
                    .expect("known blocks");
                black_box(&out);
            }
            times[method].push(secs(t.elapsed()) / n);
        }
    }
    let [t_build, t_packed, t_nb, t_masks, t_unpack] = times.map(|t| median(t) * 1e6);
    let types: usize = chunks.iter().map(Chunk::palette_len).sum();
    println!(
        "\n## packed chunks (the same chunks, {:.1} types each; µs per chunk, median of {ROUNDS} interleaved rounds without the peers)",
        types as f64 / n
    );
    println!("build the masks of a packed chunk (non-air types, both layouts) {t_build:6.1}");
    println!("mesh, chunk and neighbours in mask form                    {t_masks:11.1}");
    println!("mesh, chunk in mask form, neighbours packed                {t_nb:11.1}");
    println!(
        "mesh, chunk and neighbours packed (masks built)            {t_packed:11.1}   {:+.1} over the mask form",
        t_packed - t_masks
    );
    println!("alternative: the caller unpacks, meshes, packs again       {t_unpack:11.1}");
}

/// Ours on uniform chunks: leaves (cutout, every inner face stays) alone and between six
/// stone neighbours, and stone alone (borders only), next to the terrain figure.
fn uniform_section(reg: &BlockRegistry, terrain_us: f64) {
    const ROUNDS: usize = 41;
    const REPS: usize = 200;
    let mut ours = Mesher::new(reg);
    let mut out = ChunkMeshes::default();
    let leaves = Chunk::uniform(LEAVES);
    let stone = Chunk::uniform(blocks::STONE);
    let cases: [(&str, &Chunk, [Option<&Chunk>; 6]); 3] = [
        ("uniform leaves, no neighbours", &leaves, [None; 6]),
        (
            "uniform leaves, six stone neighbours",
            &leaves,
            [Some(&stone); 6],
        ),
        ("uniform stone, no neighbours", &stone, [None; 6]),
    ];
    println!(
        "\n## uniform chunks (ours, µs per chunk, median of {ROUNDS} rounds of {REPS}; terrain above {terrain_us:.1})"
    );
    for (name, chunk, nb) in cases {
        ours.mesh_into(chunk, nb, &mut out).expect("known blocks");
        let faces: u32 = [&out.opaque, &out.cutout, &out.translucent]
            .into_iter()
            .flatten()
            .map(|q| q.area())
            .sum();
        let quads = out.len();
        let mut times = Vec::new();
        for _ in 0..ROUNDS {
            let t = Instant::now();
            for _ in 0..REPS {
                ours.mesh_into(black_box(chunk), black_box(nb), &mut out)
                    .expect("known blocks");
                black_box(&out);
            }
            times.push(secs(t.elapsed()) / REPS as f64);
        }
        println!(
            "{:<54}{:9.2}   {quads} quads, {faces} unit faces",
            name,
            median(times) * 1e6
        );
    }
}

fn storage_and_terrain_section(reg: &BlockRegistry, generator: &TerrainGenerator) {
    // Terrain generation, serial, per chunk.
    let positions: Vec<ChunkPos> = (0..16)
        .flat_map(|x| (0..2).flat_map(move |y| (0..8).map(move |z| ChunkPos::new(x, y, z))))
        .collect();
    let mut per_chunk = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        for &p in &positions {
            black_box(generator.generate_chunk(black_box(p)));
        }
        per_chunk.push(secs(t.elapsed()) / positions.len() as f64);
    }
    println!("\n## terrain");
    println!(
        "generation, one thread: {:.0} µs per 32^3 chunk (median of 5 x {} chunks; target <= 500)",
        median(per_chunk) * 1e6,
        positions.len()
    );

    // A 2048-chunk world (32 x 2 x 32 chunks: 1024 x 64 x 1024 blocks), generated and meshed
    // in parallel.
    let registry = Arc::new(reg.clone());
    let threads = rayon::current_num_threads();
    let (mut t_gen, mut t_mesh, mut t_total) = (vec![], vec![], vec![]);
    let mut last = None;
    for _ in 0..3 {
        let t = Instant::now();
        let world = generator
            .generate_world(
                registry.clone(),
                ChunkPos::new(-16, 0, -16),
                ChunkPos::new(15, 1, 15),
            )
            .expect("valid world");
        let gen_s = secs(t.elapsed());
        let all: Vec<ChunkPos> = world.iter().map(|(p, _)| p).collect();
        let t2 = Instant::now();
        let meshes = mesh_chunks(&world, &all).expect("known blocks");
        t_mesh.push(secs(t2.elapsed()));
        t_gen.push(gen_s);
        t_total.push(secs(t.elapsed()));
        last = Some((world, meshes));
    }
    let (world, meshes) = last.expect("three runs");
    let quads: usize = meshes.iter().map(|(_, m)| m.len()).sum();
    let translucent: usize = meshes.iter().map(|(_, m)| m.translucent.len()).sum();
    println!(
        "2048-chunk world, {threads} threads: generate {:.0} ms + mesh {:.0} ms = {:.2} s (median of 3; target < 2 s); {} quads, {} translucent",
        median(t_gen) * 1e3,
        median(t_mesh) * 1e3,
        median(t_total),
        quads,
        translucent
    );
    // The same world meshed without ambient occlusion: what AO costs in quads (faces merge
    // only with faces of equal corner values).
    let mut plain = without_ao(reg);
    let mut plain_quads = 0;
    // The fewest quads any exact merging allows, with and without occlusion: per plane,
    // the minimum rectangle partition of its faces grouped by the affine function of their
    // corner values (tests/common/exact_merge.rs says why no other merge is exact but a
    // few small squares, counted here).
    let t = Instant::now();
    let (mut fewest, mut fewest_plain, mut squares, mut alone) = (0, 0, 0, 0);
    // Adds a mesh's fewest exact quads, exact non-affine squares and non-affine faces.
    let bound = |m: &ChunkMeshes, counts: [&mut usize; 3]| {
        let [fewest, squares, alone] = counts;
        for quads in [&m.opaque, &m.cutout, &m.translucent] {
            for plane in exact_merge::planes(quads).values() {
                *fewest += exact_merge::fewest_exact_quads(plane);
                *squares += exact_merge::exact_non_affine_squares(plane);
                *alone += exact_merge::non_affine_faces(plane);
            }
        }
    };
    for (p, chunk) in world.iter() {
        let m = plain
            .mesh(chunk, world.neighbourhood(p))
            .expect("known blocks");
        plain_quads += m.len();
        bound(&m, [&mut fewest_plain, &mut 0, &mut 0]);
    }
    for (_, m) in &meshes {
        bound(m, [&mut fewest, &mut squares, &mut alone]);
    }
    let bound_s = secs(t.elapsed());
    println!(
        "quads with AO / without on the 2048-chunk world: {quads} / {plain_quads} = {:.3} (target <= 1.5)",
        quads as f64 / plain_quads as f64
    );
    println!(
        "fewest exact quads (minimum partitions; {bound_s:.0} s): with AO {fewest} ({:.2}% below ours), without {fewest_plain}; with AO / ours without = {:.3}, / fewest without = {:.3}; faces with values not affine {alone}, exact merges that are not affine {squares}",
        100.0 * (quads - fewest) as f64 / quads as f64,
        fewest as f64 / plain_quads as f64,
        fewest as f64 / fewest_plain as f64
    );

    storage_section(&world);
}

fn storage_section(world: &World) {
    println!("\n## storage (the 2048-chunk world)");
    let mut uniform = 0;
    let mut sizes = [0usize; 20];
    let (mut ours, mut dense, mut packed) = (0usize, 0usize, 0usize);
    let chunks: Vec<&Chunk> = world.iter().map(|(_, c)| c).collect();
    for c in &chunks {
        ours += c.memory_bytes();
        let k = c.palette_len();
        sizes[k.min(19)] += 1;
        packed += c.packed_index_bytes();
        if c.as_uniform().is_some() {
            uniform += 1;
            dense += std::mem::size_of::<Chunk>();
        } else {
            dense += 32 * 32 * 32 * 2;
        }
    }
    let mixed: Vec<&&Chunk> = chunks.iter().filter(|c| c.as_uniform().is_none()).collect();
    println!(
        "{} chunks: {uniform} uniform (one id each), {} mixed; block types per mixed chunk: {}",
        chunks.len(),
        mixed.len(),
        sizes
            .iter()
            .enumerate()
            .filter(|(k, n)| *k > 1 && **n > 0)
            .map(|(k, n)| format!("{k}:{n}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let mib = |b: usize| b as f64 / (1 << 20) as f64;
    println!(
        "memory: bitmask palette (ours) {:.1} MiB, u16 per block {:.1} MiB, packed-index palette {:.1} MiB",
        mib(ours),
        mib(dense),
        mib(packed)
    );
    // The resident form: the same world, every chunk packed.
    let mut compact_world = world.clone();
    let t = Instant::now();
    compact_world.pack_all();
    let t_pack_all = secs(t.elapsed());
    let compact = compact_world.chunk_memory_bytes();
    println!(
        "memory, packed (ours, the resident form) {:.1} MiB = {:.2}x the packed-index palette (target <= 2); bitmask palette {:.2}x and u16 per block {:.2}x of it",
        mib(compact),
        compact as f64 / packed as f64,
        ours as f64 / compact as f64,
        dense as f64 / compact as f64
    );

    // Converting between the forms, on mixed chunks of the world (they leave the caches:
    // 256 chunks in mask form are 15 MiB).
    let originals: Vec<Chunk> = mixed.iter().take(256).map(|c| (**c).clone()).collect();
    let (mut t_pack, mut t_unpack) = (vec![], vec![]);
    for _ in 0..9 {
        let mut v = originals.clone();
        let t = Instant::now();
        for c in &mut v {
            black_box(&mut *c).pack();
        }
        t_pack.push(secs(t.elapsed()) / v.len() as f64);
        let t = Instant::now();
        for c in &mut v {
            black_box(&mut *c).unpack();
        }
        t_unpack.push(secs(t.elapsed()) / v.len() as f64);
        black_box(&v);
    }
    println!(
        "pack (masks -> packed) {:.1} µs, unpack (packed -> masks) {:.1} µs per mixed chunk (median of 9 x {}); pack_all of the world, {} threads: {:.0} ms",
        median(t_pack) * 1e6,
        median(t_unpack) * 1e6,
        originals.len(),
        rayon::current_num_threads(),
        t_pack_all * 1e3
    );

    // What a u16 store would pay on every remesh: building the per-type masks we keep.
    let sample: Vec<Vec<BlockId>> = mixed.iter().take(64).map(|c| c.to_dense()).collect();
    let mut t_masks = vec![];
    let mut t_get_dense = vec![];
    let mut t_get_ours = vec![];
    let mut t_get_packed = vec![];
    let packed_sample: Vec<Chunk> = mixed
        .iter()
        .take(sample.len())
        .map(|c| {
            let mut c = (**c).clone();
            c.pack();
            c
        })
        .collect();
    let lookups: Vec<(usize, usize, usize)> = (0..4096u64)
        .map(|i| {
            let h = i.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            (
                (h >> 10) as usize % 32,
                (h >> 20) as usize % 32,
                (h >> 30) as usize % 32,
            )
        })
        .collect();
    for _ in 0..9 {
        let t = Instant::now();
        for d in &sample {
            let mut masks: Vec<(BlockId, Box<[u32; 1024]>)> = Vec::new();
            for (i, id) in d.iter().enumerate() {
                let slot = match masks.iter().position(|(m, _)| m == id) {
                    Some(s) => s,
                    None => {
                        masks.push((*id, Box::new([0; 1024])));
                        masks.len() - 1
                    }
                };
                masks[slot].1[i / 32] |= 1 << (i % 32);
            }
            black_box(&masks);
        }
        t_masks.push(secs(t.elapsed()) / sample.len() as f64);

        let t = Instant::now();
        let mut acc = 0u32;
        for (d, _) in sample.iter().zip(&mixed) {
            for &(x, y, z) in &lookups {
                acc = acc.wrapping_add(u32::from(d[Chunk::dense_index(x, y, z)].0));
            }
        }
        black_box(acc);
        t_get_dense.push(secs(t.elapsed()) / (sample.len() * lookups.len()) as f64);

        let t = Instant::now();
        let mut acc = 0u32;
        for c in mixed.iter().take(sample.len()) {
            for &(x, y, z) in &lookups {
                acc = acc.wrapping_add(u32::from(c.get(x, y, z).map_or(0, |b| b.0)));
            }
        }
        black_box(acc);
        t_get_ours.push(secs(t.elapsed()) / (sample.len() * lookups.len()) as f64);

        let t = Instant::now();
        let mut acc = 0u32;
        for c in &packed_sample {
            for &(x, y, z) in &lookups {
                acc = acc.wrapping_add(u32::from(c.get(x, y, z).map_or(0, |b| b.0)));
            }
        }
        black_box(acc);
        t_get_packed.push(secs(t.elapsed()) / (sample.len() * lookups.len()) as f64);
    }
    println!(
        "building per-type masks from u16 per block: {:.1} µs per chunk (paid on every remesh by a u16 store)",
        median(t_masks) * 1e6
    );
    println!(
        "random get: u16 array {:.1} ns, bitmask palette {:.1} ns",
        median(t_get_dense) * 1e9,
        median(t_get_ours) * 1e9
    );
    println!("random get, packed: {:.1} ns", median(t_get_packed) * 1e9);
    let _ = blocks::AIR;
}
