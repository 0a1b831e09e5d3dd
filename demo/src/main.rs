//! The demo and headless tools of the voxel OIT renderer.
//!
//! `demo` (no subcommand) generates the default world and prints its statistics;
//! `demo stats [--seed N] [--chunks N]` does the same for another world.

mod args;

use std::sync::Arc;
use std::time::Instant;

use args::Args;
use voxel_core::{BlockRegistry, ChunkPos, TerrainConfig, TerrainGenerator};

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let (cmd, rest) = match argv.first().map(String::as_str) {
        Some(c) if !c.starts_with("--") => (c, &argv[1..]),
        _ => ("stats", &argv[..]),
    };
    let result = match cmd {
        "stats" => stats(rest),
        other => Err(format!("unknown command {other:?}; commands: stats")),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

/// Generates and meshes a world, then prints what it holds and how long it took.
fn stats(argv: &[String]) -> Result<(), String> {
    let a = Args::parse(argv, &[], &[])?;
    a.reject_unknown(&["seed", "chunks"])?;
    let seed: u32 = a.parse_or("seed", 1)?;
    let n: i32 = a.parse_or("chunks", 32)?;
    if !(1..=256).contains(&n) {
        return Err(format!(
            "--chunks {n}: must be in 1..=256 (the world is N x 2 x N chunks)"
        ));
    }
    let registry = Arc::new(BlockRegistry::default());
    let generator = TerrainGenerator::new(TerrainConfig {
        seed,
        ..TerrainConfig::default()
    });
    let half = n / 2;
    let t = Instant::now();
    let mut world = generator
        .generate_world(
            registry.clone(),
            ChunkPos::new(-half, 0, -half),
            ChunkPos::new(n - half - 1, 1, n - half - 1),
        )
        .map_err(|e| e.to_string())?;
    let gen_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let meshes = voxel_mesh::mesh_dirty(&mut world).map_err(|e| e.to_string())?;
    let mesh_s = t.elapsed().as_secs_f64();

    let uniform = world
        .iter()
        .filter(|(_, c)| c.as_uniform().is_some())
        .count();
    let sum =
        |f: fn(&voxel_mesh::ChunkMeshes) -> usize| meshes.iter().map(|(_, m)| f(m)).sum::<usize>();
    let (opaque, cutout, translucent) = (
        sum(|m| m.opaque.len()),
        sum(|m| m.cutout.len()),
        sum(|m| m.translucent.len()),
    );
    let extent = i64::from(n) * 32;
    let sites = generator.sites_in(
        -i64::from(half) * 32,
        -i64::from(half) * 32,
        extent / 2,
        extent / 2,
    );
    println!("world seed {seed}: {n} x 2 x {n} chunks ({extent} x 64 x {extent} blocks)");
    println!(
        "generated in {:.0} ms, meshed in {:.0} ms on {} threads",
        gen_s * 1e3,
        mesh_s * 1e3,
        rayon::current_num_threads()
    );
    println!("chunks: {} ({uniform} uniform)", world.len());
    println!(
        "quads: {} opaque, {cutout} cutout (leaves), {translucent} translucent (water, glass); {:.1} MiB of quads",
        opaque,
        (opaque + cutout + translucent) as f64 * 8.0 / (1 << 20) as f64
    );
    println!(
        "glass structures: {} greenhouses, {} stained-glass pavilions",
        sites
            .iter()
            .filter(|s| s.kind == voxel_core::SiteKind::Greenhouse)
            .count(),
        sites
            .iter()
            .filter(|s| s.kind == voxel_core::SiteKind::Pavilion)
            .count()
    );
    Ok(())
}
