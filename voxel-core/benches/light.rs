//! Light fields on the default generated terrain: lighting every chunk from scratch, and
//! the incremental update when a torch (or a stone block) is placed on the ground and
//! removed again. Prints figures; asserts nothing about time.
//!
//! `cargo bench -p voxel-core --bench light` (`LIGHT_RADIUS`, `LIGHT_EDITS` to change the
//! world's radius in chunks, default 4, and the number of edits, default 1000).

use std::sync::Arc;
use std::time::{Duration, Instant};

use voxel_core::{
    BlockId, BlockRegistry, ChunkPos, LightField, RenderClass, TerrainConfig, TerrainGenerator,
    World, WorldPos, blocks, light_blocks,
};

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn percentile(times: &mut [Duration], p: f64) -> f64 {
    times.sort_unstable();
    let i = ((times.len() as f64 - 1.0) * p).round() as usize;
    times[i].as_secs_f64() * 1e6
}

fn summary(name: &str, times: &mut [Duration]) {
    let mean = times.iter().sum::<Duration>().as_secs_f64() * 1e6 / times.len() as f64;
    println!(
        "| {name} | {} | {:.1} | {:.1} | {:.1} | {:.1} |",
        times.len(),
        percentile(times, 0.5),
        percentile(times, 0.99),
        percentile(times, 1.0),
        mean
    );
}

/// The first open block above the ground in column `(x, z)`, if any in the world.
fn ground(world: &World, x: i32, z: i32) -> Option<WorldPos> {
    let registry = world.registry().clone();
    (0..64).rev().find_map(|y| {
        let below = world.get_block(WorldPos::new(x, y - 1, z));
        let here = world.get_block(WorldPos::new(x, y, z));
        (here == BlockId::AIR && registry.class(below).ok() == Some(RenderClass::Opaque))
            .then_some(WorldPos::new(x, y, z))
    })
}

fn main() {
    let radius = env("LIGHT_RADIUS", 4) as i32;
    let edits = env("LIGHT_EDITS", 1000);
    let terrain = TerrainGenerator::new(TerrainConfig::default());
    let registry = Arc::new(BlockRegistry::with_lights());
    let mut world = terrain
        .generate_world(
            registry,
            ChunkPos::new(-radius, 0, -radius),
            ChunkPos::new(radius, 1, radius),
        )
        .expect("the default terrain fits the registry");
    world.pack_all();
    let chunks = world.len();
    println!(
        "default terrain, {chunks} chunks ({0}x2x{0}), packed; one thread",
        2 * radius + 1
    );

    // Full lighting: best of three.
    let mut best = Duration::MAX;
    let mut field = LightField::new(&world);
    for _ in 0..3 {
        let t = Instant::now();
        field = LightField::new(&world);
        best = best.min(t.elapsed());
    }
    let ms = best.as_secs_f64() * 1e3;
    let dense: usize = world
        .iter()
        .map(|(p, _)| field.chunk(p).map_or(0, |c| c.dense_layers()))
        .sum();
    println!(
        "full light: {ms:.1} ms, {:.3} ms a chunk, {:.1} chunks a ms",
        ms / chunks as f64,
        chunks as f64 / ms
    );
    println!(
        "light memory: {:.2} MiB ({:.1} KiB a chunk; {dense} of {} layers dense, 6 KiB each); blocks packed: {:.2} MiB",
        field.memory_bytes() as f64 / (1 << 20) as f64,
        field.memory_bytes() as f64 / 1024.0 / chunks as f64,
        chunks * 32,
        world.chunk_memory_bytes() as f64 / (1 << 20) as f64,
    );

    // Edits at random ground positions inside the world, away from its outer edge.
    let span = (2 * radius + 1) * 32 - 32;
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let mut spots = Vec::new();
    while spots.len() < edits {
        let x = -radius * 32 + 16 + (next() % span as u64) as i32;
        let z = -radius * 32 + 16 + (next() % span as u64) as i32;
        if let Some(p) = ground(&world, x, z) {
            spots.push(p);
        }
    }
    println!();
    println!("| edit | n | p50 µs | p99 µs | max µs | mean µs |");
    println!("|---|---|---|---|---|---|");
    for (name, id) in [("torch", light_blocks::TORCH), ("stone", blocks::STONE)] {
        let (mut place, mut remove) = (Vec::new(), Vec::new());
        for &p in &spots {
            let t = Instant::now();
            world.set_block_lit(&mut field, p, id).expect("valid edit");
            place.push(t.elapsed());
            let t = Instant::now();
            world
                .set_block_lit(&mut field, p, BlockId::AIR)
                .expect("valid edit");
            remove.push(t.elapsed());
        }
        let mut both: Vec<_> = place.iter().chain(&remove).copied().collect();
        summary(&format!("{name} placed"), &mut place);
        summary(&format!("{name} removed"), &mut remove);
        summary(&format!("{name} placed or removed"), &mut both);
    }

    // Streaming: a chunk unlit and unloaded, then loaded and lit again (its neighbours
    // lit), a chunk at a time over every chunk of the world.
    let positions: Vec<ChunkPos> = {
        let mut p: Vec<ChunkPos> = world.iter().map(|(p, _)| p).collect();
        p.sort_unstable();
        p
    };
    let (mut unlit, mut lit) = (Vec::new(), Vec::new());
    for p in positions {
        let t = Instant::now();
        field.remove_chunk(&world, p).expect("same registry");
        unlit.push(t.elapsed());
        let chunk = world.remove_chunk(p).expect("loaded");
        world.insert_chunk(p, chunk).expect("valid chunk");
        let t = Instant::now();
        field.add_chunk(&world, p).expect("same registry");
        lit.push(t.elapsed());
    }
    summary("chunk unlit (remove_chunk)", &mut unlit);
    summary("chunk lit (add_chunk)", &mut lit);
    assert_eq!(field.len(), chunks, "every chunk lit again");
}
