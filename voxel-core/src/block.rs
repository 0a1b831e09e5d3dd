//! Block ids, render classes, how each block looks (a procedural pattern, or images the
//! game supplies per face group), and the block registry.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use crate::{Error, Face, Result};

/// Index of a block in a [`BlockRegistry`]. Id 0 is always air. `Debug` writes
/// `BlockId(3)` on one line, pretty-printed (`{:#?}`) too; `Display` writes `#3`. An id
/// does not know its name: [`BlockRegistry::get`] gives its definition.
#[derive(Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BlockId(pub u16);

impl fmt::Debug for BlockId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Not `debug_tuple`: pretty-printed it would spread one number over three lines
        // inside every struct that holds an id (a ray hit, a camera's medium).
        write!(f, "BlockId({})", self.0)
    }
}

impl BlockId {
    /// The empty block, present in every registry at index 0.
    pub const AIR: BlockId = BlockId(0);

    /// The id as an index into registry tables.
    pub fn index(self) -> usize {
        usize::from(self.0)
    }
}

impl fmt::Display for BlockId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// Which pass draws a block's faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RenderClass {
    /// Nothing to draw; hides nothing.
    Air,
    /// Fully opaque: drawn in the opaque pass, hides every face behind it.
    Opaque,
    /// Alpha-tested (leaves): drawn with a texture alpha test, writes depth, hides nothing.
    Cutout,
    /// Blended (water, glass): drawn by the selected transparency technique, hides nothing
    /// but a neighbour of its own type.
    Translucent,
}

/// How a block's texture is drawn where the game gives it no image: procedurally, from
/// the block's colour and opacity. Chosen by [`BlockDef::pattern`], never by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pattern {
    /// The base colour with a little brightness noise, alpha the block's opacity. What
    /// [`BlockDef::new`] gives opaque and translucent blocks.
    Noise,
    /// Leaves: noise with about a third of the texels fully transparent, for the cutout
    /// pass to cut. What [`BlockDef::cutout`] gives.
    Leaves,
    /// Glass: a one-texel frame, darker and opaque, around a centre of the block's
    /// opacity.
    Framed,
    /// Grass on soil: the top is the base colour with noise; the sides are soil of colour
    /// `soil` (sRGB) under a fringe of the base colour along their top edge, so that a
    /// one-block step reads as a step; the bottom is soil.
    Grass {
        /// The soil's colour, sRGB.
        soil: [u8; 3],
    },
}

/// The groups of faces a block is textured by: its top (+y), its bottom (−y), and its four
/// sides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaceGroup {
    /// The +y face.
    Top = 0,
    /// The −y face.
    Bottom = 1,
    /// The ±x and ±z faces.
    Side = 2,
}

impl FaceGroup {
    /// Every group, indexed by its discriminant.
    pub const ALL: [FaceGroup; 3] = [FaceGroup::Top, FaceGroup::Bottom, FaceGroup::Side];

    /// The group a face belongs to.
    pub fn of(face: Face) -> FaceGroup {
        match face {
            Face::PosY => FaceGroup::Top,
            Face::NegY => FaceGroup::Bottom,
            _ => FaceGroup::Side,
        }
    }

    /// The name scene files and messages use: `top`, `bottom` or `side`.
    pub fn name(self) -> &'static str {
        match self {
            FaceGroup::Top => "top",
            FaceGroup::Bottom => "bottom",
            FaceGroup::Side => "side",
        }
    }
}

/// The largest side of a [`BlockImage`], in texels. Every block texture is scaled to the
/// largest image given (nearest texel, so a smaller image keeps its look), and 256 × 256
/// RGBA with its mipmaps is 341 KiB a layer: 256 layers of it, 85 MiB of GPU memory.
pub const MAX_IMAGE_SIZE: u32 = 256;

/// A square image for a block's faces: `size` × `size` texels of 8-bit RGBA, rows top to
/// bottom, colour sRGB-encoded (as PNG files store it), alpha straight (not
/// premultiplied). The side is a power of two from 1 to [`MAX_IMAGE_SIZE`].
///
/// How a face shows it: on a side face the image stands upright (its first row along the
/// block's top edge) with its x axis running left to right as seen from outside; on the
/// top and bottom faces its x axis runs along world +x and its y axis along world +z.
/// Alpha: a cutout block is cut where alpha is below one half; on a translucent block it
/// is the opacity of each texel; an opaque block ignores it.
#[derive(Clone, PartialEq, Eq)]
pub struct BlockImage {
    size: u32,
    rgba: Arc<[u8]>,
}

