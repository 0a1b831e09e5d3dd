//! MagicaVoxel `.vox` files as blocks: a bounded reader of the format (ephtracy's
//! `MagicaVoxel-file-format-vox.txt` and its extension: models, palette, `MATL` materials,
//! the scene graph of transforms, groups and shapes, layers) and the import of a file's
//! voxels into a [`World`], one block type per palette entry used.
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

use std::collections::HashMap;
use std::path::Path;

use crate::{
    BlockDef, BlockId, BlockRegistry, Error, Pattern, RenderClass, Result, World, WorldPos,
};

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
    /// A model's size is 0 or above [`MAX_MODEL_SIDE`] on some axis.
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
    /// Blocks farther than [`MAX_EXTENT`] from the origin.
    #[error("a model is placed {0} blocks from the origin, more than 2^30")]
    OutsideWorld(i64),
    /// More voxels than the limit ([`DEFAULT_MAX_VOXELS`] unless set).
    #[error("the scene places {count} voxels, more than the limit of {max}")]
    TooManyVoxels {
        /// Voxels the shapes would place.
        count: u64,
        /// The limit.
        max: u64,
    },
}

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

/// A rotation of the scene graph: a signed permutation, `(R v)[r] = sign[r] · v[axis[r]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxRotation {
    /// Per row, the axis it takes.
    pub axis: [u8; 3],
    /// Per row, its sign (±1).
    pub sign: [i8; 3],
}

impl VoxRotation {
    /// No turn.
    pub const IDENTITY: Self = Self {
        axis: [0, 1, 2],
        sign: [1, 1, 1],
    };

    /// Decodes MagicaVoxel's rotation byte: bits 0–1 the axis of row 0, bits 2–3 that of
    /// row 1, bits 4–6 the signs of rows 0–2 (set: negative). `None` unless a signed
    /// permutation below 128.
    pub fn from_byte(b: u8) -> Option<Self> {
        let (a0, a1) = (b & 3, (b >> 2) & 3);
        if b >= 128 || a0 > 2 || a1 > 2 || a0 == a1 {
            return None;
        }
        let sign = |bit: u8| if b & (1 << bit) == 0 { 1 } else { -1 };
        Some(Self {
            axis: [a0, a1, 3 - a0 - a1],
            sign: [sign(4), sign(5), sign(6)],
        })
    }

    /// `self · v`.
    pub fn apply(&self, v: [i64; 3]) -> [i64; 3] {
        std::array::from_fn(|r| i64::from(self.sign[r]) * v[usize::from(self.axis[r])])
    }

    /// `self · other`: `other` first, then `self`.
    pub fn then_after(&self, other: &Self) -> Self {
        Self {
            axis: std::array::from_fn(|r| other.axis[usize::from(self.axis[r])]),
            sign: std::array::from_fn(|r| self.sign[r] * other.sign[usize::from(self.axis[r])]),
        }
    }
}

/// One placement of a model by the scene graph, its transforms flattened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxInstance {
    /// Index into [`VoxFile::models`].
    pub model: usize,
    /// The product of the rotations from the root down.
    pub rotation: VoxRotation,
    /// The translation, in MagicaVoxel's axes.
    pub translation: [i64; 3],
}

impl VoxInstance {
    /// This crate's block (y-up) that the instance's voxel `v` of a model of size `size`
    /// fills (see the module docs).
    pub fn block(&self, size: [u32; 3], v: [u8; 3]) -> [i64; 3] {
        // Doubled coordinates keep the voxel centre v + 1/2 - floor(s/2) an integer.
        let centre2 = std::array::from_fn(|i| 2 * i64::from(v[i]) + 1 - 2 * i64::from(size[i] / 2));
        let r = self.rotation.apply(centre2);
        // r is odd on every axis: floor(r / 2) is exact.
        let mv: [i64; 3] = std::array::from_fn(|i| self.translation[i] + r[i].div_euclid(2));
        [mv[0], mv[2], -mv[1] - 1]
    }
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

/// MagicaVoxel's default palette (used when a file has no `RGBA` chunk), by colour index:
/// the 6×6×6 cube of 0xFF, 0xCC … 0x00 without black, then ramps of red, green, blue and
/// grey through 0xEE, 0xDD, 0xBB, 0xAA, 0x88, 0x77, 0x55, 0x44, 0x22, 0x11.
pub fn default_palette() -> [[u8; 3]; 256] {
    let mut p = [[0u8; 3]; 256];
    for i in 0..215 {
        let step = |s: usize| (255 - 51 * s) as u8;
        p[i + 1] = [step(i / 36), step((i / 6) % 6), step(i % 6)];
    }
    const RAMP: [u8; 10] = [0xee, 0xdd, 0xbb, 0xaa, 0x88, 0x77, 0x55, 0x44, 0x22, 0x11];
    for (k, v) in RAMP.iter().enumerate() {
        p[216 + k] = [*v, 0, 0];
        p[226 + k] = [0, *v, 0];
        p[236 + k] = [0, 0, *v];
        p[246 + k] = [*v, *v, *v];
    }
    p
}

/// A bounded reader over `bytes[pos..end]`.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    end: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], VoxError> {
        let left = self.end - self.pos;
        if n > left {
            return Err(VoxError::Truncated {
                what,
                at: self.pos,
                need: n as u64,
                left,
            });
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, VoxError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn i32(&mut self, what: &'static str) -> Result<i64, VoxError> {
        Ok(i64::from(self.u32(what)? as i32))
    }

    /// A count of items of at least `min_size` bytes each: more than the bytes left can
    /// hold is a truncation, found before anything is allocated for them.
    fn count(&mut self, min_size: usize, what: &'static str) -> Result<usize, VoxError> {
        let at = self.pos;
        let n = self.u32(what)? as usize;
        let left = self.end - self.pos;
        if n > left / min_size {
            return Err(VoxError::Truncated {
                what,
                at,
                need: n as u64 * min_size as u64,
                left,
            });
        }
        Ok(n)
    }

    fn string(&mut self, what: &'static str) -> Result<String, VoxError> {
        let n = self.count(1, what)?;
        let at = self.pos;
        let b = self.take(n, what)?;
        String::from_utf8(b.to_vec()).map_err(|_| VoxError::Utf8(at))
    }

    fn dict(&mut self, what: &'static str) -> Result<HashMap<String, String>, VoxError> {
        // Each entry holds two length words at least.
        let n = self.count(8, what)?;
        let mut d = HashMap::with_capacity(n);
        for _ in 0..n {
            let k = self.string(what)?;
            let v = self.string(what)?;
            d.insert(k, v);
        }
        Ok(d)
    }
}

/// A scene graph node as read.
#[derive(Debug)]
enum Node {
    Transform {
        child: i64,
        layer: i64,
        hidden: bool,
        rotation: VoxRotation,
        translation: [i64; 3],
    },
    Group(Vec<i64>),
    Shape(Option<i64>),
}

fn hidden(d: &HashMap<String, String>) -> bool {
    d.get("_hidden").is_some_and(|v| v == "1")
}

/// The material of a `MATL` dictionary (see the module docs).
fn material(index: u8, d: &HashMap<String, String>) -> Result<VoxMaterial, VoxError> {
    let number = |key: &'static str| -> Result<Option<f32>, VoxError> {
        d.get(key)
            .map(|v| {
                v.trim()
                    .parse::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| VoxError::MaterialValue {
                        index,
                        key,
                        value: v.clone(),
                    })
            })
            .transpose()
    };
    let glassy = matches!(
        d.get("_type").map(String::as_str),
        Some("_glass" | "_blend" | "_cloud")
    );
    if !glassy {
        return Ok(VoxMaterial::Opaque);
    }
    let transparency = match number("_trans")? {
        Some(t) => t,
        None => number("_alpha")?.unwrap_or(0.5),
    };
    let opacity = (1.0 - transparency).clamp(MIN_OPACITY, 1.0);
    Ok(if opacity >= 1.0 {
        VoxMaterial::Opaque
    } else {
        VoxMaterial::Glass(opacity)
    })
}

