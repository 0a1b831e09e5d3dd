//! The 26 chunks around a chunk, and which of them an edit of a block touches.

use super::Face;
use crate::{CHUNK_SIZE, Chunk};

/// The 26 chunks around a chunk, by offset (each component -1, 0 or 1, not all 0): its 6
/// face, 12 edge and 8 corner neighbours. `None` counts as air. Face neighbours decide which
/// faces a chunk shows; ambient occlusion at a chunk's edges and corners also reads the
/// blocks of the edge and corner neighbours that touch it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Neighbourhood<'a> {
    /// By `(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)`; the centre (13) stays `None`.
    chunks: [Option<&'a Chunk>; 27],
}

impl<'a> Neighbourhood<'a> {
    /// The 26 offsets, faces first (in [`Face`] order), then edges, then corners.
    pub const OFFSETS: [[i32; 3]; 26] = {
        let mut out = [[0; 3]; 26];
        let faces = [
            [1, 0, 0],
            [-1, 0, 0],
            [0, 1, 0],
            [0, -1, 0],
            [0, 0, 1],
            [0, 0, -1],
        ];
        let mut n = 0;
        while n < 6 {
            out[n] = faces[n];
            n += 1;
        }
        // Then the offsets with two non-zero components (edges), then three (corners).
        let mut nonzero = 2;
        while nonzero <= 3 {
            let mut i = 0;
            while i < 27 {
                let d = [i / 9 - 1, i / 3 % 3 - 1, i % 3 - 1];
                if (d[0] != 0) as i32 + (d[1] != 0) as i32 + (d[2] != 0) as i32 == nonzero {
                    out[n] = d;
                    n += 1;
                }
                i += 1;
            }
            nonzero += 1;
        }
        out
    };

    fn index(d: [i32; 3]) -> Option<usize> {
        let ok = d.iter().all(|v| (-1..=1).contains(v)) && d != [0; 3];
        ok.then(|| ((d[0] + 1) * 9 + (d[1] + 1) * 3 + (d[2] + 1)) as usize)
    }

    /// Each neighbour from `get(offset)`.
    pub fn from_fn(mut get: impl FnMut([i32; 3]) -> Option<&'a Chunk>) -> Self {
        let mut n = Self::default();
        for d in Self::OFFSETS {
            if let Some(i) = Self::index(d) {
                n.chunks[i] = get(d);
            }
        }
        n
    }

    /// Only the six face neighbours (in [`Face`] order); edges and corners count as air.
    pub fn faces(faces: [Option<&'a Chunk>; 6]) -> Self {
        Self::from_fn(|d| {
            Face::ALL
                .iter()
                .position(|f| f.normal() == d)
                .and_then(|i| faces[i])
        })
    }

    /// The neighbour at offset `d`; `None` for air, the centre, or an offset beyond one
    /// chunk.
    pub fn get(&self, d: [i32; 3]) -> Option<&'a Chunk> {
        Self::index(d).and_then(|i| self.chunks[i])
    }

    /// The face neighbour across `face`.
    pub fn face(&self, face: Face) -> Option<&'a Chunk> {
        self.get(face.normal())
    }
}

impl<'a> From<[Option<&'a Chunk>; 6]> for Neighbourhood<'a> {
    fn from(faces: [Option<&'a Chunk>; 6]) -> Self {
        Self::faces(faces)
    }
}

/// The neighbours (offsets of [`Neighbourhood::OFFSETS`]) whose meshes depend on the block
/// at local `local` of a chunk: a block on a chunk's face touches that face neighbour, on
/// an edge also the edge neighbour, on a corner also the corner neighbours (ambient
/// occlusion reads diagonal blocks).
pub fn touched_neighbours(local: [usize; 3]) -> impl Iterator<Item = [i32; 3]> {
    let last = CHUNK_SIZE - 1;
    Neighbourhood::OFFSETS.into_iter().filter(move |d| {
        (0..3).all(|a| match d[a] {
            1 => local[a] == last,
            -1 => local[a] == 0,
            _ => true,
        })
    })
}
