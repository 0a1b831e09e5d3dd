//! The memory the streamer keeps for edits, counted by a counting allocator (this
//! test binary's global allocator): it stays within what `ChunkStreamer::edit_bytes`
//! counts ([`voxel_render::low_level::EDIT_BYTES`] per edited block,
//! [`voxel_render::low_level::EDITED_CHUNK_BYTES`] per edited chunk), the documented bound;
//! 10 000 edits far away took 135 MB as whole chunks before.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Arc;
use std::sync::atomic::{AtomicIsize, Ordering};

use voxel_core::{BlockRegistry, Chunk, ChunkPos, WorldPos, blocks};
use voxel_render::{ChunkStreamer, StreamConfig};

/// The system allocator, counting the bytes live.
struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);

#[allow(unsafe_code)] // a global allocator is unsafe by definition; it only counts
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_add(
            new_size as isize - layout.size() as isize,
            Ordering::Relaxed,
        );
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Air above y = 0, stone below: cheap to make.
struct Flat;

impl voxel_render::ChunkSource for Flat {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        Chunk::uniform(if pos.y < 0 {
            blocks::STONE
        } else {
            voxel_core::BlockId::AIR
        })
    }
}

#[test]
fn edits_kept_stay_within_the_documented_bound() {
    let config = StreamConfig {
        view_distance: 1,
        vertical_distance: 0,
        threads: 1,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(Arc::new(BlockRegistry::default()), Flat, config).unwrap();
    let before = LIVE.load(Ordering::Relaxed);
    // 10 000 chunks far away, one edit each.
    for i in 0..10_000 {
        let at = WorldPos::new(100_000 + (i % 100) * 32, 5, (i / 100) * 32);
        s.set_block(at, blocks::GLASS).unwrap();
    }
    let one_each = LIVE.load(Ordering::Relaxed) - before;
    // 4 chunks edited in every block: 131 072 edits.
    for c in 0..4 {
        for z in 0..32 {
            for y in 0..32 {
                for x in 0..32 {
                    s.set_block(WorldPos::new(-5_000 + c * 32 + x, y, z), blocks::WATER)
                        .unwrap();
                }
            }
        }
    }
    let all = LIVE.load(Ordering::Relaxed) - before;
    eprintln!(
        "edits: 10 000 chunks x 1 edit: {one_each} bytes live; + 4 chunks x 32768 edits: {all} bytes live; counted {} bytes",
        s.edit_bytes()
    );
    assert!(
        one_each as usize
            <= 10_000
                * (voxel_render::low_level::EDIT_BYTES
                    + voxel_render::low_level::EDITED_CHUNK_BYTES)
    );
    assert!(
        all as usize <= s.edit_bytes(),
        "{all} live, {} counted",
        s.edit_bytes()
    );
    assert_eq!(s.edits().count(), 10_000 + 4 * 32 * 32 * 32);
}