fn transform_node(node: i64, r: &mut Reader<'_>) -> Result<Node, VoxError> {
    let attrs = r.dict("nTRN attributes")?;
    let child = r.i32("nTRN child")?;
    let _reserved = r.i32("nTRN reserved id")?;
    let layer = r.i32("nTRN layer")?;
    let frames = r.count(4, "nTRN frames")?;
    let mut rotation = VoxRotation::IDENTITY;
    let mut translation = [0; 3];
    for f in 0..frames {
        let d = r.dict("nTRN frame")?;
        if f > 0 {
            continue; // animation frames after the first are not used
        }
        if let Some(v) = d.get("_r") {
            rotation = v
                .trim()
                .parse::<u8>()
                .ok()
                .and_then(VoxRotation::from_byte)
                .ok_or_else(|| VoxError::Rotation {
                    node,
                    value: v.clone(),
                })?;
        }
        if let Some(v) = d.get("_t") {
            let bad = || VoxError::Translation {
                node,
                value: v.clone(),
            };
            let parts: Vec<i64> = v
                .split_whitespace()
                .map(|p| p.parse::<i32>().map(i64::from))
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            translation = parts.try_into().map_err(|_| bad())?;
        }
    }
    Ok(Node::Transform {
        child,
        layer,
        hidden: hidden(&attrs),
        rotation,
        translation,
    })
}

impl VoxFile {
    /// Reads a `.vox` file (at most [`MAX_FILE_BYTES`]) with the default voxel limit.
    /// Errors name the file.
    pub fn load(path: &Path) -> Result<Self> {
        let wrap = |error| Error::Vox {
            file: path.display().to_string(),
            error,
        };
        let bytes = read_bounded(path).map_err(wrap)?;
        Self::parse(&bytes, DEFAULT_MAX_VOXELS).map_err(wrap)
    }

