//! Reading a scene file: its limits, errors with line numbers, palettes, and building the
//! world and cameras it describes.

use crate::{Error, Result};

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use toml::Spanned;
use voxel_core::{
    BlockRegistry, ChunkPos, PaletteOverride, RenderClass, TerrainConfig, TerrainGenerator,
    VoxFile, VoxPlacement, World, WorldPos,
};
use voxel_render::Camera;

use super::blocks::{block_def, class_named};
use super::content::content_of;
use super::fields::at_line;
use super::format::{BoxDef, PaletteDef, SceneFile};
use super::{Scene, fill_box, framing_camera, model_name};

/// Most chunks a scene's terrain may generate (64 × 8 × 64 = 32768 chunks would not fit in
/// memory: this keeps a typo from taking the machine down).
const MAX_TERRAIN_CHUNKS: i128 = 4096;
/// Most blocks all boxes together may fill.
const MAX_BOX_BLOCKS: i128 = 20_000_000;
/// Most chunks all boxes together may touch (a box counts every chunk its corners span):
/// a thin row of blocks touches a chunk per 32 blocks, and a chunk holding part of a box
/// costs up to about 40 KiB, so 20 M blocks in a row (625 000 chunks) would take tens of
/// GiB. 16 384 chunks hold a 4096 × 4096 floor.
const MAX_BOX_CHUNKS: i128 = 16_384;

/// The `table.key` written on the line holding byte `at` (the key before `=`, the table
/// from the nearest header above), for error messages.
fn field_at(text: &str, at: usize) -> String {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next().unwrap_or("");
    let header = |l: &str| l.trim().starts_with('[');
    // On a table's own header (a table missing a field): that table, no key.
    let key = if header(line) {
        ""
    } else {
        line.split_once('=').map(|(k, _)| k.trim()).unwrap_or("")
    };
    let table = text[..start + line.len()]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| header(l))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']'))
        .unwrap_or("");
    match (table, key) {
        ("", k) | (k, "") => k.to_owned(),
        (t, k) => format!("{t}.{k}"),
    }
}

/// Parses the text of a scene file; errors read `LINE: field: message`. Model files are
/// found relative to the working folder; [`parse_in`] names another.
pub fn parse(text: &str) -> Result<Scene> {
    parse_in(text, Path::new(""))
}

/// What a `[[models.palette]]` entry asks for, checked.
fn palette_override(text: &str, p: &Spanned<PaletteDef>) -> Result<PaletteOverride> {
    let d = p.get_ref();
    let index = u8::try_from(*d.index.get_ref())
        .ok()
        .filter(|i| *i >= 1)
        .ok_or_else(|| {
            at_line(
                text,
                d.index.span().start,
                format!(
                    "models.palette.index: {} is not a colour index (1 to 255)",
                    d.index.get_ref()
                ),
            )
        })?;
    let class = class_named(d.class.get_ref()).ok_or_else(|| {
        at_line(
            text,
            d.class.span().start,
            format!(
                "models.palette.class: {:?} is not a class: opaque, cutout or translucent",
                d.class.get_ref()
            ),
        )
    })?;
    let opacity = match (class, d.opacity) {
        (RenderClass::Translucent, Some(a)) if a.is_finite() && a > 0.0 && a < 1.0 => a,
        (RenderClass::Translucent, _) => {
            return Err(at_line(
                text,
                p.span().start,
                "models.palette.opacity: a translucent entry needs an opacity above 0 and below 1",
            ));
        }
        (_, None) => 1.0,
        (_, Some(1.0)) => 1.0,
        (_, Some(_)) => {
            return Err(at_line(
                text,
                p.span().start,
                "models.palette.opacity: only a translucent entry has an opacity below 1",
            ));
        }
    };
    Ok(PaletteOverride {
        index,
        class,
        opacity,
    })
}

