//! Exact quad order (`voxel_mesh::order`) against the centre-distance sort
//! (`voxel_mesh::sort::quads_back_to_front`). Prints figures; asserts nothing about time.
//!
//! `cargo bench -p voxel-mesh --bench sort` measures, for chunks of about 10, 100, 1 000
//! and 10 000 translucent quads meshed by the real mesher, per sort: the centre-distance
//! sort (copying the quads, then sorting, as the renderer does), the exact sort
//! (`QuadOrder::sort_into`, writing the ordered quads) and, per chunk, building the
//! structure (`QuadOrder::new`, once per mesh upload). Eyes: inside the chunk, beside it
//! (inside its span along one or two axes) and outside it (beyond it along all three axes,
//! near and 1e6 blocks away). Medians of interleaved rounds: every round times every
//! method on every (chunk, eye) pair, in rotating order.

#![allow(clippy::needless_range_loop)] // eye classes index three parallel arrays

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;
use std::time::Instant;

use common::{Rng, add_structure_of, checkerboard, mesh, random_boxes, structures};
use voxel_core::blocks::{BLUE_GLASS, GLASS, GREEN_GLASS, RED_GLASS};
use voxel_mesh::PackedQuad;
use voxel_mesh::order::{QuadOrder, SortStats};
use voxel_mesh::sort::quads_back_to_front;

const ROUNDS: usize = 15;
const CHUNKS: usize = 10;
const EYE_CLASSES: [&str; 3] = ["inside", "beside", "outside"];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Scene {
    quads: Vec<PackedQuad>,
    order: QuadOrder,
    /// Eyes per class (inside, beside, outside), chunk-local.
    eyes: [Vec<[f64; 3]>; 3],
}

fn eyes(rng: &mut Rng, per_class: usize) -> [Vec<[f64; 3]>; 3] {
    let mut c = |lo: f64, hi: f64| lo + (hi - lo) * rng.below(1 << 20) as f64 / (1 << 20) as f64;
    let inside: Vec<[f64; 3]> = (0..per_class)
        .map(|_| [0; 3].map(|_| c(0.0, 32.0)))
        .collect();
    let beside = (0..per_class)
        .map(|i| {
            let mut e = [0; 3].map(|_| c(0.0, 32.0));
            let out = if i % 2 == 0 { 1 } else { 2 };
            for k in 0..out {
                let axis = (i + k) % 3;
                e[axis] = if c(0.0, 1.0) < 0.5 {
                    c(-200.0, -1.0)
                } else {
                    c(33.0, 232.0)
                };
            }
            e
        })
        .collect();
    let outside = (0..per_class)
        .map(|i| {
            let far = if i % 2 == 0 { 1.0e6 } else { 100.0 };
            [0; 3].map(|_| {
                if c(0.0, 1.0) < 0.5 {
                    -c(1.0, far)
                } else {
                    32.0 + c(1.0, far)
                }
            })
        })
        .collect();
    [inside, beside, outside]
}

fn scene(rng: &mut Rng, quads: Vec<PackedQuad>) -> Scene {
    Scene {
        order: QuadOrder::new(&quads),
        eyes: eyes(rng, 4),
        quads,
    }
}

struct Row {
    name: String,
    scenes: Vec<Scene>,
}

fn rows() -> Vec<Row> {
    let mut rng = Rng::new(2024);
    let mut rows = Vec::new();
    let mut row = |name: &str, rng: &mut Rng, make: &mut dyn FnMut(&mut Rng) -> Vec<PackedQuad>| {
        let scenes = (0..CHUNKS)
            .map(|_| {
                let q = make(rng);
                scene(rng, q)
            })
            .collect();
        rows.push(Row {
            name: name.into(),
            scenes,
        });
    };
    row("~10 structures", &mut rng, &mut |r| {
        // Two pillars or slabs.
        let mut c = voxel_core::Chunk::uniform(voxel_core::blocks::AIR);
        for i in 0..2 {
            let o = [
                r.range(0, 12) + 16 * i,
                r.range(0, 20),
                r.range(0, 12) + 16 * i,
            ]
            .map(|v| v as usize);
            let hi = o.map(|v| (v + r.range(2, 8) as usize).min(31));
            let kind = 2 + r.below(2);
            add_structure_of(r, &mut c, o, hi, kind);
        }
        mesh(&c)
    });
    row("~100 structures", &mut rng, &mut |r| structures(r, 100).1);
    row("~100 random boxes", &mut rng, &mut |r| {
        mesh(&random_boxes(r, 20, 8, 32))
    });
    row("~1000 structures", &mut rng, &mut |r| structures(r, 1000).1);
    row("~1000 checkerboard", &mut rng, &mut |r| {
        let o = [0; 3].map(|_| r.range(0, 20) as usize);
        mesh(&checkerboard(o, [6, 6, 5], GLASS, RED_GLASS))
    });
    row("~1000 random boxes", &mut rng, &mut |r| {
        mesh(&random_boxes(r, 200, 4, 32))
    });
    row("~10000 checkerboard", &mut rng, &mut |r| {
        let o = [0; 3].map(|_| r.range(0, 20) as usize);
        let (a, b) = if r.chance(0.5) {
            (GREEN_GLASS, BLUE_GLASS)
        } else {
            (GLASS, RED_GLASS)
        };
        mesh(&checkerboard(o, [12, 12, 12], a, b))
    });
    row("~8000 random boxes", &mut rng, &mut |r| {
        mesh(&random_boxes(r, 1500, 2, 32))
    });
    rows
}

