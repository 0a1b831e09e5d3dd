//! MagicaVoxel `.vox` files as blocks: a bounded reader of the format (ephtracy's
//! `MagicaVoxel-file-format-vox.txt` and its extension: models, palette, `MATL` materials,
//! the scene graph of transforms, groups and shapes, layers) and the import of a file's
//! voxels into a [`World`](crate::World), one block type per palette entry used.
//!
//! The reader is ours rather than `dot_vox`'s (which the tests use as the independent
//! writer): `dot_vox` 5 panics on a rotation byte that is not a signed permutation, recurses
//! without bound into nested chunks, drops a broken chunk silently (a truncated model
//! becomes no model), and finds scene nodes by file order instead of by their ids. Here
//! every length is checked against the bytes that remain before anything is allocated, so
//! memory stays within a small multiple of the file's size, and every problem is a
//! [`VoxError`] saying what is wrong and where.
//!
//! # Coordinates
//!
//! MagicaVoxel is z-up and right-handed; this crate is y-up and right-handed. A model's
//! voxel `v` of a model of size `s` under the scene graph's flattened transform `(R, t)`
//! lies in MagicaVoxel's cell `floor(R · (v + ½ − ⌊s/2⌋) + t)` (the model turns about the
//! centre of its voxel `⌊s/2⌋`, as MagicaVoxel and ogt_vox place it), and that cell
//! `(x, y, z)` becomes this crate's block `(x, z, −y − 1)`: MagicaVoxel's up is our +y, its
//! front (−y, where its camera starts) our +z. The turn is proper (no mirror image).
//!
//! # Materials
//!
//! | `MATL` `_type` | block |
//! |---|---|
//! | `_glass`, `_blend`, `_cloud` | translucent; opacity `1 − _trans` (else `1 − _alpha`, else 0.5), raised to [`MIN_OPACITY`]; at 1, opaque |
//! | `_diffuse`, `_metal`, `_emit`, `_plastic`, `_media`, none, other | opaque |
//!
//! The palette's alpha channel is not read (MagicaVoxel writes 255 everywhere), nor is the
//! pre-0.99 `MATT` chunk: an older file's water and glass come in opaque, and a
//! [`PaletteOverride`] (in the lab's scene files: `[[models.palette]]`) says which entries
//! are translucent or cutout and with what opacity. The `IMAP` chunk only orders the
//! palette in MagicaVoxel's editor and is not needed. Animations: the first frame of a
//! transform and the first model of a shape are used. Hidden transforms and hidden layers
//! are left out, as MagicaVoxel shows them.
//!
//! The bounded byte reader is in `bytes`, the chunks in `read`, the scene graph in `scene`
//! (transforms, groups, shapes, layers), the import into a [`World`](crate::World) in
//! `import`.

mod bytes;
mod error;
mod import;
mod read;
mod scene;
#[cfg(test)]
mod tests;

pub use error::VoxError;
pub use import::{PaletteOverride, VoxBlocks, VoxPlacement, world_from_vox};
pub use read::default_palette;
pub use scene::{VoxInstance, VoxRotation};

/// Largest side of a model, in voxels (MagicaVoxel's limit).
pub const MAX_MODEL_SIDE: u32 = 256;
/// Largest file [`VoxFile::load`] reads: 256 MiB holds a full 256³ model four times over.
pub const MAX_FILE_BYTES: u64 = 256 << 20;
/// Voxels placed by all shapes together at most, by default: one full 256³ model. A shape
/// may place a model many times, so this, not the file's size, bounds the import's work.
pub const DEFAULT_MAX_VOXELS: u64 = 1 << 24;
/// Lowest opacity a glass material gets: the lowest the lab's stability sweeps measure, and
/// visible (a `_trans` of 1 would otherwise make a block that draws nothing).
pub const MIN_OPACITY: f32 = 0.05;
/// How far from the origin a placed block may lie on any axis (2³⁰: room to move a model
/// anywhere a scene file can put it without leaving the `i32` world).
pub const MAX_EXTENT: i64 = 1 << 30;

/// What a palette entry's material makes of its blocks (see the module docs' table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VoxMaterial {
    /// An opaque block.
    Opaque,
    /// A glass-like material: a translucent block of this opacity (below 1).
    Glass(f32),
}

/// A model: its size and its voxels as written, `[x, y, z, colour index]` (index 1 to 255).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VoxModel {
    /// Size in voxels, MagicaVoxel's axes (z up), each 1 to 256.
    pub size: [u32; 3],
    /// The voxels.
    pub voxels: Vec<[u8; 4]>,
}

/// A `.vox` file, read and checked: models, palette, materials, and the visible placements
/// of its scene graph.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxFile {
    /// The version written in the header (150 and 200 are common).
    pub version: u32,
    /// The models, in file order.
    pub models: Vec<VoxModel>,
    /// Every visible placement of a model (one per model, untransformed, when the file has
    /// no scene graph).
    pub instances: Vec<VoxInstance>,
    /// sRGB colour per colour index (index 0 is unused).
    pub palette: [[u8; 3]; 256],
    /// Highest colour index the palette holds (255 for a full palette).
    pub palette_len: usize,
    /// Material per colour index.
    pub materials: [VoxMaterial; 256],
}