    /// Reads a `.vox` file from memory. `max_voxels` bounds the voxels all shapes together
    /// place ([`DEFAULT_MAX_VOXELS`] is one full 256³ model).
    pub fn parse(bytes: &[u8], max_voxels: u64) -> Result<Self, VoxError> {
        let mut r = Reader {
            bytes,
            pos: 0,
            end: bytes.len(),
        };
        let magic = r.take(4, "the header").map_err(|_| {
            VoxError::Magic(String::from_utf8_lossy(bytes).escape_debug().to_string())
        })?;
        if magic != b"VOX " {
            return Err(VoxError::Magic(
                String::from_utf8_lossy(magic).escape_debug().to_string(),
            ));
        }
        let version = r.u32("the version")?;
        let (id, main_at, content, children) = chunk_header(&mut r)?;
        if id != "MAIN" {
            return Err(VoxError::NoMain(id));
        }
        // MAIN's own content is empty in every writer; skip whatever it holds.
        r.take(content, "MAIN content")?;
        let mut c = Reader {
            bytes,
            pos: r.pos,
            end: r.pos + children,
        };
        let _ = main_at;

        let mut models = Vec::new();
        let mut size: Option<[u32; 3]> = None;
        let mut palette = default_palette();
        let mut palette_len = 255;
        let mut materials = [VoxMaterial::Opaque; 256];
        let mut nodes: HashMap<i64, Node> = HashMap::new();
        let mut hidden_layers = Vec::new();
        while c.pos < c.end {
            let (id, at, content, children) = chunk_header(&mut c)?;
            let mut body = Reader {
                bytes,
                pos: c.pos,
                end: c.pos + content,
            };
            // Children of chunks other than MAIN are not part of the format; skipped.
            c.pos += content + children;
            match id.as_str() {
                "SIZE" => {
                    let s = [
                        body.u32("SIZE x")?,
                        body.u32("SIZE y")?,
                        body.u32("SIZE z")?,
                    ];
                    if s.iter().any(|v| !(1..=MAX_MODEL_SIDE).contains(v)) {
                        return Err(VoxError::ModelSize {
                            model: models.len(),
                            x: s[0],
                            y: s[1],
                            z: s[2],
                        });
                    }
                    size = Some(s);
                }
                "XYZI" => {
                    let s = size.take().ok_or(VoxError::VoxelsWithoutSize(at))?;
                    let n = body.count(4, "XYZI voxels")?;
                    let raw = body.take(n * 4, "XYZI voxels")?;
                    let model = models.len();
                    let mut voxels = Vec::with_capacity(n);
                    for v in raw.chunks_exact(4) {
                        let [x, y, z, i] = [v[0], v[1], v[2], v[3]];
                        if u32::from(x) >= s[0] || u32::from(y) >= s[1] || u32::from(z) >= s[2] {
                            return Err(VoxError::VoxelOutside {
                                model,
                                x,
                                y,
                                z,
                                size: s,
                            });
                        }
                        voxels.push([x, y, z, i]);
                    }
                    models.push(VoxModel { size: s, voxels });
                }
                "RGBA" => {
                    if content == 0 || content % 4 != 0 || content > 1024 {
                        return Err(VoxError::Palette { at, size: content });
                    }
                    let raw = body.take(content, "RGBA colours")?;
                    // Entry k is colour index k + 1; the 256th entry has no index.
                    for (k, c) in raw.chunks_exact(4).take(255).enumerate() {
                        palette[k + 1] = [c[0], c[1], c[2]];
                    }
                    palette_len = (content / 4).min(255);
                }
                "MATL" => {
                    let mid = body.i32("MATL id")?;
                    let d = body.dict("MATL properties")?;
                    if !(0..=256).contains(&mid) {
                        return Err(VoxError::MaterialId { at, id: mid });
                    }
                    // Id k is colour index k; 256 stands for 0, which no voxel uses.
                    if let Ok(index @ 1..=255) = u8::try_from(mid) {
                        materials[usize::from(index)] = material(index, &d)?;
                    }
                }
                "nTRN" | "nGRP" | "nSHP" => {
                    let node = body.i32("node id")?;
                    let n = match id.as_str() {
                        "nTRN" => transform_node(node, &mut body)?,
                        "nGRP" => {
                            let _attrs = body.dict("nGRP attributes")?;
                            let k = body.count(4, "nGRP children")?;
                            let mut children = Vec::with_capacity(k);
                            for _ in 0..k {
                                children.push(body.i32("nGRP child")?);
                            }
                            Node::Group(children)
                        }
                        _ => {
                            let _attrs = body.dict("nSHP attributes")?;
                            let k = body.count(8, "nSHP models")?;
                            let mut first = None;
                            for _ in 0..k {
                                let m = body.i32("nSHP model id")?;
                                let _frame = body.dict("nSHP model attributes")?;
                                first = first.or(Some(m));
                            }
                            Node::Shape(first)
                        }
                    };
                    if nodes.insert(node, n).is_some() {
                        return Err(VoxError::DuplicateNode(node));
                    }
                }
                "LAYR" => {
                    let layer = body.i32("LAYR id")?;
                    let d = body.dict("LAYR attributes")?;
                    if hidden(&d) {
                        hidden_layers.push(layer);
                    }
                }
                // PACK, IMAP, NOTE, rOBJ, rCAM, MATT and anything newer: not needed.
                _ => {}
            }
        }

        // Palette indices are checked once the whole file (its RGBA chunk may come last)
        // is read.
        for (model, m) in models.iter().enumerate() {
            if let Some(&[x, y, z, index]) = m
                .voxels
                .iter()
                .find(|v| v[3] == 0 || usize::from(v[3]) > palette_len)
            {
                return Err(VoxError::PaletteIndex {
                    model,
                    x,
                    y,
                    z,
                    index,
                    len: palette_len,
                });
            }
        }

        let instances = if nodes.is_empty() {
            (0..models.len())
                .map(|model| VoxInstance {
                    model,
                    rotation: VoxRotation::IDENTITY,
                    translation: [0; 3],
                })
                .collect()
        } else {
            flatten(&nodes, &hidden_layers, models.len())?
        };
        let mut count = 0u64;
        for inst in &instances {
            count += models[inst.model].voxels.len() as u64;
            if count > max_voxels {
                // Count them all for the message: bounded by the instance count.
                let total = instances
                    .iter()
                    .map(|i| models[i.model].voxels.len() as u64)
                    .sum();
                return Err(VoxError::TooManyVoxels {
                    count: total,
                    max: max_voxels,
                });
            }
            // The placed box of the instance: its model's corner voxels.
            let m = &models[inst.model];
            for corner in 0..8u8 {
                let v = std::array::from_fn(|i| {
                    if corner & (1 << i) == 0 {
                        0
                    } else {
                        (m.size[i] - 1) as u8
                    }
                });
                let b = inst.block(m.size, v);
                if let Some(far) = b.iter().map(|c| c.abs()).find(|c| *c > MAX_EXTENT) {
                    return Err(VoxError::OutsideWorld(far));
                }
            }
        }
        Ok(Self {
            version,
            models,
            instances,
            palette,
            palette_len,
            materials,
        })
    }

