//! The crate's error type.

use crate::{BlockId, ChunkPos};

/// Everything that can go wrong in `voxel-core`. Each variant names the input at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A block id that the registry does not hold.
    #[error("unknown block id {0} (the registry holds ids 0..{1})")]
    UnknownBlock(BlockId, usize),
    /// A block name that the registry does not hold; `known` lists the names it does hold.
    #[error("unknown block name {name:?}; known blocks: {known}")]
    UnknownBlockName {
        /// The name asked for.
        name: String,
        /// Comma-separated list of the registered names.
        known: String,
    },
    /// A local chunk coordinate outside `0..CHUNK_SIZE`.
    #[error("local coordinate ({x}, {y}, {z}) is outside the chunk (0..32 on each axis)")]
    LocalOutOfRange {
        /// x as given
        x: usize,
        /// y as given
        y: usize,
        /// z as given
        z: usize,
    },
    /// A chunk position whose blocks would lie outside the `i32` world coordinate range.
    #[error("chunk {0:?} lies outside the i32 world (chunk coordinates must be in -2^26..2^26)")]
    ChunkOutOfRange(ChunkPos),
    /// A block definition that breaks a rule of the registry.
    #[error("invalid block definition {name:?}: {reason}")]
    InvalidBlockDef {
        /// The block's name.
        name: String,
        /// Which rule it breaks.
        reason: &'static str,
    },
    /// Two blocks with the same name.
    #[error("a block named {0:?} is already registered")]
    DuplicateBlockName(String),
    /// More blocks than a 16-bit id can name.
    #[error("the registry is full (65536 blocks)")]
    TooManyBlocks,
    /// A block image that cannot be a block texture (not square, not a power of two, too
    /// large, or the wrong number of bytes).
    #[error("invalid block image: {0}")]
    InvalidImage(String),
    /// A terrain generator whose blocks a registry does not hold (it names each role that
    /// is missing or maps to another block there).
    #[error("the terrain generator's blocks do not fit this registry: {0}")]
    TerrainBlocks(String),
    /// A ray cast with a NaN or infinite origin, a zero or non-finite direction, or a
    /// maximum distance that is negative, not a number, or beyond the limit.
    #[error("invalid ray: {0}")]
    InvalidRay(String),
    /// A light field used with a world over another block registry than the one it was
    /// built for.
    #[error("the light field was built for another block registry than this world's")]
    LightRegistry,
    /// A MagicaVoxel file that cannot be imported: which file, and what is wrong with it.
    #[error("{file}: {error}")]
    Vox {
        /// The file (or model) name.
        file: String,
        /// What is wrong.
        error: crate::vox::VoxError,
    },
}

/// `Result` with this crate's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;