impl fmt::Debug for BlockImage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "BlockImage({0}x{0})", self.size)
    }
}

impl BlockImage {
    /// An image of `width` × `height` texels from `rgba` (4 bytes a texel, rows top to
    /// bottom). Fails when it is not square, its side is not a power of two from 1 to
    /// [`MAX_IMAGE_SIZE`], or `rgba` does not hold exactly its texels.
    pub fn new(width: u32, height: u32, rgba: Vec<u8>) -> Result<Self> {
        let bad = |reason: String| Err(Error::InvalidImage(reason));
        if width != height {
            return bad(format!(
                "{width}x{height} texels: a block image must be square"
            ));
        }
        if !width.is_power_of_two() || width > MAX_IMAGE_SIZE {
            return bad(format!(
                "{width}x{height} texels: the side must be a power of two from 1 to {MAX_IMAGE_SIZE}"
            ));
        }
        let want = (width as usize) * (height as usize) * 4;
        if rgba.len() != want {
            return bad(format!(
                "{width}x{height} texels need {want} bytes of RGBA, not {}",
                rgba.len()
            ));
        }
        Ok(Self {
            size: width,
            rgba: rgba.into(),
        })
    }

    /// One colour: a 1 × 1 image.
    pub fn solid(rgba: [u8; 4]) -> Self {
        Self {
            size: 1,
            rgba: Arc::new(rgba),
        }
    }

    /// Texels along each side.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// The texels, 4 bytes each, rows top to bottom.
    pub fn rgba(&self) -> &[u8] {
        &self.rgba
    }

    /// The texel at column `x`, row `y` (taken modulo the size: the image repeats).
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (((y % self.size) * self.size + x % self.size) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }
}

/// The images a game gives a block's faces, by [`FaceGroup`]; a group without one is drawn
/// with the block's [`Pattern`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FaceImages {
    /// The +y face.
    pub top: Option<BlockImage>,
    /// The −y face.
    pub bottom: Option<BlockImage>,
    /// The four side faces.
    pub side: Option<BlockImage>,
}

impl FaceImages {
    /// The same image on every face.
    pub fn all(image: BlockImage) -> Self {
        Self {
            top: Some(image.clone()),
            bottom: Some(image.clone()),
            side: Some(image),
        }
    }

    /// The image of `group`, if it has one.
    pub fn get(&self, group: FaceGroup) -> Option<&BlockImage> {
        match group {
            FaceGroup::Top => self.top.as_ref(),
            FaceGroup::Bottom => self.bottom.as_ref(),
            FaceGroup::Side => self.side.as_ref(),
        }
    }

    /// Whether no group has an image.
    pub fn is_empty(&self) -> bool {
        FaceGroup::ALL.iter().all(|&g| self.get(g).is_none())
    }
}

impl RenderClass {
    /// Every class that draws something: what stops a ray that picks visible blocks
    /// (`World::raycast`).
    pub const VISIBLE: [RenderClass; 3] = [
        RenderClass::Opaque,
        RenderClass::Cutout,
        RenderClass::Translucent,
    ];
}