    /// Voxels the instances place, all together.
    pub fn voxel_count(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.models[i.model].voxels.len() as u64)
            .sum()
    }

    /// Every placed voxel: this crate's block (y-up, before any [`VoxPlacement`]) and its
    /// colour index.
    pub fn voxels(&self) -> impl Iterator<Item = ([i64; 3], u8)> + '_ {
        self.instances.iter().flat_map(move |inst| {
            let m = &self.models[inst.model];
            m.voxels
                .iter()
                .map(move |v| (inst.block(m.size, [v[0], v[1], v[2]]), v[3]))
        })
    }

    /// Whether colour index `i` is used by a placed voxel, per index.
    pub fn used(&self) -> [bool; 256] {
        let mut per_model = vec![[false; 256]; self.models.len()];
        for (m, used) in self.models.iter().zip(&mut per_model) {
            for v in &m.voxels {
                used[usize::from(v[3])] = true;
            }
        }
        let mut used = [false; 256];
        for inst in &self.instances {
            for (u, m) in used.iter_mut().zip(&per_model[inst.model]) {
                *u |= *m;
            }
        }
        used
    }

    /// The blocks' bounding box (inclusive corners, y-up, before placement), or `None`
    /// when nothing is placed.
    pub fn bounds(&self) -> Option<([i64; 3], [i64; 3])> {
        let mut b: Option<([i64; 3], [i64; 3])> = None;
        for inst in &self.instances {
            let m = &self.models[inst.model];
            if m.voxels.is_empty() {
                continue;
            }
            for corner in 0..8u8 {
                let v = std::array::from_fn(|i| {
                    if corner & (1 << i) == 0 {
                        0
                    } else {
                        (m.size[i] - 1) as u8
                    }
                });
                let p = inst.block(m.size, v);
                let (lo, hi) = b.get_or_insert((p, p));
                for i in 0..3 {
                    lo[i] = lo[i].min(p[i]);
                    hi[i] = hi[i].max(p[i]);
                }
            }
        }
        b
    }

    /// The block type colour index `index` becomes, with `overrides` applied, named
    /// `{name}#{index}` (`{name} glass #{index}` for a glass material). A glass material
    /// is framed like the built-in glass ([`Pattern::Framed`]); an override gets its
    /// class's default pattern.
    pub fn block_def(&self, name: &str, index: u8, overrides: &[PaletteOverride]) -> BlockDef {
        let color = self.palette[usize::from(index)];
        if let Some(o) = overrides.iter().rev().find(|o| o.index == index) {
            let def = match o.class {
                RenderClass::Cutout => BlockDef::cutout(format!("{name}#{index}"), color),
                _ => BlockDef::new(format!("{name}#{index}"), color, o.opacity),
            };
            return BlockDef {
                class: o.class,
                opacity: o.opacity,
                ..def
            };
        }
        match self.materials[usize::from(index)] {
            VoxMaterial::Opaque => BlockDef::new(format!("{name}#{index}"), color, 1.0),
            VoxMaterial::Glass(a) => BlockDef::new(format!("{name} glass #{index}"), color, a)
                .with_pattern(Pattern::Framed),
        }
    }

    /// Registers one block type per colour index the file uses (see [`Self::block_def`]).
    /// A name already registered with the same definition is reused (the same file placed
    /// twice shares its types, so its water meets without a wall); with another definition
    /// a `~2`, `~3` … suffix keeps both. Fails on an override of index 0, a definition the
    /// registry refuses (an override's opacity against its class) or a full registry.
    pub fn register_blocks(
        &self,
        name: &str,
        overrides: &[PaletteOverride],
        registry: &mut BlockRegistry,
    ) -> Result<VoxBlocks> {
        if let Some(o) = overrides.iter().find(|o| o.index == 0) {
            return Err(Error::InvalidBlockDef {
                name: format!("{name}#{}", o.index),
                reason: "palette overrides name colour indices 1 to 255",
            });
        }
        let used = self.used();
        let mut ids = [BlockId::AIR; 256];
        for index in 1..=255u8 {
            if !used[usize::from(index)] {
                continue;
            }
            let def = self.block_def(name, index, overrides);
            let mut candidate = def.clone();
            let mut k = 1;
            ids[usize::from(index)] = loop {
                match registry.id(&candidate.name) {
                    Ok(id) if registry.get(id).ok() == Some(&candidate) => break id,
                    Ok(_) => {
                        k += 1;
                        candidate.name = format!("{}~{k}", def.name);
                    }
                    Err(_) => break registry.register(candidate)?,
                }
            };
        }
        Ok(VoxBlocks { ids })
    }

    /// Writes every placed voxel into `world` as the block `blocks` gives its colour index,
    /// turned by `placement` and moved so that the bounding box's lowest corner lands on
    /// its `at`. Voxels only ever set blocks (empty cells leave the world as it was).
    /// Returns the placed box (inclusive corners), `None` when nothing was placed. `file`
    /// names the model in errors.
    pub fn place(
        &self,
        file: &str,
        blocks: &VoxBlocks,
        placement: VoxPlacement,
        world: &mut World,
    ) -> Result<Option<(WorldPos, WorldPos)>> {
        let Some((lo, hi)) = self.bounds() else {
            return Ok(None);
        };
        let turns = placement.quarter_turns % 4;
        let (tlo, thi) = turn_box(lo, hi, turns);
        let shift: [i64; 3] = std::array::from_fn(|i| i64::from(placement.at[i]) - tlo[i]);
        let far = |p: [i64; 3]| p.iter().map(|c| c.abs()).max().unwrap_or(0);
        let (min, max): ([i64; 3], [i64; 3]) = (
            std::array::from_fn(|i| tlo[i] + shift[i]),
            std::array::from_fn(|i| thi[i] + shift[i]),
        );
        let extent = far(min).max(far(max));
        if extent > MAX_EXTENT {
            return Err(Error::Vox {
                file: file.to_owned(),
                error: VoxError::OutsideWorld(extent),
            });
        }
        // Every coordinate is within 2^30 now, so the casts below are exact.
        let pos = |p: [i64; 3]| WorldPos::new(p[0] as i32, p[1] as i32, p[2] as i32);
        for (p, index) in self.voxels() {
            let t = turn(p, turns);
            let id = blocks.ids[usize::from(index)];
            world.set_block(pos(std::array::from_fn(|i| t[i] + shift[i])), id)?;
        }
        Ok(Some((pos(min), pos(max))))
    }
}

/// A block `p` turned `turns` quarter turns about +y (right-handed: +x goes to −z), as a
/// cell: its centre turns, so `(x, z)` becomes `(z, −x − 1)` per turn.
fn turn(p: [i64; 3], turns: u8) -> [i64; 3] {
    let mut p = p;
    for _ in 0..turns {
        p = [p[2], p[1], -p[0] - 1];
    }
    p
}

/// The box `lo..=hi` turned like [`turn`] turns its blocks.
fn turn_box(lo: [i64; 3], hi: [i64; 3], turns: u8) -> ([i64; 3], [i64; 3]) {
    let (a, b) = (turn(lo, turns), turn(hi, turns));
    (
        std::array::from_fn(|i| a[i].min(b[i])),
        std::array::from_fn(|i| a[i].max(b[i])),
    )
}

/// A chunk header: id, where it starts, content and children sizes (both checked to lie
/// within `r`).
fn chunk_header(r: &mut Reader<'_>) -> Result<(String, usize, usize, usize), VoxError> {
    let at = r.pos;
    let id = r.take(4, "a chunk header")?;
    let id = String::from_utf8_lossy(id).escape_debug().to_string();
    let content = r.u32("a chunk header")?;
    let children = r.u32("a chunk header")?;
    let size = u64::from(content) + u64::from(children);
    if size > (r.end - r.pos) as u64 {
        return Err(VoxError::ChunkPastEnd {
            id,
            at,
            size,
            end: r.end,
        });
    }
    Ok((id, at, content as usize, children as usize))
}

