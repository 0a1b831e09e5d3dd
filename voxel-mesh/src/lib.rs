//! Chunk mesher of the voxel OIT renderer: splits every chunk's visible faces into opaque,
//! cutout and translucent meshes of 8-byte packed quads, culling against neighbour chunks.
//!
//! - [`Mesher`]: one chunk with its neighbours → [`ChunkMeshes`] (binary greedy meshing),
//!   with per-vertex ambient occlusion ([`ao`]); [`Mesher::mesh_lit`] adds smooth
//!   per-vertex light from a [`voxel_core::LightField`] ([`light`]).
//! - [`PackedQuad`]: the 8-byte quad format the renderer expands in its vertex shader.
//! - [`mesh_dirty`]: remesh a world's dirty chunks in parallel with rayon
//!   ([`mesh_dirty_lit`] with light, and the chunks whose light changed).
//! - [`order`]: exact back-to-front order of a chunk's translucent quads, re-sorted only
//!   when the eye crosses a trigger plane; exact chunk order.
//! - [`sort`]: back-to-front ordering of translucent quads and chunks for a camera.

#![warn(missing_docs)]

pub mod ao;
mod bits;
pub mod levels;
pub mod light;
mod mesher;
pub mod order;
mod quad;
pub mod sort;
mod world;

pub use ao::AO_NONE;
pub use bits::greedy_rects;
pub use light::{LightStreams, PackedLight, QuadLight};
pub use mesher::{ChunkMeshes, MeshOptions, Mesher, Neighbours};
pub use quad::{FLAG_INTERFACE, PackedQuad, Quad, UV_AXES};
pub use voxel_core::Neighbourhood;
pub use world::{mesh_chunks, mesh_chunks_lit, mesh_dirty, mesh_dirty_lit, mesh_world};

use voxel_core::BlockId;

/// What can go wrong while meshing.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A chunk (or a neighbour) holds a block id that the registry does not know.
    #[error("a chunk holds block id {0}, which the registry does not know")]
    UnknownBlock(BlockId),
    /// A chunk meshed with light has more than 65 536 distinct corner lights, more than
    /// the 16-bit indices of [`light::QuadLight`] address.
    #[error("a chunk has more than 65536 distinct corner lights")]
    LightPalette,
}

/// `Result` with this crate's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;