/// One block type.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockDef {
    /// Unique name, used by scene files and error messages.
    pub name: String,
    /// Which pass draws it.
    pub class: RenderClass,
    /// Base colour, sRGB: the procedural pattern's colour, the colour of flat textures and
    /// of the fog inside a translucent volume.
    pub color: [u8; 3],
    /// Opacity in `(0, 1]`; below 1 means the block is [`RenderClass::Translucent`]. With
    /// images, each texel's alpha is the opacity drawn; this stays the block's opacity as a
    /// whole (flat textures, the fog inside it, the WBOIT weight's estimate).
    pub opacity: f32,
    /// The procedural texture of the face groups without an image.
    pub pattern: Pattern,
    /// Images the game supplies, per face group.
    pub images: FaceImages,
    /// A translucent block that is a volume (water): how much of the light crossing it
    /// it absorbs per block. What lies behind its surface, or beyond it from inside,
    /// keeps `exp(−absorption · d)` of its light over a path of `d` blocks through it and
    /// takes the block's colour (lit like a face turned to the sky) for the rest. 0 (the
    /// default of [`BlockDef::new`]): a thin surface, which only its faces' opacity tints
    /// seen from outside, and whose inside an eye sees fogged as every translucent block
    /// always was ([`BlockDef::eye_absorption`]). Volumes are chosen, never given: the
    /// built-in water is one, absorbing `−ln(1 − 0.7) / 16` ≈ 0.075 a block
    /// ([`WATER_ABSORPTION`]); [`BlockDef::volume`] makes a game's block one the same way.
    pub absorption: f32,
    /// For a cutout block (kelp, seagrass, a fence): the volume it stands in, a
    /// translucent block with absorption ("waterlogged"). The medium's faces toward it are
    /// not drawn (the volume goes on through it), its holes show the medium, and an eye in
    /// it is in the medium. `None` (the default): it stands in air.
    pub medium: Option<BlockId>,
    /// The light the block gives out (torch, lava, glowing glass): the block light level
    /// of its own cell per channel, linear RGB from 0 to 255, falling
    /// [`crate::LIGHT_FALLOFF`] a block from there (255 lights 15 blocks around it); see
    /// [`crate::LightField`]. `[0, 0, 0]` (the default): it gives none.
    pub emission: [u8; 3],
}

/// The built-in water's absorption per block: 16 blocks of it dim what lies behind as
/// much as one water surface does (`(1 − 0.7)`), so that one block of water looks as a
/// thin water surface did (surface and one block: 72 % opaque instead of 70 %), 2 blocks
/// over sand show it clearly and 30 blocks show little but the water's colour.
pub const WATER_ABSORPTION: f32 = 0.075_248_3;

/// The largest absorption per block: beyond it a single block lets through less than
/// `e^-64` of the light, all but opaque.
pub const MAX_ABSORPTION: f32 = 64.0;

/// Blocks of a translucent block's inside that dim what lies beyond as much as one of its
/// surfaces: the fog an eye inside a thin translucent block sees
/// ([`BlockDef::eye_absorption`]), and the absorption [`BlockDef::volume`] gives.
pub const FOG_BLOCKS: f32 = 16.0;

/// The absorption per block that dims as much over [`FOG_BLOCKS`] blocks as one surface of
/// `opacity` does: `−ln(1 − opacity) / FOG_BLOCKS` (0 for an opacity outside `(0, 1)`, at
/// most [`MAX_ABSORPTION`]).
pub fn fog_absorption(opacity: f32) -> f32 {
    if opacity > 0.0 && opacity < 1.0 {
        (-(1.0 - opacity).ln() / FOG_BLOCKS).min(MAX_ABSORPTION)
    } else {
        0.0
    }
}

impl BlockDef {
    /// A block whose class follows from its opacity: translucent below 1, opaque at 1;
    /// pattern [`Pattern::Noise`], no images.
    pub fn new(name: impl Into<String>, color: [u8; 3], opacity: f32) -> Self {
        let class = if opacity < 1.0 {
            RenderClass::Translucent
        } else {
            RenderClass::Opaque
        };
        Self {
            name: name.into(),
            class,
            color,
            opacity,
            pattern: Pattern::Noise,
            images: FaceImages::default(),
            absorption: 0.0,
            medium: None,
            emission: [0; 3],
        }
    }

    /// A translucent block that is a volume like the built-in water: its absorption is
    /// [`fog_absorption`] of its opacity, so that [`FOG_BLOCKS`] blocks of it dim as much
    /// as one of its surfaces (the built-in water's [`WATER_ABSORPTION`] at opacity 0.7).
    /// Its inside is fogged as a thin block's is; seen from outside it darkens with the
    /// depth of the path through it. `with_absorption` sets another absorption.
    pub fn volume(name: impl Into<String>, color: [u8; 3], opacity: f32) -> Self {
        Self::new(name, color, opacity).with_absorption(fog_absorption(opacity))
    }

    /// How much an eye inside a block of this type has absorbed per block of the way to
    /// the medium's first surface (the fog under water): a volume's [`BlockDef::absorption`];
    /// for a thin translucent block (absorption 0), [`fog_absorption`] of its opacity, the
    /// fog every translucent block had before volumes existed, so that a game's water made
    /// with [`BlockDef::new`] keeps it; 0 for a block that is not translucent.
    pub fn eye_absorption(&self) -> f32 {
        match self.class {
            RenderClass::Translucent if self.absorption > 0.0 => self.absorption,
            RenderClass::Translucent => fog_absorption(self.opacity),
            _ => 0.0,
        }
    }