/// The visible instances of the scene graph under node 0. Each node is entered once: a
/// node met again is a cycle (when it is an ancestor) or shared (two parents).
fn flatten(
    nodes: &HashMap<i64, Node>,
    hidden_layers: &[i64],
    models: usize,
) -> Result<Vec<VoxInstance>, VoxError> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        OnPath,
        Done,
    }
    enum Step {
        Enter(i64, i64, VoxRotation, [i64; 3]),
        Leave(i64),
    }
    let mut state: HashMap<i64, State> = HashMap::with_capacity(nodes.len());
    let mut out = Vec::new();
    let mut stack = vec![Step::Enter(0, -1, VoxRotation::IDENTITY, [0; 3])];
    while let Some(step) = stack.pop() {
        let (id, from, rot, t) = match step {
            Step::Leave(id) => {
                state.insert(id, State::Done);
                continue;
            }
            Step::Enter(id, from, rot, t) => (id, from, rot, t),
        };
        let node = nodes
            .get(&id)
            .ok_or(VoxError::MissingNode { from, missing: id })?;
        match state.get(&id) {
            Some(State::OnPath) => return Err(VoxError::Cycle(id)),
            Some(State::Done) => return Err(VoxError::SharedNode(id)),
            None => {}
        }
        state.insert(id, State::OnPath);
        stack.push(Step::Leave(id));
        match node {
            Node::Transform {
                child,
                layer,
                hidden,
                rotation,
                translation,
            } => {
                if *hidden || hidden_layers.contains(layer) {
                    continue;
                }
                // Parent after child: p = R_parent (R_child v + t_child) + t_parent.
                let moved = rot.apply(*translation);
                let t2 = std::array::from_fn(|i| t[i] + moved[i]);
                // Deep chains could grow without bound; MAX_EXTENT is checked per instance
                // later, this keeps the sums themselves far from overflow.
                if let Some(far) = t2.iter().map(|c: &i64| c.abs()).find(|c| *c > 1 << 40) {
                    return Err(VoxError::OutsideWorld(far));
                }
                stack.push(Step::Enter(*child, id, rot.then_after(rotation), t2));
            }
            Node::Group(children) => {
                for c in children.iter().rev() {
                    stack.push(Step::Enter(*c, id, rot, t));
                }
            }
            Node::Shape(model) => {
                if let Some(m) = *model {
                    let index = usize::try_from(m).ok().filter(|i| *i < models).ok_or(
                        VoxError::MissingModel {
                            node: id,
                            model: m,
                            count: models,
                        },
                    )?;
                    out.push(VoxInstance {
                        model: index,
                        rotation: rot,
                        translation: t,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// Reads at most [`MAX_FILE_BYTES`] of `path`.
fn read_bounded(path: &Path) -> Result<Vec<u8>, VoxError> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| VoxError::Io(e.to_string()))?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| VoxError::Io(e.to_string()))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        let len = std::fs::metadata(path).map_or(bytes.len() as u64, |m| m.len());
        return Err(VoxError::TooLarge(len));
    }
    Ok(bytes)
}

/// What a palette entry of an older file (or any file) becomes, instead of what its
/// material says: `class` with `opacity` (below 1 for translucent, 1 otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaletteOverride {
    /// The colour index, 1 to 255, as MagicaVoxel numbers its palette.
    pub index: u8,
    /// Opaque, cutout or translucent.
    pub class: RenderClass,
    /// The opacity: in (0, 1) for translucent, 1 for the others.
    pub opacity: f32,
}

/// The block id of each colour index (air where the file does not use it), from
/// [`VoxFile::register_blocks`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VoxBlocks {
    /// Per colour index.
    pub ids: [BlockId; 256],
}

/// Where a model goes in a world.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VoxPlacement {
    /// Where the lowest corner of the model's bounding box goes.
    pub at: [i32; 3],
    /// Quarter turns about +y (right-handed: seen from above, counterclockwise), applied
    /// before the move.
    pub quarter_turns: u8,
}

