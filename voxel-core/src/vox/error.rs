//! What can be wrong with a `.vox` file.

use super::MAX_FILE_BYTES;

/// What is wrong with a `.vox` file. Offsets are in bytes from the start of the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum VoxError {
    /// The file could not be read.
    #[error("cannot read the file: {0}")]
    Io(String),
    /// The file is larger than [`MAX_FILE_BYTES`].
    #[error("the file holds {0} bytes, more than the {MAX_FILE_BYTES} a .vox file may hold")]
    TooLarge(u64),
    /// The first four bytes are not `VOX `.
    #[error("not a MagicaVoxel file: it starts with {0:?}, not \"VOX \"")]
    Magic(String),
    /// The file ends inside something.
    #[error("truncated: {what} at offset {at} needs {need} bytes, {left} are left")]
    Truncated {
        /// What was being read.
        what: &'static str,
        /// Where it starts.
        at: usize,
        /// Bytes it needs.
        need: u64,
        /// Bytes left in its chunk (or the file).
        left: usize,
    },
    /// A chunk's declared size reaches past the end of its parent (or of the file).
    #[error(
        "chunk {id} at offset {at} declares {size} bytes, past the end of its parent at offset {end}"
    )]
    ChunkPastEnd {
        /// The chunk's four-letter id.
        id: String,
        /// Where its header starts.
        at: usize,
        /// Content plus children, as declared.
        size: u64,
        /// Where the parent ends.
        end: usize,
    },
    /// The first chunk is not `MAIN`.
    #[error("the first chunk is {0:?}, not MAIN")]
    NoMain(String),
    /// A model's size is 0 or above [`MAX_MODEL_SIDE`](super::MAX_MODEL_SIDE) on some axis.
    #[error("model {model}: size {x}x{y}x{z}; each side must be 1 to 256")]
    ModelSize {
        /// The model's index in the file.
        model: usize,
        /// x as given
        x: u32,
        /// y as given
        y: u32,
        /// z as given
        z: u32,
    },
    /// An `XYZI` chunk without a `SIZE` chunk before it.
    #[error("XYZI chunk at offset {0} has no SIZE chunk before it")]
    VoxelsWithoutSize(usize),
    /// A voxel outside its model's size.
    #[error("model {model}: voxel ({x}, {y}, {z}) lies outside its size {size:?}")]
    VoxelOutside {
        /// The model's index.
        model: usize,
        /// x
        x: u8,
        /// y
        y: u8,
        /// z
        z: u8,
        /// The model's size.
        size: [u32; 3],
    },
    /// A voxel's colour index names no palette entry (0 means empty and is never written;
    /// a short `RGBA` chunk holds fewer than 255 entries).
    #[error(
        "model {model}: voxel ({x}, {y}, {z}) has colour index {index}; the palette holds 1 to {len}"
    )]
    PaletteIndex {
        /// The model's index.
        model: usize,
        /// x
        x: u8,
        /// y
        y: u8,
        /// z
        z: u8,
        /// The colour index as written.
        index: u8,
        /// Highest index the palette holds.
        len: usize,
    },
    /// An `RGBA` chunk whose size is not a whole number of colours from 1 to 256.
    #[error("RGBA chunk at offset {at}: {size} bytes is not 1 to 256 colours of 4 bytes")]
    Palette {
        /// Where the chunk starts.
        at: usize,
        /// Its content size.
        size: usize,
    },
    /// A `MATL` chunk for an id past the palette (ids run 0 to 256; 256 stands for 0).
    #[error("MATL chunk at offset {at}: material id {id} is out of range (0 to 256)")]
    MaterialId {
        /// Where the chunk starts.
        at: usize,
        /// The id as written.
        id: i64,
    },
    /// A material property that is not a number.
    #[error("material {index}: {key} = {value:?} is not a number")]
    MaterialValue {
        /// The colour index the material belongs to.
        index: u8,
        /// The property.
        key: &'static str,
        /// Its text.
        value: String,
    },
    /// A string that is not UTF-8.
    #[error("the string at offset {0} is not UTF-8")]
    Utf8(usize),
    /// Two scene nodes with one id.
    #[error("scene graph: node {0} is defined twice")]
    DuplicateNode(i64),
    /// A node (or the root, node 0) that the file does not hold.
    #[error("scene graph: node {from} refers to node {missing}, which the file does not hold")]
    MissingNode {
        /// The referring node (-1: the root reference).
        from: i64,
        /// The id it names.
        missing: i64,
    },
    /// A shape naming a model the file does not hold.
    #[error(
        "scene graph: shape node {node} refers to model {model}; the file holds {count} models"
    )]
    MissingModel {
        /// The shape node.
        node: i64,
        /// The model id it names.
        model: i64,
        /// Models in the file.
        count: usize,
    },
    /// A node that is its own ancestor.
    #[error("scene graph: node {0} is part of a cycle")]
    Cycle(i64),
    /// A node with two parents (MagicaVoxel writes trees; a shared node would let a small
    /// file place a model exponentially often).
    #[error("scene graph: node {0} has more than one parent")]
    SharedNode(i64),
    /// A transform's `_r` that is not a rotation byte.
    #[error(
        "scene graph: transform node {node} has rotation _r = {value:?}, not a signed permutation (0 to 127)"
    )]
    Rotation {
        /// The transform node.
        node: i64,
        /// The text.
        value: String,
    },
    /// A transform's `_t` that is not three integers.
    #[error(
        "scene graph: transform node {node} has translation _t = {value:?}, not three integers"
    )]
    Translation {
        /// The transform node.
        node: i64,
        /// The text.
        value: String,
    },
    /// Blocks farther than [`MAX_EXTENT`](super::MAX_EXTENT) from the origin.
    #[error("a model is placed {0} blocks from the origin, more than 2^30")]
    OutsideWorld(i64),
    /// More voxels than the limit ([`DEFAULT_MAX_VOXELS`](super::DEFAULT_MAX_VOXELS) unless set).
    #[error("the scene places {count} voxels, more than the limit of {max}")]
    TooManyVoxels {
        /// Voxels the shapes would place.
        count: u64,
        /// The limit.
        max: u64,
    },
}
