//! Block types a scene file declares: their class, pattern, textures and medium.

use crate::Result;

use std::path::Path;

use serde::Deserialize;
use toml::Spanned;
use voxel_core::{BlockDef, BlockImage, BlockRegistry, FaceImages, Pattern, RenderClass};

use super::fields::{at_line, exact, exact_opt};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BlockDefFile {
    name: String,
    #[serde(deserialize_with = "exact")]
    color: [u8; 3],
    opacity: f32,
    /// `opaque`, `cutout` or `translucent`; by default from the opacity.
    class: Option<Spanned<String>>,
    /// `noise`, `leaves`, `framed` or `grass`; by default the class's.
    pattern: Option<Spanned<String>>,
    /// The soil colour of the `grass` pattern.
    #[serde(default, deserialize_with = "exact_opt")]
    soil: Option<[u8; 3]>,
    /// A translucent block's absorption per block: a volume (0, the default: a thin
    /// surface).
    absorption: Option<Spanned<f32>>,
    /// A cutout block standing in this medium (a translucent block named before it).
    medium: Option<Spanned<String>>,
    /// A PNG file for every face, relative to the scene file.
    texture: Option<Spanned<String>>,
    /// PNG files for the top, bottom and side faces (over `texture`).
    top: Option<Spanned<String>>,
    bottom: Option<Spanned<String>>,
    side: Option<Spanned<String>>,
}

/// A render class by its scene-file name.
pub(super) fn class_named(name: &str) -> Option<RenderClass> {
    match name {
        "opaque" => Some(RenderClass::Opaque),
        "cutout" => Some(RenderClass::Cutout),
        "translucent" => Some(RenderClass::Translucent),
        _ => None,
    }
}

/// The block a `[[blocks]]` entry declares: class, pattern and images checked, images read
/// relative to `dir`. Errors read `LINE: blocks.key: message`.
pub(super) fn block_def(
    text: &str,
    dir: &Path,
    b: &Spanned<BlockDefFile>,
    registry: &BlockRegistry,
) -> Result<BlockDef> {
    let d = b.get_ref();
    let mut def = BlockDef::new(d.name.clone(), d.color, d.opacity);
    if let Some(a) = &d.absorption {
        def = def.with_absorption(*a.get_ref());
    }
    if let Some(m) = &d.medium {
        let id = registry.id(m.get_ref()).map_err(|_| {
            at_line(
                text,
                m.span().start,
                format!(
                    "blocks.medium: no block {:?} before this one (a medium is a translucent block)",
                    m.get_ref()
                ),
            )
        })?;
        def = def.in_medium(id);
    }
    if let Some(class) = &d.class {
        def.class = class_named(class.get_ref()).ok_or_else(|| {
            at_line(
                text,
                class.span().start,
                format!(
                    "blocks.class: {:?} is not a class: opaque, cutout or translucent",
                    class.get_ref()
                ),
            )
        })?;
        if def.class == RenderClass::Cutout {
            def.pattern = Pattern::Leaves;
        }
    }
    if let Some(pattern) = &d.pattern {
        let at = pattern.span().start;
        def.pattern = match pattern.get_ref().as_str() {
            "noise" => Pattern::Noise,
            "leaves" => Pattern::Leaves,
            "framed" => Pattern::Framed,
            "grass" => Pattern::Grass {
                soil: d.soil.ok_or_else(|| {
                    at_line(
                        text,
                        at,
                        "blocks.pattern: \"grass\" needs a soil = [r, g, b] colour",
                    )
                })?,
            },
            other => {
                return Err(at_line(
                    text,
                    at,
                    format!(
                        "blocks.pattern: {other:?} is not a pattern: noise, leaves, framed or grass"
                    ),
                ));
            }
        };
    }
    let image = |key: &str, file: &Option<Spanned<String>>| -> Result<Option<BlockImage>> {
        let Some(file) = file else { return Ok(None) };
        voxel_render::textures::load_block_image(&dir.join(file.get_ref()))
            .map(Some)
            .map_err(|e| at_line(text, file.span().start, format!("blocks.{key}: {e}")))
    };
    let all = image("texture", &d.texture)?;
    def.images = FaceImages {
        top: image("top", &d.top)?.or_else(|| all.clone()),
        bottom: image("bottom", &d.bottom)?.or_else(|| all.clone()),
        side: image("side", &d.side)?.or(all),
    };
    Ok(def)
}
