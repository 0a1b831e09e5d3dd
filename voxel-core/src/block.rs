//! Block ids, render classes and the block registry (seed 000's per-index palette opacity).

use std::collections::HashMap;
use std::fmt;

use crate::{Error, Result};

/// Index of a block in a [`BlockRegistry`]. Id 0 is always air.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BlockId(pub u16);

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

/// One block type.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockDef {
    /// Unique name, used by scene files and error messages.
    pub name: String,
    /// Which pass draws it.
    pub class: RenderClass,
    /// Base colour, sRGB.
    pub color: [u8; 3],
    /// Opacity in `(0, 1]`; below 1 means the block is [`RenderClass::Translucent`].
    pub opacity: f32,
}

impl BlockDef {
    /// A block whose class follows from its opacity: translucent below 1, opaque at 1.
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
        }
    }

    /// An alpha-tested block such as leaves (opacity 1 where the texture is solid).
    pub fn cutout(name: impl Into<String>, color: [u8; 3]) -> Self {
        Self {
            name: name.into(),
            class: RenderClass::Cutout,
            color,
            opacity: 1.0,
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
        };
        Self {
            by_name: HashMap::from([(air.name.clone(), BlockId::AIR)]),
            defs: vec![air],
        }
    }

    /// Adds a block and returns its id. Fails on a duplicate name, an opacity outside
    /// `(0, 1]`, a class that contradicts the opacity, or a full registry.
    pub fn register(&mut self, def: BlockDef) -> Result<BlockId> {
        def.validate()?;
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
    /// The built-in blocks, with the ids of [`blocks`]: soil and rock, leaves (cutout), water,
    /// clear glass, ice, and three stained glasses of different colour and opacity so that a
    /// scene can stack translucent layers that differ in both.
    fn default() -> Self {
        let mut r = Self::new();
        let defs = [
            BlockDef::new("stone", [125, 125, 128], 1.0),
            BlockDef::new("dirt", [121, 85, 58], 1.0),
            BlockDef::new("grass", [96, 160, 64], 1.0),
            BlockDef::new("sand", [219, 205, 150], 1.0),
            BlockDef::new("wood", [110, 80, 45], 1.0),
            BlockDef::cutout("leaves", [60, 130, 45]),
            BlockDef::new("water", [25, 105, 165], 0.7),
            BlockDef::new("glass", [225, 240, 245], 0.2),
            BlockDef::new("ice", [170, 210, 245], 0.92),
            BlockDef::new("red_glass", [210, 40, 40], 0.5),
            BlockDef::new("green_glass", [50, 190, 70], 0.35),
            BlockDef::new("blue_glass", [40, 70, 220], 0.7),
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
