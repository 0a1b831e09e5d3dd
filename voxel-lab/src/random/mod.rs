//! Random scenes: the lab on scenes nobody wrote.
//!
//! [`generate`] turns a seed and an index into the **text of a scene file** (the format of
//! [`scene`](super::scene)) and the [`Features`] it was built with. The lab parses every random
//! scene from that text with the same parser as a scene file, so writing a scene's text to
//! a `.toml` file replays it exactly (`demo eval --scenes worst/sorted-quads.toml`).
//!
//! Determinism: the generator uses its own [`SplitMix64`], integer arithmetic and only
//! correctly rounded float operations (`+ - * /`, `sqrt`, `round`, `floor`: no `sin`,
//! `ln` or `powf`, whose last bit may differ between C libraries), and every coordinate it
//! writes is a multiple of 1/128 printed exactly. So the same seed and index give the same
//! text on every machine, and scene `i` of a seed does not depend on how many are drawn.
//!
//! # What a scene holds
//!
//! The particles and entities (a game's content, drawn through the renderer's stages) come
//! from a second stream of the same seed and index, drawn after the camera: the blocks and
//! the camera of a scene are what they were before the generator had content.
//!
//! Everything lies in a local box of about 48³ blocks (a stack may run up to 192 blocks
//! along its axis), moved by a random offset of −48 to 16 blocks per axis so that negative
//! coordinates and chunk borders occur. Each part is drawn independently, with the
//! designed probability:
//!
//! | part | probability | what |
//! |---|---|---|
//! | extra block types | 0.5 | 1–3 translucent types with a random colour and opacity 0.05–0.98, declared in `[[blocks]]` (only those used) |
//! | opaque ground | 0.45 | a 48 × 48 slab of stone, dirt, grass or sand under everything |
//! | random boxes | always, 2–7 | translucent (60 %), opaque (20 %) or cutout leaves (20 %); thin sheets (40 %), solid volumes 2–12 (35 %), small blocks 1–3 (25 %) |
//! | a stack | 0.35 | 2–8 (half), 9–24 (30 %) or 25–64 (20 %) parallel sheets along a random axis, 2–4 types in turn, 1 to 3 blocks apart (1: touching, so every boundary is a layer) |
//! | a large surface with small objects | 0.3 | a 24–48 wide slab, translucent (70 %) or opaque, 3–12 small objects on it, sunk into it or under it |
//! | a glass floor and/or ceiling | 0.3 | a translucent sheet 20–48 wide below and/or above the eye, with objects beyond it |
//! | leaves | 0.15 more | a leaf box if none was drawn above (72 % of scenes end up with cutout blocks) |
//! | a game's particles | 0.35 | 100–1000 (60 %) or 1000–5000 camera-facing squares, 0.04–0.4 blocks across, opacity 0.1–0.9, one random colour, in a box around the target up to 0.3 of its distance (at most 12 blocks) across |
//! | a game's entities | 0.3 | 1–3 boxes 0.5–4 blocks on a side, turned any way, near the target: opaque (30 %) or translucent (opacity 0.1–0.95); none around the eye |
//!
//! The camera (an aimed eye is never inside an opaque or cutout block, and sees its target
//! without an opaque block between them whenever one of 40 tries finds such a place):
//!
//! | camera | probability | what |
//! |---|---|---|
//! | eye inside a translucent volume | 0.2 | inside a volume of the scene (a water box engulfing part of the scene is added if there is none); the scene's camera then gets that block as its medium |
//! | grazing | 0.15 | 0–0.6 blocks above (or below) a large translucent surface, looking across it 0.3°–4.6° down (or up) |
//! | aimed | 0.65 | at a stack (along its axis 70 % of the time), through a floor or ceiling, or at any translucent box, from 1.5 to 40 blocks; 10 % of aimed views are distant telephoto views (200–2000 blocks, field of view 0.5°–20° fitted to the target) |
//! | eye on a face plane | 0.2, any mode | one coordinate of the eye set exactly to the integer plane of a face of a translucent box |
//! | near plane | always | log-uniform from 0.01 to 1 |
//! | far plane | always | 64–400 (half), 400–2000 (30 %), 2000–5000 (20 %); 8 % of close views put it just behind the target, cutting through the scene |
//! | field of view | always | 35°–100° (80 %), 110°–170° (10 %), 10°–34° (10 %), telephoto as above |
//!
//! What comes out, measured over scenes 0..10 000 of seed 1 ([`Features::flags`]; the unit
//! test `feature_shares_match_the_design` checks the main ones against the design):
//!
//! | feature | share |
//! |---|---|
//! | a stack of 2–8 / 9–24 / 25–64 layers | 18.0 % / 10.2 % / 6.8 % |
//! | stacked sheets touching (no gaps) | 11.8 % |
//! | the eye inside a translucent volume | 27.7 % (aimed views land in volumes too) |
//! | the eye exactly on a face plane | 21.2 % |
//! | a grazing view along a surface | 14.6 % |
//! | a distant telephoto view | 4.8 % |
//! | a near plane below 0.05 | 22.6 % |
//! | a far plane beyond 1000 | 38.0 % |
//! | the far plane cutting through the scene | 7.5 % |
//! | a wide field of view (over 110°) | 9.1 % |
//! | extra block types | 51.2 % |
//! | a nearly clear type (opacity below 0.15) | 9.3 % |
//! | a nearly opaque type (opacity above 0.9; ice is 0.92) | 58.2 % |
//! | 4+ translucent types | 66.7 % |
//! | a large surface with small objects | 30.6 % |
//! | a glass floor or ceiling | 29.7 % |
//! | cutout blocks (leaves) | 71.8 % |
//! | opaque blocks | 86.9 % |
//! | thin translucent sheets | 87.0 % |
//! | solid translucent volumes | 70.0 % |
//! | a game's particles | 35.4 % |
//! | a game's translucent entity | 24.3 % |
//! | a game's opaque entity | 13.8 % |
//!
//! `demo eval --random` reports the same shares for the scenes it drew, and the share of
//! scenes where the reference equals `opaque-only` (nothing translucent in view: the aim
//! failed; 7.5 % of the first 200 scenes of seed 1).
//!
//! # Layout
//!
//! - `rng`: the [`SplitMix64`] generator.
//! - `boxes`: the generator's state (the boxes placed so far, the translucent types to
//!   draw from), the queries on it and the features measured on the final boxes.
//! - `parts`: the blocks of a scene (ground, random boxes, a large surface, a floor or
//!   ceiling, a stack, the extra types).
//! - `camera`: the camera (inside a volume, grazing, aimed; a face plane, the near and
//!   far planes, the field of view).
//! - `content`: a game's particles and entities.
//! - here: the set of scenes, the [`Features`] and [`generate`], which writes the text.

