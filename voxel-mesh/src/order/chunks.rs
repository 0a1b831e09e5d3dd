//! Exact back-to-front order of a grid of chunks (Theorem 3 of `docs/quad-order.md`).

use std::cmp::Reverse;

use voxel_core::{CHUNK_SIZE, ChunkPos};

/// The draw-order key of a chunk for an eye in world block coordinates: sort by it,
/// largest (farthest) first, ties in any order. It is the squared distance, in chunks,
/// between the chunk and the chunk that holds the eye, so it is computed in integers and
/// changes only when the eye crosses a chunk border; exact for a grid of equal cubes (see
/// "Order across chunks" in `docs/quad-order.md`). Never panics: a NaN coordinate counts
/// as 0, far and infinite eyes are clamped beyond every `i32` chunk.
pub fn chunk_order_key(pos: ChunkPos, eye: [f64; 3]) -> u128 {
    let s = CHUNK_SIZE as f64;
    let p = [pos.x, pos.y, pos.z];
    (0..3)
        .map(|k| {
            let e = ((eye[k] / s).floor() as i64)
                .clamp(i64::from(i32::MIN) - 1, i64::from(i32::MAX) + 1);
            let d = u128::from((i64::from(p[k]) - e).unsigned_abs());
            d * d
        })
        .sum()
}

/// Sorts chunks back to front by [`chunk_order_key`] (farthest first), ties by position.
pub fn chunks_back_to_front(chunks: &mut [ChunkPos], eye: [f64; 3]) {
    chunks.sort_by_cached_key(|&p| (Reverse(chunk_order_key(p, eye)), p));
}
