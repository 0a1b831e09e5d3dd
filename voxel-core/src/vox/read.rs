//! The bounded reader of the format: the header, the chunks, models, palette and
//! materials. Every length is checked against the bytes that remain before anything is
//! allocated.

use std::collections::HashMap;
use std::path::Path;

use super::bytes::Reader;
use super::scene::{Node, flatten, hidden, transform_node};
use super::{
    DEFAULT_MAX_VOXELS, MAX_EXTENT, MAX_FILE_BYTES, MAX_MODEL_SIDE, MIN_OPACITY, VoxError, VoxFile,
    VoxInstance, VoxMaterial, VoxModel, VoxRotation,
};
use crate::{Error, Result};

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
