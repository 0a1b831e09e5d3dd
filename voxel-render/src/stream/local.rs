//! The index of a block within its chunk, as the edit lists key it.

use voxel_core::CHUNK_SIZE;

/// The index of a block within its chunk (x fastest), as the edit lists key it.
pub(super) fn local_index([x, y, z]: [usize; 3]) -> u16 {
    (x + CHUNK_SIZE * (y + CHUNK_SIZE * z)) as u16
}

/// The position in its chunk of the block at index `index` (the inverse of [`local_index`]).
pub(super) fn local_of(index: u16) -> [usize; 3] {
    let i = usize::from(index);
    [
        i % CHUNK_SIZE,
        (i / CHUNK_SIZE) % CHUNK_SIZE,
        i / (CHUNK_SIZE * CHUNK_SIZE),
    ]
}