    /// An alpha-tested block such as leaves (opacity 1 where the texture is solid);
    /// pattern [`Pattern::Leaves`], no images.
    pub fn cutout(name: impl Into<String>, color: [u8; 3]) -> Self {
        Self {
            name: name.into(),
            class: RenderClass::Cutout,
            color,
            opacity: 1.0,
            pattern: Pattern::Leaves,
            images: FaceImages::default(),
            absorption: 0.0,
            medium: None,
            emission: [0; 3],
        }
    }

    /// The same block drawn with `pattern` where it has no image.
    pub fn with_pattern(self, pattern: Pattern) -> Self {
        Self { pattern, ..self }
    }

    /// The same block with `images` on its faces.
    pub fn with_images(self, images: FaceImages) -> Self {
        Self { images, ..self }
    }

    /// The same (translucent) block as a volume absorbing `absorption` a block (see
    /// [`BlockDef::absorption`]).
    pub fn with_absorption(self, absorption: f32) -> Self {
        Self { absorption, ..self }
    }

    /// The same block giving out light `emission` (see [`BlockDef::emission`]).
    pub fn emitting(self, emission: [u8; 3]) -> Self {
        Self { emission, ..self }
    }

    /// The same (cutout) block standing in `medium` (see [`BlockDef::medium`]).
    pub fn in_medium(self, medium: BlockId) -> Self {
        Self {
            medium: Some(medium),
            ..self
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |reason| {
            Err(Error::InvalidBlockDef {
                name: self.name.clone(),
                reason,
            })
        };
        if self.name.trim().is_empty() {
            return bad("the name is empty");
        }
        if !self.opacity.is_finite() || self.opacity <= 0.0 || self.opacity > 1.0 {
            return bad("opacity must be a number in (0, 1]");
        }
        match self.class {
            RenderClass::Air => bad("only id 0 is air"),
            RenderClass::Translucent if self.opacity >= 1.0 => {
                bad("a translucent block needs opacity below 1")
            }
            RenderClass::Opaque | RenderClass::Cutout if self.opacity < 1.0 => {
                bad("opacity below 1 makes a block translucent")
            }
            _ if !(0.0..=MAX_ABSORPTION).contains(&self.absorption) => {
                bad("absorption must be a number from 0 to 64 a block")
            }
            RenderClass::Opaque | RenderClass::Cutout if self.absorption > 0.0 => {
                bad("only a translucent block is a volume that absorbs")
            }
            class if self.medium.is_some() && class != RenderClass::Cutout => {
                bad("only a cutout block stands in a medium")
            }
            _ => Ok(()),
        }
    }
}

/// Ids of the blocks of [`BlockRegistry::default`], in registration order.
pub mod blocks {
    use super::BlockId;
    /// Empty space.
    pub const AIR: BlockId = BlockId(0);
    /// Grey rock under the soil.
    pub const STONE: BlockId = BlockId(1);
    /// Soil under the grass.
    pub const DIRT: BlockId = BlockId(2);
    /// Top of the soil above sea level.
    pub const GRASS: BlockId = BlockId(3);
    /// Shores and sea floor.
    pub const SAND: BlockId = BlockId(4);
    /// Tree trunks and structure frames.
    pub const WOOD: BlockId = BlockId(5);
    /// Tree canopies: alpha-tested (cutout).
    pub const LEAVES: BlockId = BlockId(6);
    /// Sea and pools (opacity 0.7).
    pub const WATER: BlockId = BlockId(7);
    /// Clear glass (opacity 0.2).
    pub const GLASS: BlockId = BlockId(8);
    /// Ice (opacity 0.92): a near-opaque layer in front of light ones.
    pub const ICE: BlockId = BlockId(9);
    /// Red stained glass (opacity 0.5).
    pub const RED_GLASS: BlockId = BlockId(10);
    /// Green stained glass (opacity 0.35).
    pub const GREEN_GLASS: BlockId = BlockId(11);
    /// Blue stained glass (opacity 0.7).
    pub const BLUE_GLASS: BlockId = BlockId(12);
}

/// All block types of a world, indexed by [`BlockId`].
#[derive(Clone, Debug, PartialEq)]
pub struct BlockRegistry {
    defs: Vec<BlockDef>,
    by_name: HashMap<String, BlockId>,
}

impl BlockRegistry {
    /// A registry holding only air (id 0).
    pub fn new() -> Self {
        let air = BlockDef {
            name: "air".into(),
            class: RenderClass::Air,
            color: [0, 0, 0],
            opacity: 0.0,
            pattern: Pattern::Noise,
            images: FaceImages::default(),
            absorption: 0.0,
            medium: None,
            emission: [0; 3],
        };
        Self {
            by_name: HashMap::from([(air.name.clone(), BlockId::AIR)]),
            defs: vec![air],
        }
    }