use crate::{Error, Result};

mod boxes;
mod camera;
mod content;
mod parts;
mod rng;

#[cfg(test)]
mod tests;

use serde::Serialize;
use voxel_core::{BlockRegistry, RenderClass};

pub use rng::SplitMix64;

use boxes::{Gen, add};
use content::content;

/// Most scenes one run may draw. A scene takes about a second at small sizes on lavapipe
/// (every technique, the weights and both exact methods), so 100 000 scenes already take
/// more than a day; and the run keeps every record (16 per scene, a few hundred bytes
/// each) in memory and in `summary.json`, which at this count is about half a gigabyte.
pub const MAX_SCENES: usize = 100_000;

/// A set of random scenes: `count` scenes from `seed`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct RandomSet {
    /// How many scenes.
    pub count: usize,
    /// The seed.
    pub seed: u64,
}

impl RandomSet {
    /// `count` scenes from `seed`; `count` must be 1 to [`MAX_SCENES`].
    pub fn new(count: usize, seed: u64) -> Result<Self> {
        if count == 0 {
            return Err(Error::NoRandomScenes);
        }
        if count > MAX_SCENES {
            return Err(too_many(&count.to_string()));
        }
        Ok(Self { count, seed })
    }

    /// Name of scene `index`: `random-SEED-INDEX`.
    pub fn name(&self, index: usize) -> String {
        scene_name(self.seed, index)
    }

    /// Scene `index` at output size `size`.
    pub fn scene(&self, index: usize, size: (u32, u32)) -> RandomScene {
        generate(self.seed, index, size)
    }
}

