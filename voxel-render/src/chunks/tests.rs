use glam::{DVec3, Vec3};
use voxel_core::{CHUNK_SIZE, ChunkPos, Face};
use voxel_mesh::PackedQuad;

use super::cull::{Place, REGION_CHUNKS, Regions};
use super::gpu_chunk::{distinct_planes, layers_bounds};
use super::*;
use crate::Camera;
use crate::arena::Alloc;
use crate::arena::tests::rng;
use crate::layers::{self, Plane};

#[test]
fn frustum_keeps_chunks_in_view_and_drops_the_rest() {
    let cam = Camera::look_at(
        DVec3::new(16.0, 16.0, 100.0),
        DVec3::new(16.0, 16.0, 0.0),
        60.0,
        0.1,
        500.0,
    )
    .unwrap();
    let f = Frustum::new(cam.view_proj(1.0), cam.eye);
    assert!(
        f.chunk_distance(ChunkPos::new(0, 0, 0)).is_some(),
        "straight ahead"
    );
    assert!(
        f.chunk_distance(ChunkPos::new(0, 0, 5)).is_none(),
        "behind the eye"
    );
    assert!(
        f.chunk_distance(ChunkPos::new(40, 0, 0)).is_none(),
        "far to the side"
    );
    assert!(
        f.chunk_distance(ChunkPos::new(0, 0, -20)).is_none(),
        "past the far plane"
    );
    assert!(
        f.chunk_distance(ChunkPos::new(0, 0, 3)).is_some(),
        "the eye's own chunk"
    );
}

fn mesh(page: u32, offset: u32) -> Option<Alloc> {
    Some(Alloc {
        page,
        offset,
        quads: 1,
    })
}

/// `n` planes marked with `mark` (their optical depths).
fn marked_planes(n: u64, mark: u32) -> Vec<Plane> {
    (0..n)
        .map(|k| Plane {
            face: Face::PosY,
            lo: Vec3::ZERO,
            hi: Vec3::ONE,
            tau: (mark * 4 + k as u32) as f32,
        })
        .collect()
}

/// Every place points at its slot's member, every region is non-empty and found by its
/// key, the members are exactly the chunks held, each with its planes, and at most half
/// of a region's planes are garbage.
fn check_bookkeeping(regions: &Regions, held: &[Option<(ChunkPos, Vec<Plane>)>]) {
    let mut members = 0;
    for (i, r) in regions.regions.iter().enumerate() {
        assert!(!r.members.is_empty(), "empty region {:?} kept", r.key);
        let live: usize = (0..r.members.len()).map(|j| r.planes_of(j).len()).sum();
        assert_eq!(live + r.garbage, r.planes.len());
        assert!(
            r.garbage * 2 <= r.planes.len(),
            "{} of {}",
            r.garbage,
            r.planes.len()
        );
        assert_eq!(regions.by_key.get(&r.key), Some(&(i as u32)));
        for (j, m) in r.members.iter().enumerate() {
            assert_eq!(Regions::key(m.pos), r.key);
            let place = Place {
                region: i as u32,
                index: j as u32,
            };
            assert_eq!(regions.places[m.slot as usize], Some(place));
            let (pos, planes) = held[m.slot as usize].as_ref().unwrap();
            assert_eq!(*pos, m.pos);
            assert_eq!(r.planes_of(j), &planes[..]);
            members += 1;
        }
    }
    assert_eq!(regions.by_key.len(), regions.regions.len());
    assert_eq!(members, held.iter().flatten().count());
}

#[test]
fn regions_follow_uploads_and_removals() {
    let mut next = rng(0x0dd_ba11_5eed);
    let mut regions = Regions::default();
    let mut held: Vec<Option<(ChunkPos, Vec<Plane>)>> = vec![None; 600];
    for step in 0..6000 {
        let slot = (next() % held.len() as u64) as u32;
        if next().is_multiple_of(3) {
            regions.remove(slot);
            held[slot as usize] = None;
        } else {
            let c = |n: u64| (n % 40) as i32 - 20;
            let same = held[slot as usize]
                .as_ref()
                .filter(|_| next().is_multiple_of(2))
                .map(|h| h.0);
            let pos = same.unwrap_or_else(|| ChunkPos::new(c(next()), c(next()) / 4, c(next())));
            // A chunk that stays may keep its planes (its meshes moved).
            let planes = if same.is_some() && next().is_multiple_of(2) {
                None
            } else {
                Some(marked_planes(next() % 4, step))
            };
            regions.set(
                slot,
                pos,
                0,
                [mesh(0, step), None, mesh(1, step)],
                planes.as_deref(),
            );
            let kept = held[slot as usize].take().map(|h| h.1);
            held[slot as usize] = Some((pos, planes.or(kept).unwrap_or_default()));
        }
        if step % 500 == 0 {
            check_bookkeeping(&regions, &held);
        }
    }
    check_bookkeeping(&regions, &held);
    for slot in 0..held.len() as u32 {
        regions.remove(slot);
    }
    check_bookkeeping(&regions, &[]);
    assert!(regions.regions.is_empty());
}