/// A world of `file` alone, placed at the origin: the default registry plus its blocks
/// (named after `name`). The one-call import for a game.
pub fn world_from_vox(file: &VoxFile, name: &str, overrides: &[PaletteOverride]) -> Result<World> {
    let mut registry = BlockRegistry::default();
    let blocks = file.register_blocks(name, overrides, &mut registry)?;
    let mut world = World::new(std::sync::Arc::new(registry));
    file.place(name, &blocks, VoxPlacement::default(), &mut world)?;
    Ok(world)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test
    use super::*;

    /// A chunk: id, content, children bytes.
    fn chunk(id: &[u8; 4], content: &[u8], children: &[u8]) -> Vec<u8> {
        let mut v = id.to_vec();
        v.extend((content.len() as u32).to_le_bytes());
        v.extend((children.len() as u32).to_le_bytes());
        v.extend(content);
        v.extend(children);
        v
    }

    fn file(chunks: &[Vec<u8>]) -> Vec<u8> {
        let mut v = b"VOX ".to_vec();
        v.extend(200u32.to_le_bytes());
        v.extend(chunk(b"MAIN", &[], &chunks.concat()));
        v
    }

    fn words(w: &[u32]) -> Vec<u8> {
        w.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    fn size(x: u32, y: u32, z: u32) -> Vec<u8> {
        chunk(b"SIZE", &words(&[x, y, z]), &[])
    }

    fn xyzi(voxels: &[[u8; 4]]) -> Vec<u8> {
        let mut c = words(&[voxels.len() as u32]);
        c.extend(voxels.concat());
        chunk(b"XYZI", &c, &[])
    }

    fn dict(entries: &[(&str, &str)]) -> Vec<u8> {
        let mut v = words(&[entries.len() as u32]);
        for (k, val) in entries {
            for s in [k, val] {
                v.extend(words(&[s.len() as u32]));
                v.extend(s.as_bytes());
            }
        }
        v
    }

    fn trn(id: u32, child: u32, frame: &[(&str, &str)]) -> Vec<u8> {
        let mut c = words(&[id]);
        c.extend(dict(&[]));
        c.extend(words(&[child, u32::MAX, 0, 1]));
        c.extend(dict(frame));
        chunk(b"nTRN", &c, &[])
    }

    fn grp(id: u32, children: &[u32]) -> Vec<u8> {
        let mut c = words(&[id]);
        c.extend(dict(&[]));
        c.extend(words(&[children.len() as u32]));
        c.extend(words(children));
        chunk(b"nGRP", &c, &[])
    }

    fn shp(id: u32, model: u32) -> Vec<u8> {
        let mut c = words(&[id]);
        c.extend(dict(&[]));
        c.extend(words(&[1, model]));
        c.extend(dict(&[]));
        chunk(b"nSHP", &c, &[])
    }

    fn parse(bytes: &[u8]) -> Result<VoxFile, VoxError> {
        VoxFile::parse(bytes, DEFAULT_MAX_VOXELS)
    }

    fn one_voxel() -> Vec<Vec<u8>> {
        vec![size(2, 2, 2), xyzi(&[[1, 0, 1, 5]])]
    }

    #[test]
    fn the_default_palette_is_magicavoxels() {
        let ours = default_palette();
        for (k, c) in dot_vox::DEFAULT_PALETTE.iter().take(255).enumerate() {
            assert_eq!(ours[k + 1], [c.r, c.g, c.b], "colour index {}", k + 1);
        }
    }

    #[test]
    fn rotations_decode_as_dot_vox_does_and_compose_as_matrices() {
        let matrix = |r: &VoxRotation| -> [[i64; 3]; 3] {
            std::array::from_fn(|row| std::array::from_fn(|col| r.apply(unit(col))[row]))
        };
        fn unit(i: usize) -> [i64; 3] {
            std::array::from_fn(|j| i64::from(i == j))
        }
        let mut valid = Vec::new();
        for b in 0..=255u8 {
            let (a0, a1) = (b & 3, (b >> 2) & 3);
            let ok = b < 128 && a0 < 3 && a1 < 3 && a0 != a1;
            let r = VoxRotation::from_byte(b);
            assert_eq!(r.is_some(), ok, "byte {b}");
            if let Some(r) = r {
                // dot_vox's matrix, independently decoded: cols[c][r].
                let cols = dot_vox::Rotation::from_byte(b).to_cols_array_2d();
                let m = matrix(&r);
                for (row, m_row) in m.iter().enumerate() {
                    for (col, v) in m_row.iter().enumerate() {
                        assert_eq!(*v as f32, cols[col][row], "byte {b} ({row}, {col})");
                    }
                }
                valid.push(r);
            }
        }
        assert_eq!(valid.len(), 48, "every signed permutation of three axes");
        for a in &valid {
            for b in &valid {
                let (ma, mb, mc) = (matrix(a), matrix(b), matrix(&a.then_after(b)));
                for r in 0..3 {
                    for c in 0..3 {
                        let p: i64 = (0..3).map(|k| ma[r][k] * mb[k][c]).sum();
                        assert_eq!(mc[r][c], p);
                    }
                }
            }
        }
    }

    #[test]
    fn a_model_without_scene_graph_is_placed_about_its_centre_voxel() {
        let f = parse(&file(&one_voxel())).unwrap();
        assert_eq!(f.instances.len(), 1);
        // Voxel (1, 0, 1) of a 2x2x2 model: MagicaVoxel cell (0, -1, 0), our (0, 0, 0).
        assert_eq!(f.voxels().collect::<Vec<_>>(), vec![([0, 0, 0], 5)]);
        assert_eq!(f.bounds(), Some(([-1, -1, -1], [0, 0, 0])));
        assert_eq!(f.palette_len, 255);
        assert_eq!(f.palette[5], default_palette()[5]);
    }

    #[test]
    fn glass_materials_map_to_opacities() {
        let mat = |id: u32, props: &[(&str, &str)]| {
            let mut c = words(&[id]);
            c.extend(dict(props));
            chunk(b"MATL", &c, &[])
        };
        let mut chunks = one_voxel();
        chunks.extend([
            mat(1, &[("_type", "_glass"), ("_trans", "0.25")]),
            mat(2, &[("_type", "_glass"), ("_alpha", "0.5")]),
            mat(3, &[("_type", "_glass")]),
            mat(4, &[("_type", "_glass"), ("_trans", "1")]),
            mat(5, &[("_type", "_metal"), ("_trans", "0.5")]),
            mat(6, &[("_type", "_glass"), ("_trans", "0")]),
            mat(256, &[("_type", "_glass")]),
            mat(0, &[("_type", "_glass")]),
        ]);
        let f = parse(&file(&chunks)).unwrap();
        assert_eq!(f.materials[1], VoxMaterial::Glass(0.75));
        assert_eq!(f.materials[2], VoxMaterial::Glass(0.5));
        assert_eq!(f.materials[3], VoxMaterial::Glass(0.5));
        assert_eq!(f.materials[4], VoxMaterial::Glass(MIN_OPACITY));
        assert_eq!(f.materials[5], VoxMaterial::Opaque);
        assert_eq!(f.materials[6], VoxMaterial::Opaque);
        assert_eq!(f.materials[0], VoxMaterial::Opaque);

        let bad = file(&[mat(1, &[("_type", "_glass"), ("_trans", "lots")])]);
        assert!(matches!(
            parse(&bad),
            Err(VoxError::MaterialValue { index: 1, .. })
        ));
        let bad = file(&[mat(300, &[])]);
        assert!(matches!(
            parse(&bad),
            Err(VoxError::MaterialId { id: 300, .. })
        ));
    }

    #[test]
    fn the_scene_graph_places_groups_translations_and_rotations() {
        // Root -> group -> two transforms: one moved, one turned a quarter about z.
        // Row 0 takes axis 1 (y) negated, row 1 axis 0 (x): rows (-y, x, z).
        let turn_z: u8 = 1 | (1 << 4);
        let chunks = [
            size(3, 1, 1),
            xyzi(&[[0, 0, 0, 1], [2, 0, 0, 2]]),
            trn(0, 1, &[]),
            grp(1, &[2, 4]),
            trn(2, 3, &[("_t", "10 20 30")]),
            shp(3, 0),
            trn(4, 5, &[("_r", &turn_z.to_string())]),
            shp(5, 0),
        ];
        let f = parse(&file(&chunks)).unwrap();
        assert_eq!(f.instances.len(), 2);
        let got: Vec<_> = f.voxels().collect();
        // Moved: centre voxel (1, 0, 0) sits at the translation; MV (9, 20, 30) and
        // (11, 20, 30) become ours (x, z, -y - 1).
        assert_eq!(got[0], ([9, 30, -21], 1));
        assert_eq!(got[1], ([11, 30, -21], 2));
        // Turned: R (x, y, z) = (-y, x, z) on the doubled centres (-1, 1, 1) and (3, 1, 1):
        // (-1, -1, 1) -> MV cell (-1, -1, 0); (-1, 3, 1) -> (-1, 1, 0).
        assert_eq!(got[2], ([-1, 0, 0], 1));
        assert_eq!(got[3], ([-1, 0, -2], 2));
    }

    #[test]
    fn hidden_transforms_and_layers_are_left_out() {
        let mut layr = words(&[1]);
        layr.extend(dict(&[("_hidden", "1")]));
        layr.extend(words(&[u32::MAX]));
        let mut hidden_trn = words(&[4]);
        hidden_trn.extend(dict(&[("_hidden", "1")]));
        hidden_trn.extend(words(&[5, u32::MAX, 0, 1]));
        hidden_trn.extend(dict(&[]));
        let mut in_layer = words(&[6]);
        in_layer.extend(dict(&[]));
        in_layer.extend(words(&[7, u32::MAX, 1, 1]));
        in_layer.extend(dict(&[]));
        let chunks = [
            size(1, 1, 1),
            xyzi(&[[0, 0, 0, 1]]),
            trn(0, 1, &[]),
            grp(1, &[2, 4, 6]),
            trn(2, 3, &[]),
            shp(3, 0),
            chunk(b"nTRN", &hidden_trn, &[]),
            shp(5, 0),
            chunk(b"nTRN", &in_layer, &[]),
            shp(7, 0),
            chunk(b"LAYR", &layr, &[]),
        ];
        let f = parse(&file(&chunks)).unwrap();
        assert_eq!(f.instances.len(), 1);
    }

    #[test]
    fn every_bad_file_row_is_its_error() {
        let e = |bytes: Vec<u8>| parse(&bytes).unwrap_err();
        // Wrong magic, and a file too short for one.
        assert!(matches!(e(b"PNG\x89....".to_vec()), VoxError::Magic(_)));
        assert!(matches!(e(b"VO".to_vec()), VoxError::Magic(_)));
        assert!(matches!(
            e(b"VOX \xc8\0\0\0NOPE\0\0\0\0\0\0\0\0".to_vec()),
            VoxError::NoMain(_)
        ));
        // Truncated: cut anywhere, a good file is an error, never a panic.
        let good = file(&one_voxel());
        for cut in 0..good.len() {
            assert!(parse(&good[..cut]).is_err(), "cut at {cut}");
        }
        assert!(matches!(
            e(good[..good.len() - 2].to_vec()),
            VoxError::ChunkPastEnd { .. }
        ));
        // Chunk sizes past the end, in MAIN and inside it.
        let mut past = good.clone();
        past[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(e(past), VoxError::ChunkPastEnd { ref id, .. } if id == "MAIN"));
        let mut past = good.clone();
        past[24..28].copy_from_slice(&1000u32.to_le_bytes());
        assert!(matches!(e(past), VoxError::ChunkPastEnd { ref id, .. } if id == "SIZE"));
        // Counts larger than the bytes: found before allocating.
        let mut huge = words(&[u32::MAX]);
        huge.extend([0, 0, 0, 1]);
        assert!(matches!(
            e(file(&[size(1, 1, 1), chunk(b"XYZI", &huge, &[])])),
            VoxError::Truncated {
                what: "XYZI voxels",
                ..
            }
        ));
        // Model sizes 0 and above 256.
        for s in [[0, 1, 1], [1, 257, 1], [1, 1, u32::MAX]] {
            assert!(matches!(
                e(file(&[size(s[0], s[1], s[2])])),
                VoxError::ModelSize { model: 0, .. }
            ));
        }
        assert!(parse(&file(&[size(256, 256, 256), xyzi(&[[255, 255, 255, 1]])])).is_ok());
        // Voxels outside the size, or without one.
        assert!(matches!(
            e(file(&[size(2, 2, 2), xyzi(&[[2, 0, 0, 1]])])),
            VoxError::VoxelOutside { x: 2, .. }
        ));
        assert!(matches!(
            e(file(&[xyzi(&[[0, 0, 0, 1]])])),
            VoxError::VoxelsWithoutSize(_)
        ));
        // Palette indices out of range: 0, and past a short palette.
        assert!(matches!(
            e(file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 0]])])),
            VoxError::PaletteIndex { index: 0, .. }
        ));
        let short = chunk(b"RGBA", &[255; 16], &[]);
        assert!(matches!(
            e(file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 5]]), short.clone()])),
            VoxError::PaletteIndex {
                index: 5,
                len: 4,
                ..
            }
        ));
        assert!(parse(&file(&[size(1, 1, 1), xyzi(&[[0, 0, 0, 4]]), short])).is_ok());
        assert!(matches!(
            e(file(&[chunk(b"RGBA", &[1, 2, 3], &[])])),
            VoxError::Palette { size: 3, .. }
        ));
        // Scene graphs: a cycle, a missing node, a missing model, a shared node, no root.
        let m = one_voxel();
        let graph = |nodes: Vec<Vec<u8>>| file(&[m.clone(), nodes].concat());
        assert!(matches!(
            e(graph(vec![trn(0, 1, &[]), grp(1, &[2]), trn(2, 1, &[])])),
            VoxError::Cycle(1)
        ));
        assert!(matches!(
            e(graph(vec![trn(0, 1, &[]), grp(1, &[2, 9])])),
            VoxError::MissingNode {
                from: 1,
                missing: 2
            }
        ));
        assert!(matches!(
            e(graph(vec![trn(0, 1, &[]), shp(1, 3)])),
            VoxError::MissingModel {
                model: 3,
                count: 1,
                ..
            }
        ));
        assert!(matches!(
            e(graph(vec![
                trn(0, 1, &[]),
                grp(1, &[2, 2]),
                trn(2, 3, &[]),
                shp(3, 0)
            ])),
            VoxError::SharedNode(2)
        ));
        assert!(matches!(
            e(graph(vec![grp(1, &[])])),
            VoxError::MissingNode {
                from: -1,
                missing: 0
            }
        ));
        assert!(matches!(
            e(graph(vec![trn(0, 1, &[]), grp(1, &[]), grp(1, &[])])),
            VoxError::DuplicateNode(1)
        ));
        // Bad rotations and translations.
        for r in ["3", "15", "128", "-1", "x"] {
            assert!(
                matches!(
                    e(graph(vec![trn(0, 1, &[("_r", r)]), shp(1, 0)])),
                    VoxError::Rotation { node: 0, .. }
                ),
                "{r}"
            );
        }
        for t in ["1 2", "1 2 3 4", "a b c", "99999999999 0 0"] {
            assert!(
                matches!(
                    e(graph(vec![trn(0, 1, &[("_t", t)]), shp(1, 0)])),
                    VoxError::Translation { node: 0, .. }
                ),
                "{t}"
            );
        }
        // Placed too far, and deep chains of far translations.
        let far = i32::MAX.to_string();
        let t = format!("{far} 0 0");
        assert!(matches!(
            e(graph(vec![trn(0, 1, &[("_t", &t)]), shp(1, 0)])),
            VoxError::OutsideWorld(_)
        ));
        let mut chain = Vec::new();
        for i in 0..600u32 {
            chain.push(trn(2 * i, 2 * i + 1, &[("_t", &t)]));
            chain.push(grp(2 * i + 1, &[2 * i + 2]));
        }
        chain.push(trn(1200, 1201, &[]));
        chain.push(shp(1201, 0));
        assert!(matches!(e(graph(chain)), VoxError::OutsideWorld(_)));
        // Too many voxels: a model placed over and over.
        let many: Vec<u32> = (0..100).map(|i| 2 + 2 * i).collect();
        let mut nodes = vec![trn(0, 1, &[]), grp(1, &many)];
        for &n in &many {
            nodes.push(trn(n, n + 1, &[]));
            nodes.push(shp(n + 1, 0));
        }
        let bytes = graph(nodes);
        assert!(matches!(
            VoxFile::parse(&bytes, 99),
            Err(VoxError::TooManyVoxels {
                count: 100,
                max: 99
            })
        ));
        assert!(VoxFile::parse(&bytes, 100).is_ok());
    }

    #[test]
    fn deep_nesting_is_no_stack_overflow() {
        // 100 000 nested chunks (dot_vox would recurse into each): children of chunks
        // other than MAIN are skipped, not read.
        let leaf = chunk(b"SIZE", &words(&[1, 1, 1]), &[]);
        let depth = 100_000;
        let mut nested = Vec::with_capacity(depth * 12 + leaf.len());
        for level in 0..depth {
            nested.extend(b"NEST");
            nested.extend(words(&[0, ((depth - 1 - level) * 12 + leaf.len()) as u32]));
        }
        nested.extend(&leaf);
        let f = parse(&file(&[nested])).unwrap();
        assert!(f.models.is_empty());
        // A chain of 100 000 transforms and groups: walked with a stack of our own.
        let mut nodes = one_voxel();
        for i in 0..50_000u32 {
            nodes.push(trn(2 * i, 2 * i + 1, &[]));
            nodes.push(grp(2 * i + 1, &[2 * i + 2]));
        }
        nodes.push(trn(100_000, 100_001, &[]));
        nodes.push(shp(100_001, 0));
        assert_eq!(parse(&file(&nodes)).unwrap().instances.len(), 1);
    }

    #[test]
    fn blocks_are_registered_once_per_used_index_and_placed_turned() {
        let mut chunks = vec![size(3, 1, 2), xyzi(&[[0, 0, 0, 7], [2, 0, 1, 9]])];
        let mut c = words(&[9]);
        c.extend(dict(&[("_type", "_glass"), ("_trans", "0.6")]));
        chunks.push(chunk(b"MATL", &c, &[]));
        let f = parse(&file(&chunks)).unwrap();
        let mut registry = BlockRegistry::default();
        let blocks = f.register_blocks("m", &[], &mut registry).unwrap();
        assert_eq!(registry.len(), 15);
        let (a, b) = (blocks.ids[7], blocks.ids[9]);
        assert_eq!(registry.get(a).unwrap().name, "m#7");
        assert_eq!(registry.get(a).unwrap().class, RenderClass::Opaque);
        let glass = registry.get(b).unwrap();
        assert_eq!(
            (glass.name.as_str(), glass.class),
            ("m glass #9", RenderClass::Translucent)
        );
        assert!((glass.opacity - 0.4).abs() < 1e-6);
        assert_eq!(
            glass.pattern,
            Pattern::Framed,
            "glass is framed by its field"
        );
        assert_eq!(registry.get(a).unwrap().pattern, Pattern::Noise);
        // Again: the same types. With an override: a new name for the changed one.
        assert_eq!(f.register_blocks("m", &[], &mut registry).unwrap(), blocks);
        let water = PaletteOverride {
            index: 7,
            class: RenderClass::Translucent,
            opacity: 0.6,
        };
        let again = f.register_blocks("m", &[water], &mut registry).unwrap();
        assert_eq!(registry.get(again.ids[7]).unwrap().name, "m#7~2");
        assert_eq!(again.ids[9], b);
        // Overrides the registry refuses, and index 0.
        let bad = PaletteOverride {
            opacity: 1.0,
            ..water
        };
        assert!(f.register_blocks("n", &[bad], &mut registry).is_err());
        let zero = PaletteOverride { index: 0, ..water };
        assert!(f.register_blocks("n", &[zero], &mut registry).is_err());

        // MV voxels (0,0,0) and (2,0,1) of a 3x1x2 model: ours (-1,0,0) and (1,1,0); the box
        // x -1..1, y 0..1, z 0..0. One quarter turn: (x, z) -> (z, -x - 1).
        let mut world = World::new(std::sync::Arc::new(registry));
        let placed = f
            .place(
                "m",
                &blocks,
                VoxPlacement {
                    at: [10, 20, 30],
                    quarter_turns: 1,
                },
                &mut world,
            )
            .unwrap();
        // Turned: (-1,0,0) -> (0,0,0), (1,1,0) -> (0,1,-2); box z -2..0 -> moved to 30.
        assert_eq!(
            placed,
            Some((WorldPos::new(10, 20, 30), WorldPos::new(10, 21, 32)))
        );
        assert_eq!(world.get_block(WorldPos::new(10, 20, 32)), a);
        assert_eq!(world.get_block(WorldPos::new(10, 21, 30)), b);
        let far = VoxPlacement {
            at: [i32::MAX, 0, 0],
            quarter_turns: 0,
        };
        assert!(matches!(
            f.place("m", &blocks, far, &mut world),
            Err(Error::Vox {
                error: VoxError::OutsideWorld(_),
                ..
            })
        ));
    }
}
