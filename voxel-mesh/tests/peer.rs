//! Our face area against a peer: block-mesh's `visible_block_faces` (one quad per visible
//! face) on the same opaque-only voxels must cover exactly the area our greedy quads cover,
//! direction by direction, whatever the storage forms of the chunk and its neighbours.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use block_mesh::ndshape::{ConstShape, ConstShape3u32};
use block_mesh::{
    MergeVoxel, RIGHT_HANDED_Y_UP_CONFIG, UnitQuadBuffer, Voxel, VoxelVisibility,
    visible_block_faces,
};
use voxel_core::{
    BlockId, BlockRegistry, Chunk, ChunkPos, Face, RenderClass, TerrainConfig, TerrainGenerator,
};
use voxel_mesh::{Mesher, Neighbours};

#[derive(Clone, Copy, PartialEq, Eq)]
struct V(u16);

impl Voxel for V {
    fn get_visibility(&self) -> VoxelVisibility {
        if self.0 == 0 {
            VoxelVisibility::Empty
        } else {
            VoxelVisibility::Opaque
        }
    }
}

impl MergeVoxel for V {
    type MergeValue = u16;
    fn merge_value(&self) -> u16 {
        self.0
    }
}

type Padded = ConstShape3u32<34, 34, 34>;

/// Keeps opaque blocks, turns everything else into air.
fn opaque_only(c: &Chunk, reg: &BlockRegistry) -> Chunk {
    let mut out = c.clone();
    for (id, _) in c.palette() {
        if reg.class(id).unwrap() != RenderClass::Opaque {
            for x in 0..32 {
                for z in 0..32 {
                    for y in 0..32 {
                        if out.get(x, y, z).unwrap() == id {
                            out.set(x, y, z, BlockId::AIR).unwrap();
                        }
                    }
                }
            }
        }
    }
    out
}

/// block-mesh's unit-face count per direction, in our `Face` order.
fn peer_faces(c: &Chunk, nb: Neighbours<'_>) -> [usize; 6] {
    let mut voxels = vec![V(0); Padded::SIZE as usize];
    for px in 0..34i32 {
        for py in 0..34i32 {
            for pz in 0..34i32 {
                let p = [px - 1, py - 1, pz - 1];
                let outside: Vec<Face> = Face::ALL
                    .into_iter()
                    .filter(|f| {
                        let v = p[f.axis()];
                        if f.is_positive() { v == 32 } else { v == -1 }
                    })
                    .collect();
                let l = p.map(|v| v.rem_euclid(32) as usize);
                let id = match outside.as_slice() {
                    [] => c.get(l[0], l[1], l[2]).unwrap(),
                    [f] => {
                        nb[*f as usize].map_or(BlockId::AIR, |n| n.get(l[0], l[1], l[2]).unwrap())
                    }
                    _ => BlockId::AIR, // edges and corners of the padding are never read
                };
                voxels[Padded::linearize([px as u32, py as u32, pz as u32]) as usize] = V(id.0);
            }
        }
    }
    let mut buf = UnitQuadBuffer::new();
    visible_block_faces(
        &voxels,
        &Padded {},
        [0; 3],
        [33; 3],
        &RIGHT_HANDED_Y_UP_CONFIG.faces,
        &mut buf,
    );
    // RIGHT_HANDED_Y_UP_CONFIG's groups are -x, -y, -z, +x, +y, +z.
    let g = |i: usize| buf.groups[i].len();
    [g(3), g(0), g(4), g(1), g(5), g(2)]
}

/// Our unit-face count per direction, the same with the chunk and its neighbours as they
/// are, all packed, and only the neighbours packed.
fn our_faces(mesher: &mut Mesher, c: &Chunk, nb: Neighbours<'_>) -> [usize; 6] {
    let packed = |c: &Chunk| {
        let mut c = c.clone();
        c.pack();
        c
    };
    let (pc, pnb) = (packed(c), nb.map(|n| n.map(packed)));
    let pnb: Neighbours<'_> = std::array::from_fn(|i| pnb[i].as_ref());
    let areas = [(c, nb), (&pc, pnb), (c, pnb)].map(|(c, nb)| {
        let m = mesher.mesh(c, nb).unwrap();
        assert!(m.cutout.is_empty() && m.translucent.is_empty());
        let mut area = [0; 6];
        for q in &m.opaque {
            area[q.face_index()] += q.area() as usize;
        }
        area
    });
    assert!(areas.iter().all(|a| *a == areas[0]), "{areas:?}");
    areas[0]
}

#[test]
fn terrain_chunks_match_block_mesh_face_area() {
    let reg = BlockRegistry::default();
    let generator = TerrainGenerator::new(TerrainConfig::default());
    let mut mesher = Mesher::new(&reg);
    let mut total = 0;
    for (x, z) in [(0, 0), (3, -2), (-5, 4), (7, 7)] {
        for y in 0..2 {
            let p = ChunkPos::new(x, y, z);
            let c = opaque_only(&generator.generate_chunk(p), &reg);
            let nbs: Vec<Chunk> = Face::ALL
                .iter()
                .map(|f| opaque_only(&generator.generate_chunk(p.neighbour(*f).unwrap()), &reg))
                .collect();
            let nb: Neighbours<'_> = std::array::from_fn(|i| Some(&nbs[i]));
            let ours = our_faces(&mut mesher, &c, nb);
            assert_eq!(ours, peer_faces(&c, nb), "chunk {p:?}");
            // And with no neighbours loaded (both count them as air).
            assert_eq!(
                our_faces(&mut mesher, &c, [None; 6]),
                peer_faces(&c, [None; 6])
            );
            total += ours.iter().sum::<usize>();
        }
    }
    assert!(total > 5000, "terrain produced only {total} faces");
}

#[test]
fn random_chunks_match_block_mesh_face_area() {
    let reg = BlockRegistry::default();
    let mut mesher = Mesher::new(&reg);
    let mut s = 0x1234_5678_9abc_def1u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let opaque: Vec<BlockId> = reg
        .iter()
        .filter(|(_, d)| d.class == RenderClass::Opaque)
        .map(|(id, _)| id)
        .collect();
    for density in [8u64, 50, 92] {
        let mut chunks = Vec::new();
        for _ in 0..7 {
            let mut c = Chunk::default();
            for x in 0..32 {
                for y in 0..32 {
                    for z in 0..32 {
                        let r = next();
                        if r % 100 < density {
                            c.set(x, y, z, opaque[(r >> 32) as usize % opaque.len()])
                                .unwrap();
                        }
                    }
                }
            }
            chunks.push(c);
        }
        let nb: Neighbours<'_> = std::array::from_fn(|i| Some(&chunks[i + 1]));
        let ours = our_faces(&mut mesher, &chunks[0], nb);
        assert_eq!(ours, peer_faces(&chunks[0], nb), "density {density}%");
        assert!(ours.iter().all(|&n| n > 0));
    }
}