/// The box and distinct planes of a mesh derived from its layers are what its quads
/// give directly.
#[test]
fn bounds_and_planes_from_layers_are_those_of_the_quads() {
    let mut next = rng(0x1a7e_5eed);
    let blocks = [
        voxel_core::blocks::GLASS,
        voxel_core::blocks::WATER,
        voxel_core::blocks::ICE,
        voxel_core::BlockId(999),
    ];
    let opacity = [0.5f32; 8];
    for round in 0..200 {
        let quads: Vec<PackedQuad> = (0..round % 40)
            .map(|_| {
                let mut n = |m: u64| (next() % m) as usize;
                let (w, h) = (1 + n(8), 1 + n(8));
                let at = [n(24), n(24), n(24)];
                PackedQuad::new(at, w, h, Face::ALL[n(6)], blocks[n(4)])
            })
            .collect();
        let layers = layers::planes(&quads, &opacity);
        let mut want: Vec<(Face, u8)> = quads
            .iter()
            .filter_map(|q| q.unpack())
            .map(|q| (q.face, q.bounds().0[q.face.axis()] as u8))
            .collect();
        want.sort_unstable_by_key(|&(f, c)| (f as u8, c));
        want.dedup();
        assert_eq!(distinct_planes(&layers), want);
        let bounds = quads
            .iter()
            .filter_map(|q| q.unpack())
            .map(|q| q.bounds())
            .reduce(|(lo, hi), (a, b)| {
                (
                    [0, 1, 2].map(|k| lo[k].min(a[k])),
                    [0, 1, 2].map(|k| hi[k].max(b[k])),
                )
            });
        assert_eq!(layers_bounds(&layers), bounds);
    }
}

#[test]
fn region_culling_finds_what_testing_every_chunk_finds() {
    let mut next = rng(0x5eed_cafe_f00d);
    let mut unit = move || (next() % 1_000_000) as f64 / 1e6;
    let mut covers = [0usize; 3];
    for scene in 0..24 {
        // Around the origin, and far out (where f32 corners round to 1/8 block and more).
        let centre = match scene % 3 {
            0 => [0, 0, 0],
            1 => [31_250, -40, -31_250],
            _ => [60_000_000, 100, -60_000_000],
        };
        let mut regions = Regions::default();
        let mut held = Vec::new();
        for slot in 0..2500u32 {
            let c = |u: f64, r: f64| (u * 2.0 * r - r).floor() as i32;
            let pos = ChunkPos::new(
                centre[0] + c(unit(), 40.0),
                centre[1] + c(unit(), 6.0),
                centre[2] + c(unit(), 40.0),
            );
            if regions.by_key.contains_key(&Regions::key(pos)) && unit() < 0.05 {
                continue;
            }
            let planes = marked_planes(u64::from(slot % 3), slot);
            regions.set(slot, pos, 0, [mesh(0, slot), None, None], Some(&planes));
            held.push((slot, pos, planes));
        }
        for _ in 0..40 {
            let s = CHUNK_SIZE as f64;
            let eye = DVec3::new(
                (f64::from(centre[0]) + unit() * 60.0 - 30.0) * s,
                (f64::from(centre[1]) + unit() * 8.0 - 4.0) * s,
                (f64::from(centre[2]) + unit() * 60.0 - 30.0) * s,
            );
            let far = [50.0, 500.0, 5000.0, crate::camera::MAX_FAR][(unit() * 4.0) as usize];
            let cam = Camera::from_yaw_pitch(
                eye,
                unit() * 7.0,
                unit() * 3.0 - 1.5,
                10.0 + unit() * 150.0,
                crate::camera::MIN_NEAR + unit(),
                far,
            )
            .unwrap();
            let f = Frustum::new(cam.view_proj(0.5 + unit() * 2.0), cam.eye);
            let size = REGION_CHUNKS.map(|c| i64::from(c) * CHUNK_SIZE as i64);
            for r in &regions.regions {
                covers[f.region_cover(r.origin, size) as usize] += 1;
            }
            let mut found = Vec::new();
            regions.cull(&f, |m, d, planes| {
                found.push((m.slot, m.pos, d.to_bits(), planes.to_vec()));
            });
            found.sort_unstable_by_key(|e| e.0);
            let every: Vec<_> = held
                .iter()
                .filter_map(|(slot, pos, planes)| {
                    Some((
                        *slot,
                        *pos,
                        f.chunk_distance(*pos)?.to_bits(),
                        planes.clone(),
                    ))
                })
                .collect();
            assert_eq!(found, every, "eye {eye:?}");
        }
    }
    // Every kind of region was met.
    assert!(covers.iter().all(|&n| n > 100), "{covers:?}");
}
