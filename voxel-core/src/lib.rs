//! Blocks, chunks and worlds of the voxel OIT renderer, and a deterministic noise terrain.
//!
//! [`vox`] imports MagicaVoxel models into a [`World`].
//!
//! Nothing here knows about the GPU: `voxel-mesh` and `voxel-render` build on these types.
//! Coordinates: `y` is up; a chunk is [`CHUNK_SIZE`]³ blocks; world block coordinates are `i32`.

#![warn(missing_docs)]

mod block;
mod chunk;
mod error;
mod light;
mod terrain;
pub mod vox;
mod world;

pub use block::{
    BlockDef, BlockId, BlockImage, BlockRegistry, FOG_BLOCKS, FaceGroup, FaceImages,
    MAX_ABSORPTION, MAX_IMAGE_SIZE, Pattern, RenderClass, WATER_ABSORPTION, blocks, fog_absorption,
};
pub use chunk::{
    CHUNK_AREA, CHUNK_SIZE, CHUNK_VOLUME, Chunk, ColumnMask, LayerMask, MaskBuffer, Occupancy,
    column_index, row_index,
};
pub use error::{Error, Result};
pub use light::{
    LIGHT_FALLOFF, Light, LightChunk, LightField, LightLayer, OddCells, SunCell, SunFilters,
    SunMarch, light_blocks,
};
pub use terrain::{
    MAX_LEVEL, Showcase, Site, SiteKind, TerrainBlocks, TerrainConfig, TerrainGenerator,
    TerrainRole, level_cell, level_origin, level_scale,
};
pub use vox::{PaletteOverride, VoxError, VoxFile, VoxPlacement};
pub use world::{
    ChunkPos, Face, MAX_RAY_DISTANCE, Neighbourhood, RayHit, World, WorldPos, touched_neighbours,
    unit_direction,
};