    /// Adds a block and returns its id. Fails on a duplicate name, an opacity outside
    /// `(0, 1]`, a class that contradicts the opacity, an absorption outside 0 to
    /// [`MAX_ABSORPTION`] or on a block that is not translucent, a medium that is not a
    /// translucent block already registered (or on a block that is not cutout), or a full
    /// registry.
    pub fn register(&mut self, def: BlockDef) -> Result<BlockId> {
        def.validate()?;
        if let Some(m) = def.medium {
            let ok = self
                .defs
                .get(m.index())
                .is_some_and(|d| d.class == RenderClass::Translucent);
            if !ok {
                return Err(Error::InvalidBlockDef {
                    name: def.name,
                    reason: "its medium must be a translucent block registered before it",
                });
            }
        }
        if self.by_name.contains_key(&def.name) {
            return Err(Error::DuplicateBlockName(def.name));
        }
        let id = BlockId(u16::try_from(self.defs.len()).map_err(|_| Error::TooManyBlocks)?);
        self.by_name.insert(def.name.clone(), id);
        self.defs.push(def);
        Ok(id)
    }

    /// The definition of `id`, or [`Error::UnknownBlock`].
    pub fn get(&self, id: BlockId) -> Result<&BlockDef> {
        self.defs
            .get(id.index())
            .ok_or(Error::UnknownBlock(id, self.defs.len()))
    }

    /// The render class of `id`, or [`Error::UnknownBlock`].
    pub fn class(&self, id: BlockId) -> Result<RenderClass> {
        self.get(id).map(|d| d.class)
    }

    /// Looks a block up by name; the error lists every known name.
    pub fn id(&self, name: &str) -> Result<BlockId> {
        self.by_name
            .get(name)
            .copied()
            .ok_or_else(|| Error::UnknownBlockName {
                name: name.to_owned(),
                known: self.names().collect::<Vec<_>>().join(", "),
            })
    }

    /// Whether `id` names a registered block.
    pub fn contains(&self, id: BlockId) -> bool {
        id.index() < self.defs.len()
    }

    /// Number of registered blocks, air included.
    pub fn len(&self) -> usize {
        self.defs.len()
    }

    /// Always false: air is always registered.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Block names in id order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.defs.iter().map(|d| d.name.as_str())
    }

    /// `(id, definition)` pairs in id order.
    pub fn iter(&self) -> impl Iterator<Item = (BlockId, &BlockDef)> {
        self.defs
            .iter()
            .enumerate()
            .map(|(i, d)| (BlockId(i as u16), d))
    }
}