/// The error for a count above [`MAX_SCENES`], written as the user wrote it.
pub fn too_many(count: &str) -> Error {
    Error::TooManyRandomScenes {
        count: count.to_owned(),
        max: MAX_SCENES,
    }
}

/// Name of scene `index` of `seed`.
pub fn scene_name(seed: u64, index: usize) -> String {
    format!("random-{seed}-{index}")
}

/// A generated scene: its file text and what it was built with.
#[derive(Clone, Debug)]
pub struct RandomScene {
    /// `random-SEED-INDEX`.
    pub name: String,
    /// The scene file (TOML), parsed by [`parse`](super::scene::parse).
    pub text: String,
    /// What it holds.
    pub features: Features,
}

/// What a random scene holds, for finding where a technique fails.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Features {
    /// Boxes in the scene file.
    pub boxes: u32,
    /// Sheets of the stack (0: no stack).
    pub stack_layers: u32,
    /// Distance between the stack's sheets (1: touching).
    pub stack_spacing: u32,
    /// Different translucent block types in the scene.
    pub translucent_types: u32,
    /// Extra block types declared (and used).
    pub extra_types: u32,
    /// Lowest opacity of the translucent types used.
    pub min_opacity: f32,
    /// Highest opacity of the translucent types used.
    pub max_opacity: f32,
    /// Translucent sheets one block thick (stack sheets included).
    pub thin_sheets: bool,
    /// Translucent volumes at least 2 blocks thick on every axis.
    pub solid_volumes: bool,
    /// Opaque blocks.
    pub opaque: bool,
    /// Cutout blocks (leaves).
    pub cutout: bool,
    /// A large slab with small objects on, in or under it.
    pub large_surface: bool,
    /// A translucent floor below the eye.
    pub glass_floor: bool,
    /// A translucent ceiling above the eye.
    pub glass_ceiling: bool,
    /// The eye inside a translucent block (the camera's medium).
    pub eye_inside: bool,
    /// An eye coordinate exactly on the plane of a translucent box's face.
    pub eye_on_plane: bool,
    /// A view along a large surface at a grazing angle.
    pub grazing: bool,
    /// A telephoto view from 200–2000 blocks away.
    pub distant: bool,
    /// The far plane just behind the target, cutting through the scene.
    pub far_cuts: bool,
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance.
    pub far: f64,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// Distance from the eye to the point it looks at.
    pub distance: f64,
    /// A game's particles around the target (0: none).
    pub particles: u32,
    /// A game's translucent box entities, turned any way.
    pub translucent_entities: u32,
    /// A game's opaque box entities.
    pub opaque_entities: u32,
}

impl Features {
    /// Every yes/no feature the reports count, in plain words.
    pub fn flags(&self) -> Vec<(&'static str, bool)> {
        vec![
            (
                "a stack of 2–8 layers",
                (2..=8).contains(&self.stack_layers),
            ),
            (
                "a stack of 9–24 layers",
                (9..=24).contains(&self.stack_layers),
            ),
            (
                "a stack of 25–64 layers",
                (25..=64).contains(&self.stack_layers),
            ),
            (
                "stacked sheets touching (no gaps)",
                self.stack_layers > 0 && self.stack_spacing == 1,
            ),
            ("the eye inside a translucent volume", self.eye_inside),
            ("the eye exactly on a face plane", self.eye_on_plane),
            ("a grazing view along a surface", self.grazing),
            ("a distant telephoto view", self.distant),
            ("a near plane below 0.05", self.near < 0.05),
            ("a far plane beyond 1000", self.far > 1000.0),
            ("the far plane cutting through the scene", self.far_cuts),
            ("a wide field of view (over 110°)", self.fov > 110.0),
            ("extra block types", self.extra_types > 0),
            (
                "a nearly clear type (opacity below 0.15)",
                self.min_opacity < 0.15,
            ),
            (
                "a nearly opaque type (opacity above 0.9)",
                self.max_opacity > 0.9,
            ),
            ("4+ translucent types", self.translucent_types >= 4),
            ("a large surface with small objects", self.large_surface),
            (
                "a glass floor or ceiling",
                self.glass_floor || self.glass_ceiling,
            ),
            ("cutout blocks (leaves)", self.cutout),
            ("opaque blocks", self.opaque),
            ("thin translucent sheets", self.thin_sheets),
            ("solid translucent volumes", self.solid_volumes),
            ("a game's particles", self.particles > 0),
            ("a game's translucent entity", self.translucent_entities > 0),
            ("a game's opaque entity", self.opaque_entities > 0),
        ]
    }
}