fn main() {
    let rows = rows();
    println!("# voxel-mesh sort benchmark (cargo bench -p voxel-mesh --bench sort)");
    println!(
        "µs per sort of one chunk's translucent quads (build: per chunk); medians of {ROUNDS} \
         interleaved rounds; each row: {CHUNKS} chunks x 12 eyes, 4 per class: inside the chunk, \
         beside it (inside its span along 1 or 2 axes), outside it (beyond it along all 3 \
         axes, 100 or 1e6 blocks away)."
    );
    println!(
        "centre = copy + voxel_mesh::sort::quads_back_to_front; exact = QuadOrder::sort_into; \
         build = QuadOrder::new. stuck % = quads in pairwise leaves; triggers = trigger planes \
         per chunk (3 axes); cycles / eye-dep. = groups met over the {} sorts of the row.",
        CHUNKS * 12
    );
    println!(
        "structures: glass houses, water tanks, pillars, slabs and stairs 3-8 blocks a side, \
         apart from each other; random boxes: overlapping boxes of 6 translucent types with \
         some air and stone (a dense tangle); checkerboards: two glasses alternating, no \
         merging possible."
    );
    println!(
        "\n| chunks | quads | stuck % | triggers | centre | exact | exact/centre | exact in / beside / out | build | cycles | eye-dep. |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|");
    for row in &rows {
        report(row);
    }
}

fn report(row: &Row) {
    let scenes = &row.scenes;
    let n = scenes.len() as f64;
    let quads = scenes.iter().map(|s| s.quads.len()).sum::<usize>() as f64 / n;
    let stuck = scenes.iter().map(|s| s.order.stuck().1).sum::<usize>() as f64 / n;
    let triggers = scenes
        .iter()
        .map(|s| {
            s.order
                .trigger_planes()
                .iter()
                .map(|p| p.len())
                .sum::<usize>()
        })
        .sum::<usize>() as f64
        / n;
    // Stats of one pass (deterministic).
    let mut stats = SortStats::default();
    let mut sorts = 0;
    let mut out = Vec::new();
    for s in scenes {
        for e in s.eyes.iter().flatten() {
            let st = s.order.sort_into(*e, &mut out);
            stats.cycles += st.cycles;
            stats.eye_dependent += st.eye_dependent;
            sorts += 1;
        }
    }
    let mut centre: [Vec<f64>; 3] = Default::default();
    let mut exact: [Vec<f64>; 3] = Default::default();
    let mut build = Vec::new();
    let mut buf: Vec<PackedQuad> = Vec::new();
    for round in 0..ROUNDS {
        for step in 0..3 {
            match (round + step) % 3 {
                0 => {
                    for class in 0..3 {
                        let t = Instant::now();
                        let mut calls = 0;
                        for s in scenes {
                            for e in &s.eyes[class] {
                                buf.clear();
                                buf.extend_from_slice(&s.quads);
                                let eye = e.map(|v| v as f32);
                                quads_back_to_front(black_box(&mut buf), black_box(eye));
                                black_box(&buf);
                                calls += 1;
                            }
                        }
                        centre[class].push(t.elapsed().as_secs_f64() / f64::from(calls));
                    }
                }
                1 => {
                    for class in 0..3 {
                        let t = Instant::now();
                        let mut calls = 0;
                        for s in scenes {
                            for e in &s.eyes[class] {
                                black_box(s.order.sort_into(black_box(*e), &mut out));
                                black_box(&out);
                                calls += 1;
                            }
                        }
                        exact[class].push(t.elapsed().as_secs_f64() / f64::from(calls));
                    }
                }
                _ => {
                    let t = Instant::now();
                    for s in scenes {
                        black_box(QuadOrder::new(black_box(&s.quads)));
                    }
                    build.push(t.elapsed().as_secs_f64() / n);
                }
            }
        }
    }
    let us = |v: &Vec<f64>| median(v.clone()) * 1e6;
    let c: Vec<f64> = centre.iter().map(us).collect();
    let x: Vec<f64> = exact.iter().map(us).collect();
    let (c_all, x_all) = (c.iter().sum::<f64>() / 3.0, x.iter().sum::<f64>() / 3.0);
    println!(
        "| {} | {:.0} | {:.0} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} / {:.2} / {:.2} | {:.1} | {} | {} |",
        row.name,
        quads,
        100.0 * stuck / quads.max(1.0),
        triggers,
        c_all,
        x_all,
        x_all / c_all,
        x[0],
        x[1],
        x[2],
        us(&build),
        stats.cycles,
        stats.eye_dependent,
    );
    let _ = (sorts, EYE_CLASSES);
}