impl Default for BlockRegistry {
    /// The built-in blocks, with the ids of [`blocks`]: soil and rock, grass with soil
    /// sides, leaves (cutout), water (a volume: [`WATER_ABSORPTION`]), clear glass, ice,
    /// and three stained glasses of different colour and opacity so that a scene can stack
    /// translucent layers that differ in both (thin surfaces). The glasses are framed
    /// ([`Pattern::Framed`]); water and ice are not.
    fn default() -> Self {
        let mut r = Self::new();
        let dirt = [121, 85, 58];
        let framed = |def: BlockDef| def.with_pattern(Pattern::Framed);
        let defs = [
            BlockDef::new("stone", [125, 125, 128], 1.0),
            BlockDef::new("dirt", dirt, 1.0),
            BlockDef::new("grass", [96, 160, 64], 1.0).with_pattern(Pattern::Grass { soil: dirt }),
            BlockDef::new("sand", [219, 205, 150], 1.0),
            BlockDef::new("wood", [110, 80, 45], 1.0),
            BlockDef::cutout("leaves", [60, 130, 45]),
            BlockDef::volume("water", [25, 105, 165], 0.7),
            framed(BlockDef::new("glass", [225, 240, 245], 0.2)),
            BlockDef::new("ice", [170, 210, 245], 0.92),
            framed(BlockDef::new("red_glass", [210, 40, 40], 0.5)),
            framed(BlockDef::new("green_glass", [50, 190, 70], 0.35)),
            framed(BlockDef::new("blue_glass", [40, 70, 220], 0.7)),
        ];
        for def in defs {
            // The built-in table is valid by construction; the test below checks it.
            let _ = r.register(def);
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_print_on_one_line() {
        assert_eq!(format!("{:?}", BlockId(3)), "BlockId(3)");
        assert_eq!(format!("{:#?}", BlockId(3)), "BlockId(3)");
        assert_eq!(
            format!("{:#?}", Some(BlockId(7))),
            "Some(\n    BlockId(7),\n)"
        );
        assert_eq!(BlockId(3).to_string(), "#3");
    }

    #[test]
    fn defaults_match_the_id_constants() {
        let r = BlockRegistry::default();
        assert_eq!(r.len(), 13);
        let expect = [
            (blocks::AIR, "air", RenderClass::Air),
            (blocks::STONE, "stone", RenderClass::Opaque),
            (blocks::LEAVES, "leaves", RenderClass::Cutout),
            (blocks::WATER, "water", RenderClass::Translucent),
            (blocks::GLASS, "glass", RenderClass::Translucent),
            (blocks::ICE, "ice", RenderClass::Translucent),
            (blocks::BLUE_GLASS, "blue_glass", RenderClass::Translucent),
        ];
        for (id, name, class) in expect {
            assert_eq!(r.id(name).unwrap(), id);
            assert_eq!(r.class(id).unwrap(), class);
        }
        assert!(r.get(blocks::ICE).unwrap().opacity >= 0.9);
    }

    /// The built-in water is a volume made by `volume`, and a thin block of its opacity
    /// fogs an eye inside it the same: a game's water made with `new` keeps its fog.
    #[test]
    fn a_thin_block_fogs_the_eye_as_a_volume_of_its_opacity() {
        let r = BlockRegistry::default();
        let water = r.get(blocks::WATER).unwrap();
        assert!((water.absorption - WATER_ABSORPTION).abs() < 1e-6);
        assert_eq!(water.eye_absorption(), water.absorption);
        let thin = BlockDef::new("my_water", [30, 90, 160], 0.7);
        assert_eq!(thin.absorption, 0.0, "a volume only when chosen");
        assert!((thin.eye_absorption() - WATER_ABSORPTION).abs() < 1e-6);
        // Sixteen blocks of fog dim as one surface.
        let glass = r.get(blocks::GLASS).unwrap();
        let keep = (-glass.eye_absorption() * FOG_BLOCKS).exp();
        assert!((keep - (1.0 - glass.opacity)).abs() < 1e-6);
        let own = BlockDef::volume("lake", [30, 90, 160], 0.7).with_absorption(0.3);
        assert_eq!(own.eye_absorption(), 0.3);
        assert_eq!(r.get(blocks::STONE).unwrap().eye_absorption(), 0.0);
        assert_eq!(BlockDef::cutout("kelp", [0; 3]).eye_absorption(), 0.0);
        assert_eq!(fog_absorption(1.0), 0.0);
        assert_eq!(fog_absorption(f32::NAN), 0.0);
        assert!(fog_absorption(0.999_999_9) <= MAX_ABSORPTION);
    }

    #[test]
    fn stained_glasses_differ_in_colour_and_opacity() {
        let r = BlockRegistry::default();
        let g = [blocks::RED_GLASS, blocks::GREEN_GLASS, blocks::BLUE_GLASS]
            .map(|id| r.get(id).unwrap().clone());
        for i in 0..3 {
            for j in i + 1..3 {
                assert_ne!(g[i].color, g[j].color);
                assert_ne!(g[i].opacity, g[j].opacity);
            }
        }
    }

    #[test]
    fn opacity_below_one_is_translucent() {
        assert_eq!(
            BlockDef::new("x", [0; 3], 0.99).class,
            RenderClass::Translucent
        );
        assert_eq!(BlockDef::new("x", [0; 3], 1.0).class, RenderClass::Opaque);
    }

    #[test]
    fn unknown_id_and_name_are_errors() {
        let r = BlockRegistry::default();
        assert_eq!(
            r.get(BlockId(999)),
            Err(Error::UnknownBlock(BlockId(999), 13))
        );
        let err = r.id("lava").unwrap_err().to_string();
        assert!(err.contains("lava") && err.contains("water") && err.contains("stone"));
    }

    #[test]
    fn bad_definitions_are_rejected() {
        let mut r = BlockRegistry::default();
        for def in [
            BlockDef::new("", [0; 3], 1.0),
            BlockDef::new("nan", [0; 3], f32::NAN),
            BlockDef::new("zero", [0; 3], 0.0),
            BlockDef::new("big", [0; 3], 1.5),
            BlockDef {
                class: RenderClass::Cutout,
                ..BlockDef::new("thin_leaves", [0; 3], 0.5)
            },
            BlockDef {
                class: RenderClass::Air,
                ..BlockDef::new("void", [0; 3], 1.0)
            },
        ] {
            assert!(
                matches!(r.register(def.clone()), Err(Error::InvalidBlockDef { .. })),
                "{def:?}"
            );
        }
        assert_eq!(
            r.register(BlockDef::new("stone", [0; 3], 1.0)),
            Err(Error::DuplicateBlockName("stone".into()))
        );
        let id = r
            .register(BlockDef::new("lava", [255, 80, 0], 1.0))
            .unwrap();
        assert_eq!(id, BlockId(13));
    }

    #[test]
    fn patterns_are_fields_not_names() {
        let r = BlockRegistry::default();
        let pattern = |id| r.get(id).unwrap().pattern;
        assert_eq!(pattern(blocks::GLASS), Pattern::Framed);
        assert_eq!(pattern(blocks::BLUE_GLASS), Pattern::Framed);
        assert_eq!(pattern(blocks::WATER), Pattern::Noise);
        assert_eq!(pattern(blocks::LEAVES), Pattern::Leaves);
        assert_eq!(
            pattern(blocks::GRASS),
            Pattern::Grass {
                soil: r.get(blocks::DIRT).unwrap().color
            }
        );
        // A name says nothing about the look.
        assert_eq!(
            BlockDef::new("amber_glass", [200, 140, 40], 0.5).pattern,
            Pattern::Noise
        );
    }

    #[test]
    fn images_must_be_square_powers_of_two_within_the_limit() {
        let img = |w: u32, h: u32| BlockImage::new(w, h, vec![0; (w * h * 4) as usize]);
        for (w, h) in [(1, 1), (16, 16), (MAX_IMAGE_SIZE, MAX_IMAGE_SIZE)] {
            assert_eq!(img(w, h).unwrap().size(), w);
        }
        let message = |r: Result<BlockImage>| r.unwrap_err().to_string();
        assert!(message(img(16, 32)).contains("square"));
        assert!(message(img(12, 12)).contains("power of two"));
        assert!(message(img(512, 512)).contains("256"));
        assert!(message(img(0, 0)).contains("power of two"));
        assert!(message(BlockImage::new(2, 2, vec![0; 15])).contains("16 bytes"));
        let checker = BlockImage::new(2, 2, (0..16).collect()).unwrap();
        assert_eq!(checker.texel(1, 0), [4, 5, 6, 7]);
        assert_eq!(checker.texel(2, 3), [8, 9, 10, 11], "the image repeats");
        let all = FaceImages::all(checker.clone());
        assert!(FaceGroup::ALL.iter().all(|&g| all.get(g) == Some(&checker)));
        assert!(FaceImages::default().is_empty());
        assert_eq!(FaceGroup::of(Face::PosY), FaceGroup::Top);
        assert_eq!(FaceGroup::of(Face::NegY), FaceGroup::Bottom);
        assert_eq!(FaceGroup::of(Face::NegX), FaceGroup::Side);
    }

    #[test]
    fn registry_full_is_an_error() {
        let mut r = BlockRegistry::new();
        for i in 1..=u16::MAX {
            r.register(BlockDef::new(format!("b{i}"), [0; 3], 1.0))
                .unwrap();
        }
        assert_eq!(
            r.register(BlockDef::new("one_more", [0; 3], 1.0)),
            Err(Error::TooManyBlocks)
        );
    }
}
