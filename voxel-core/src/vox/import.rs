//! The import of a file's voxels into a [`World`]: one block type per colour index used,
//! registered once, and the voxels placed, turned and moved.

use super::{MAX_EXTENT, VoxError, VoxFile, VoxMaterial};
use crate::{
    BlockDef, BlockId, BlockRegistry, Error, Pattern, RenderClass, Result, World, WorldPos,
};

impl VoxFile {
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