/// [`parse`], with model files found relative to `dir` (the scene file's folder).
pub fn parse_in(text: &str, dir: &Path) -> Result<Scene> {
    let file: SceneFile = toml::from_str(text).map_err(|e| match e.span() {
        Some(s) => {
            let field = field_at(text, s.start);
            let message = e.message().trim();
            if field.is_empty() {
                at_line(text, s.start, message)
            } else {
                at_line(text, s.start, format!("{field}: {message}"))
            }
        }
        None => Error::scene(None, e.message().trim()),
    })?;

    let mut registry = if file.light {
        BlockRegistry::with_lights()
    } else {
        BlockRegistry::default()
    };
    for b in &file.blocks {
        let def = block_def(text, dir, b, &registry)?;
        registry
            .register(def)
            .map_err(|e| at_line(text, b.span().start, format!("blocks: {e}")))?;
    }
    // Models are read (and their block types registered) before the world exists: the
    // world's registry is fixed once it is made.
    let mut models = Vec::new();
    let mut voxels: i128 = 0;
    for m in &file.models {
        let (span, def) = (m.span(), m.get_ref());
        let path = dir.join(def.file.get_ref());
        let line = def.file.span().start;
        let vox =
            VoxFile::load(&path).map_err(|e| at_line(text, line, format!("models.file: {e}")))?;
        voxels += i128::from(vox.voxel_count());
        if voxels > MAX_BOX_BLOCKS {
            return Err(at_line(
                text,
                span.start,
                format!("models: more than {MAX_BOX_BLOCKS} voxels in all"),
            ));
        }
        let turns = match &def.rotate {
            None => 0,
            Some(r) if r.get_ref().rem_euclid(90) == 0 => (r.get_ref().rem_euclid(360) / 90) as u8,
            Some(r) => {
                return Err(at_line(
                    text,
                    r.span().start,
                    format!(
                        "models.rotate: {} is not a multiple of 90 degrees",
                        r.get_ref()
                    ),
                ));
            }
        };
        let overrides = def
            .palette
            .iter()
            .map(|p| palette_override(text, p))
            .collect::<Result<Vec<_>, _>>()?;
        let name = model_name(&path);
        let blocks = vox
            .register_blocks(&name, &overrides, &mut registry)
            .map_err(|e| at_line(text, span.start, format!("models: {}: {e}", path.display())))?;
        let placement = VoxPlacement {
            at: def.at,
            quarter_turns: turns,
        };
        models.push((span.start, path, vox, blocks, placement));
    }
    let registry = Arc::new(registry);
    let mut world = match &file.terrain {
        Some(t) => {
            let (span, t) = (t.span(), t.get_ref());
            // i128: three extents of up to 2^32 each cannot overflow it.
            let count: i128 = (0..3)
                .map(|i| i128::from(t.max_chunk[i]) - i128::from(t.min_chunk[i]) + 1)
                .product();
            if (0..3).any(|i| t.min_chunk[i] > t.max_chunk[i]) || count > MAX_TERRAIN_CHUNKS {
                return Err(at_line(
                    text,
                    span.start,
                    format!(
                        "terrain: min_chunk..max_chunk must be a non-empty box of at most {MAX_TERRAIN_CHUNKS} chunks"
                    ),
                ));
            }
            let generator = TerrainGenerator::new(TerrainConfig {
                seed: t.seed,
                ..TerrainConfig::default()
            });
            let min = ChunkPos::new(t.min_chunk[0], t.min_chunk[1], t.min_chunk[2]);
            let max = ChunkPos::new(t.max_chunk[0], t.max_chunk[1], t.max_chunk[2]);
            generator
                .generate_world(registry.clone(), min, max)
                .map_err(|e| at_line(text, span.start, format!("terrain: {e}")))?
        }
        None => World::new(registry.clone()),
    };
    let mut filled: i128 = 0;
    // Boxes and models in the order the file lists them.
    enum Item<'a> {
        Box(&'a Spanned<BoxDef>),
        Model(usize),
    }
    let mut items: Vec<(usize, Item<'_>)> = file
        .boxes
        .iter()
        .map(|b| (b.span().start, Item::Box(b)))
        .chain(
            models
                .iter()
                .enumerate()
                .map(|(i, m)| (m.0, Item::Model(i))),
        )
        .collect();
    items.sort_by_key(|(at, _)| *at);
    let mut model_bounds: Option<(WorldPos, WorldPos)> = None;
    // Chunks the boxes and models touch, bounded like the blocks they fill.
    let mut touched: i128 = 0;
    let chunks_between = |lo: [i32; 3], hi: [i32; 3]| {
        let chunk = |v: i32| i128::from(v.div_euclid(voxel_core::CHUNK_SIZE as i32));
        (0..3)
            .map(|i| chunk(hi[i]) - chunk(lo[i]) + 1)
            .product::<i128>()
    };
    for (_, item) in items {
        let b = match item {
            Item::Box(b) => b,
            Item::Model(i) => {
                let (at, path, vox, blocks, placement) = &models[i];
                let placed = vox
                    .place(&path.display().to_string(), blocks, *placement, &mut world)
                    .map_err(|e| at_line(text, *at, format!("models: {e}")))?;
                if let Some((lo, hi)) = placed {
                    touched += chunks_between([lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]);
                    if touched > MAX_BOX_CHUNKS {
                        return Err(at_line(
                            text,
                            *at,
                            format!(
                                "models: boxes and models touch more than {MAX_BOX_CHUNKS} chunks in all"
                            ),
                        ));
                    }
                    let (mut a, mut b) = model_bounds.unwrap_or((lo, hi));
                    (a.x, a.y, a.z) = (a.x.min(lo.x), a.y.min(lo.y), a.z.min(lo.z));
                    (b.x, b.y, b.z) = (b.x.max(hi.x), b.y.max(hi.y), b.z.max(hi.z));
                    model_bounds = Some((a, b));
                }
                continue;
            }
        };
        let (span, def) = (b.span(), b.get_ref());
        let id = registry
            .id(def.block.get_ref())
            .map_err(|e| at_line(text, def.block.span().start, format!("boxes.block: {e}")))?;
        if (0..3).any(|i| def.min[i] > def.max[i]) {
            return Err(at_line(
                text,
                span.start,
                "boxes: min must not exceed max on any axis",
            ));
        }
        filled += (0..3)
            .map(|i| i128::from(def.max[i]) - i128::from(def.min[i]) + 1)
            .product::<i128>();
        if filled > MAX_BOX_BLOCKS {
            return Err(at_line(
                text,
                span.start,
                format!("boxes: more than {MAX_BOX_BLOCKS} blocks in all"),
            ));
        }
        touched += chunks_between(def.min, def.max);
        if touched > MAX_BOX_CHUNKS {
            return Err(at_line(
                text,
                span.start,
                format!("boxes: they touch more than {MAX_BOX_CHUNKS} chunks in all"),
            ));
        }
        fill_box(&mut world, def.min, def.max, id)
            .map_err(|e| at_line(text, span.start, format!("boxes: {e}")))?;
    }
    let mut cameras = Vec::new();
    let mut paths = Vec::new();
    if file.cameras.is_empty() {
        let (lo, hi) = model_bounds.ok_or_else(|| {
            Error::scene(
                Some(1),
                "cameras: a scene needs at least one [[cameras]] entry (or a model)",
            )
        })?;
        let (camera, path_to) = framing_camera(lo, hi)?;
        cameras.push(camera.in_medium(world.medium_at(camera.eye.to_array())));
        paths.push(Some(path_to));
    }
    for c in &file.cameras {
        let (span, d) = (c.span(), c.get_ref());
        let camera = Camera::look_at(
            DVec3::from(d.eye),
            DVec3::from(d.target),
            d.fov,
            d.near,
            d.far,
        )
        .map_err(|e| at_line(text, span.start, format!("cameras: {e}")))?;
        // The flicker test moves the eye to `path_to`: the camera there must be valid too,
        // so that every command accepts or refuses the same files.
        if let Some(to) = d.path_to {
            Camera::look_at(DVec3::from(to), DVec3::from(d.target), d.fov, d.near, d.far)
                .map_err(|e| at_line(text, span.start, format!("cameras.path_to: {e}")))?;
        }
        cameras.push(camera.in_medium(world.medium_at(d.eye)));
        paths.push(d.path_to.map(DVec3::from));
    }
    let size = match &file.size {
        Some(s) => {
            let &[w, h] = s.get_ref().as_slice() else {
                return Err(at_line(
                    text,
                    s.span().start,
                    format!(
                        "size: {} values, expected 2 (width and height)",
                        s.get_ref().len()
                    ),
                ));
            };
            let size = (w, h);
            crate::limits::check_size("size", size)
                .map_err(|e| at_line(text, s.span().start, e))?;
            Some(size)
        }
        None => None,
    };
    let content = content_of(text, &file)?;
    Ok(Scene {
        name: file.name,
        description: file.description,
        world,
        cameras,
        paths,
        size,
        content,
        light: file.light,
        sun_shadows: file.sun_shadows,
    })
}
