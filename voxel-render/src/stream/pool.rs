//! Where the streamer's jobs run: its own rayon pool (native), or a queue the thread that
//! calls [`ChunkStreamer::update`] works through within [`StreamConfig::local_budget`]
//! (wasm32, where a page has one thread, and [`ChunkStreamer::new_local`]).
//!
//! [`ChunkStreamer::update`]: super::ChunkStreamer::update
//! [`ChunkStreamer::new_local`]: super::ChunkStreamer::new_local
//! [`StreamConfig::local_budget`]: super::StreamConfig::local_budget

use crate::Result;
use std::collections::VecDeque;

/// A generation or meshing job.
pub(super) type Job = Box<dyn FnOnce() + Send + 'static>;

pub(super) enum Pool {
    /// Worker threads (not on wasm32).
    #[cfg(not(target_arch = "wasm32"))]
    Threads(rayon::ThreadPool),
    /// Jobs run by [`Pool::run_local`], oldest first, on the updating thread.
    Local(VecDeque<Job>),
}

impl Pool {
    /// Worker threads where the target has them (`threads`: 0 picks one fewer than the
    /// cores, at least 1), else a local queue.
    pub(super) fn new(threads: usize) -> Result<Self> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            let threads = match threads {
                0 => std::thread::available_parallelism()
                    .map_or(1, |n| n.get().saturating_sub(1).max(1)),
                n => n,
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("chunk-streamer-{i}"))
                .build()
                .map_err(|e| {
                    crate::Error::InvalidSetting(format!("the streamer's {threads} threads: {e}"))
                })?;
            Ok(Self::Threads(pool))
        }
        #[cfg(target_arch = "wasm32")]
        {
            let _ = threads;
            Ok(Self::local())
        }
    }

    pub(super) fn local() -> Self {
        Self::Local(VecDeque::new())
    }

    pub(super) fn is_local(&self) -> bool {
        matches!(self, Self::Local(_))
    }

    pub(super) fn spawn(&mut self, job: impl FnOnce() + Send + 'static) {
        match self {
            #[cfg(not(target_arch = "wasm32"))]
            Self::Threads(pool) => pool.spawn(job),
            Self::Local(queue) => queue.push_back(Box::new(job)),
        }
    }

    /// The oldest job of a local queue (none for worker threads).
    pub(super) fn pop(&mut self) -> Option<Job> {
        match self {
            Self::Local(queue) => queue.pop_front(),
            #[cfg(not(target_arch = "wasm32"))]
            Self::Threads(_) => None,
        }
    }
}