/// Formats an f64 so that TOML reads back the same number (always with a `.` or an
/// exponent, so it stays a float).
fn num(v: f64) -> String {
    format!("{v:?}")
}

fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

/// Scene `index` of `seed` at output size `size`.
pub fn generate(seed: u64, index: usize, size: (u32, u32)) -> RandomScene {
    let mut rng = SplitMix64::new(seed ^ (index as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    rng.next_u64();
    let builtin = BlockRegistry::default();
    let mut pool: Vec<(String, f32)> = builtin
        .iter()
        .filter(|(_, d)| d.class == RenderClass::Translucent)
        .map(|(_, d)| (d.name.clone(), d.opacity))
        .collect();
    let mut extras = Vec::new();
    if rng.chance(0.5) {
        for j in 0..rng.int(1, 3) {
            let name = format!("extra_{}", (b'a' + j as u8) as char);
            let color = [0; 3].map(|_| rng.int(0, 255) as u8);
            // 0.05 to 0.98 in hundredths, exact in decimal.
            let opacity = rng.int(5, 98) as f32 / 100.0;
            pool.push((name.clone(), opacity));
            extras.push((name, color, opacity));
        }
    }
    let mut g = Gen {
        rng,
        boxes: Vec::new(),
        pool,
        extras,
        features: Features::default(),
        ground: false,
        surface: None,
        stack: None,
        floor: None,
        ceiling: None,
        beyond: Vec::new(),
    };
    g.ground = g.rng.chance(0.45);
    g.parts();
    g.use_extras();
    let (eye, target, fov, near, far) = g.camera();
    g.finish_features(eye);
    let offset = [0; 3].map(|_| g.rng.int(-48, 16));
    let off_f = offset.map(f64::from);
    let content_text = content(seed, index, eye, target, near, off_f, &mut g.features);

    let name = scene_name(seed, index);
    let f = &g.features;
    let words: Vec<&str> = f
        .flags()
        .into_iter()
        .filter(|(_, on)| *on)
        .map(|(w, _)| w)
        .collect();
    let mut t = String::new();
    t += &format!("# Random scene {index} of seed {seed}, made by voxel-lab's generator.\n");
    t += &format!("name = \"{name}\"\n");
    t += &format!(
        "description = \"{}; near {}, far {}, fov {}\"\n",
        if words.is_empty() {
            "plain boxes".to_owned()
        } else {
            words.join(", ")
        },
        num(near),
        num(far),
        num(fov)
    );
    t += &format!("size = [{}, {}]\n", size.0, size.1);
    let used: Vec<&str> = g.boxes.iter().map(|b| b.block.as_str()).collect();
    for (n, c, o) in &g.extras {
        if used.contains(&n.as_str()) {
            t += &format!(
                "\n[[blocks]]\nname = \"{n}\"\ncolor = [{}, {}, {}]\nopacity = {o:?}\n",
                c[0], c[1], c[2]
            );
        }
    }
    for b in &g.boxes {
        let min = [0, 1, 2].map(|k| b.min[k] + offset[k]);
        let max = [0, 1, 2].map(|k| b.max[k] + offset[k]);
        t += &format!(
            "\n[[boxes]]\nblock = \"{}\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\n",
            b.block, min[0], min[1], min[2], max[0], max[1], max[2]
        );
    }
    t += &content_text;
    t += &format!(
        "\n[[cameras]]\neye = {}\ntarget = {}\nfov = {}\nnear = {}\nfar = {}\n",
        vec3(add(eye, off_f)),
        vec3(add(target, off_f)),
        num(fov),
        num(near),
        num(far)
    );
    RandomScene {
        name,
        text: t,
        features: g.features,
    }
}
