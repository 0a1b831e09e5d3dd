//! Deterministic terrain from a seed: a 2D fBm heightmap (hills), a sea, sand shores, trees
//! with leaf canopies, and glass structures on the shore so that views through glass onto
//! water exist. Only 2D noise: nothing here needs caves or overhangs.
//!
//! Every chunk is generated on its own (so chunks can be generated in parallel): trees and
//! structures that straddle chunk borders are placed by hashing world positions, and each
//! chunk writes the part that falls inside it.
//!
//! The generator fills roles ([`TerrainRole`]: stone, dirt, grass, ...) with the blocks of a
//! [`TerrainBlocks`] mapping: the default registry's, or a game's own, checked against the
//! registry the world is made with.

use std::sync::Arc;

use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;

use crate::{BlockId, BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, Error, World, blocks};

/// What the generator places: each role is filled with one block of the game's choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TerrainRole {
    /// Rock under the soil.
    Stone,
    /// Soil under the grass.
    Dirt,
    /// The top block of dry land.
    Grass,
    /// Shores and sea floor.
    Sand,
    /// The sea, up to the sea level.
    Water,
    /// Tree trunks and the frames of structures.
    Log,
    /// Tree canopies and the bushes in greenhouses.
    Leaves,
    /// Clear glass: greenhouse walls and roofs, a pavilion's wall and skylight.
    Glass,
    /// A pavilion's red wall.
    RedGlass,
    /// A greenhouse's partition and a pavilion's green wall.
    GreenGlass,
    /// A pavilion's blue wall.
    BlueGlass,
}

impl TerrainRole {
    /// Every role, indexed by its discriminant.
    pub const ALL: [TerrainRole; 11] = [
        TerrainRole::Stone,
        TerrainRole::Dirt,
        TerrainRole::Grass,
        TerrainRole::Sand,
        TerrainRole::Water,
        TerrainRole::Log,
        TerrainRole::Leaves,
        TerrainRole::Glass,
        TerrainRole::RedGlass,
        TerrainRole::GreenGlass,
        TerrainRole::BlueGlass,
    ];

    /// The role's name, which is also the name of its block in the default registry
    /// (except `log`, the default registry's `wood`).
    pub fn name(self) -> &'static str {
        match self {
            TerrainRole::Stone => "stone",
            TerrainRole::Dirt => "dirt",
            TerrainRole::Grass => "grass",
            TerrainRole::Sand => "sand",
            TerrainRole::Water => "water",
            TerrainRole::Log => "log",
            TerrainRole::Leaves => "leaves",
            TerrainRole::Glass => "glass",
            TerrainRole::RedGlass => "red_glass",
            TerrainRole::GreenGlass => "green_glass",
            TerrainRole::BlueGlass => "blue_glass",
        }
    }

    /// The role's block in [`BlockRegistry::default`].
    pub fn default_block(self) -> BlockId {
        match self {
            TerrainRole::Stone => blocks::STONE,
            TerrainRole::Dirt => blocks::DIRT,
            TerrainRole::Grass => blocks::GRASS,
            TerrainRole::Sand => blocks::SAND,
            TerrainRole::Water => blocks::WATER,
            TerrainRole::Log => blocks::WOOD,
            TerrainRole::Leaves => blocks::LEAVES,
            TerrainRole::Glass => blocks::GLASS,
            TerrainRole::RedGlass => blocks::RED_GLASS,
            TerrainRole::GreenGlass => blocks::GREEN_GLASS,
            TerrainRole::BlueGlass => blocks::BLUE_GLASS,
        }
    }

    /// Whether a generator with `config` places this role: the glass roles only with
    /// structures.
    pub fn used_by(self, config: &TerrainConfig) -> bool {
        config.structures
            || !matches!(
                self,
                TerrainRole::Glass
                    | TerrainRole::RedGlass
                    | TerrainRole::GreenGlass
                    | TerrainRole::BlueGlass
            )
    }
}

/// The block of each [`TerrainRole`], with the name that block had in the registry the
/// mapping was made from: [`TerrainBlocks::check`] compares them with the registry a world
/// is made with, so a mapping never silently draws another registry's blocks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TerrainBlocks {
    ids: [BlockId; TerrainRole::ALL.len()],
    names: [String; TerrainRole::ALL.len()],
}

impl Default for TerrainBlocks {
    /// The blocks of [`BlockRegistry::default`].
    fn default() -> Self {
        let registry = BlockRegistry::default();
        let ids = TerrainRole::ALL.map(TerrainRole::default_block);
        Self {
            names: ids.map(|id| registry.get(id).map_or(String::new(), |d| d.name.clone())),
            ids,
        }
    }
}

impl TerrainBlocks {
    /// The blocks of `registry`: each role in `map` takes the block given there; every
    /// other role takes the block named like the role (`stone`, `dirt`, ..., `log` or
    /// else `wood`). Fails naming every role the registry has no block for (and ids
    /// `map` gives that it does not hold); roles a generator with `config` does not place
    /// may be missing (they stay air).
    pub fn from_registry(
        registry: &BlockRegistry,
        config: &TerrainConfig,
        map: &[(TerrainRole, BlockId)],
    ) -> crate::Result<Self> {
        let mut ids = [BlockId::AIR; TerrainRole::ALL.len()];
        let mut missing = Vec::new();
        for role in TerrainRole::ALL {
            let given = map
                .iter()
                .rev()
                .find(|(r, _)| *r == role)
                .map(|(_, id)| *id);
            let found = match given {
                Some(id) if registry.contains(id) && id != BlockId::AIR => Some(id),
                Some(id) => {
                    missing.push(format!("{} (id {id} is not a block of it)", role.name()));
                    continue;
                }
                None => registry.id(role.name()).ok().or_else(|| {
                    (role == TerrainRole::Log)
                        .then(|| registry.id("wood").ok())
                        .flatten()
                }),
            };
            match found {
                Some(id) => ids[role as usize] = id,
                None if role.used_by(config) => {
                    missing.push(format!(
                        "{} (no block named {:?})",
                        role.name(),
                        role.name()
                    ));
                }
                None => {}
            }
        }
        if !missing.is_empty() {
            return Err(Error::TerrainBlocks(format!(
                "the registry lacks blocks for the roles {}: register a block named like each \
                 role, or give the role a block of the registry in the `map` argument, e.g. \
                 &[(TerrainRole::Log, oak_id)]",
                missing.join(", ")
            )));
        }
        Ok(Self {
            names: ids.map(|id| registry.get(id).map_or(String::new(), |d| d.name.clone())),
            ids,
        })
    }

    /// The block of `role` (air for a role the mapping left out).
    pub fn get(&self, role: TerrainRole) -> BlockId {
        self.ids[role as usize]
    }

    /// Checks that `registry` holds each role's block under the name it had where the
    /// mapping was made; fails naming every role that differs (a generator made for the
    /// default registry, used with a game's registry whose id 8 is `amber_glass`, fails
    /// here instead of drawing amber glass where glass belongs).
    pub fn check(&self, registry: &BlockRegistry, config: &TerrainConfig) -> crate::Result<()> {
        let wrong: Vec<String> = TerrainRole::ALL
            .into_iter()
            .filter(|r| r.used_by(config))
            .filter_map(|role| {
                let (id, name) = (self.ids[role as usize], &self.names[role as usize]);
                let here = registry.get(id).ok().map(|d| d.name.as_str());
                (here != Some(name.as_str())).then(|| match here {
                    Some(other) => format!(
                        "{} is block {id} {name:?}, but this registry's {id} is {other:?}",
                        role.name()
                    ),
                    None => format!(
                        "{} is block {id} {name:?}, which this registry does not hold",
                        role.name()
                    ),
                })
            })
            .collect();
        if wrong.is_empty() {
            Ok(())
        } else {
            Err(Error::TerrainBlocks(format!(
                "{}; make the generator with TerrainGenerator::with_blocks and TerrainBlocks::from_registry",
                wrong.join("; ")
            )))
        }
    }
}

/// Parameters of the generator. `Default` gives the world the demo and tests use.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainConfig {
    /// Seed of every noise and hash: the same seed gives the same world.
    pub seed: u32,
    /// World y of the sea surface: empty blocks at or below it are water. 24 puts the sea
    /// inside the lowest chunk layer so that a 2-chunk-high world holds hills and sea.
    pub sea_level: i32,
    /// Mean ground height. 26: a little above the sea, so land and sea are both common.
    pub base_height: i32,
    /// Ground height varies by about ± this much. 18 keeps hills below y = 50, inside
    /// two chunk layers.
    pub amplitude: f64,
    /// Horizontal size of a hill, in blocks. 110 gives coasts every hundred blocks or so.
    pub hill_size: f64,
    /// Fraction of 8×8 tree cells holding a tree (on dry land). 0.3: woods, not a forest.
    pub tree_density: f64,
    /// Whether to place glass structures (greenhouses, stained-glass pavilions) on shores.
    pub structures: bool,
}

impl Default for TerrainConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            sea_level: 24,
            base_height: 26,
            amplitude: 18.0,
            hill_size: 110.0,
            tree_density: 0.3,
            structures: true,
        }
    }
}

/// What stands on a [`Site`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SiteKind {
    /// An 11×9 clear-glass house with a wooden frame, a green-glass partition and bushes
    /// (leaves) inside.
    Greenhouse,
    /// A 9×9 pavilion on a platform whose four walls are red, blue, green and clear glass.
    Pavilion,
}

/// A structure placed on a shore.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Site {
    /// Which structure.
    pub kind: SiteKind,
    /// World position of the centre of its floor (the first block above the floor slab).
    pub center: [i64; 3],
    /// Horizontal direction `(dx, dz)` from the centre in which the sea lies.
    pub water_dir: [i32; 2],
}

impl Site {
    /// Half extents `(x, z)` of the footprint.
    pub fn half_extent(&self) -> [i64; 2] {
        match self.kind {
            SiteKind::Greenhouse => [5, 4],
            SiteKind::Pavilion => [4, 4],
        }
    }
}

/// The default scene ([`TerrainGenerator::showcase`]): its world and where it is seen from,
/// world blocks.
#[derive(Debug)]
pub struct Showcase {
    /// The terrain around the structure.
    pub world: World,
    /// The eye.
    pub eye: [f64; 3],
    /// The point looked at.
    pub target: [f64; 3],
    /// The unit horizontal direction from the structure to the sea.
    pub water_dir: [f64; 3],
}

/// Side of the square regions that hold at most one structure each.
const REGION: i64 = 96;
/// Side of the square cells that hold at most one tree each.
const TREE_CELL: i64 = 8;
/// How far leaves reach from a trunk.
const CANOPY: i64 = 2;
/// No tree stands within this many blocks of a structure's footprint: a clearing, so that
/// the structure can be seen from around it.
const CLEARING: i64 = 22;

/// The coarsest level of detail [`TerrainGenerator::generate_level_chunk`] makes: cells of
/// 2^6 = 64 blocks, a level chunk 2048 blocks (64 full-detail chunks) wide; with a level
/// a ring, a view distance of 2048 chunks.
pub const MAX_LEVEL: u8 = 6;

/// How many blocks wide (in x and z) a cell of level `level` is: `2^level` (levels over
/// [`MAX_LEVEL`] are taken as it).
pub fn level_scale(level: u8) -> i64 {
    1 << level.min(MAX_LEVEL)
}

/// World block coordinates of the first block of chunk `pos` of level `level`: x and z
/// `32 · 2^level` blocks a chunk, y 32 (a level's cells are one block high).
pub fn level_origin(level: u8, pos: ChunkPos) -> [i64; 3] {
    level_origin_scaled(level_scale(level), pos)
}

/// The chunk of level `level` and the cell in it (x, y, z within the chunk) that hold the
/// world block at `block`: the cell whose *sample column* (see
/// [`TerrainGenerator::generate_level_chunk`]) is the block's column. `None` where the
/// block's column is no cell's sample column at that level (at level `k ≥ 1`, one column in
/// `2^k` along each of x and z is), or the chunk lies outside [`ChunkPos::is_valid`]. Level
/// 0 holds every block. What an edit of that block changes at each level.
pub fn level_cell(level: u8, block: [i64; 3]) -> Option<(ChunkPos, [usize; 3])> {
    let scale = level_scale(level);
    let n = CHUNK_SIZE as i64;
    let cell = |v: i64| {
        let off = v - scale / 2;
        (off.rem_euclid(scale) == 0).then(|| off.div_euclid(scale))
    };
    let (cx, cz) = (cell(block[0])?, cell(block[2])?);
    let c = [cx, block[1], cz];
    let chunk = c.map(|v| i32::try_from(v.div_euclid(n)).ok());
    let pos = ChunkPos::new(chunk[0]?, chunk[1]?, chunk[2]?);
    pos.is_valid()
        .then(|| (pos, c.map(|v| v.rem_euclid(n) as usize)))
}

fn level_origin_scaled(scale: i64, pos: ChunkPos) -> [i64; 3] {
    let n = CHUNK_SIZE as i64;
    [
        i64::from(pos.x) * n * scale,
        i64::from(pos.y) * n,
        i64::from(pos.z) * n * scale,
    ]
}

/// The terrain generator. Cheap to share between threads.
#[derive(Debug, Clone)]
pub struct TerrainGenerator {
    config: TerrainConfig,
    height: Fbm<Perlin>,
    blocks: TerrainBlocks,
}

/// splitmix64 over the seed, a position and a salt: the one source of randomness.
fn hash(seed: u32, x: i64, z: i64, salt: u64) -> u64 {
    let mut h = u64::from(seed)
        ^ (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (z as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ salt.wrapping_mul(0x1656_67b1_9e37_79f9);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

/// A box of one block in world coordinates, inclusive.
struct WorldBox {
    min: [i64; 3],
    max: [i64; 3],
    /// A role, or `None` for air.
    role: Option<TerrainRole>,
}

fn bx(min: [i64; 3], max: [i64; 3], role: TerrainRole) -> WorldBox {
    WorldBox {
        min,
        max,
        role: Some(role),
    }
}

fn air(min: [i64; 3], max: [i64; 3]) -> WorldBox {
    WorldBox {
        min,
        max,
        role: None,
    }
}

impl TerrainGenerator {
    /// A generator for `config` placing the blocks of [`BlockRegistry::default`] (a world
    /// over another registry is checked by [`TerrainGenerator::check`] and refused).
    pub fn new(config: TerrainConfig) -> Self {
        Self::with_blocks(config, TerrainBlocks::default())
    }

    /// A generator for `config` placing `blocks` (a game's own, from
    /// [`TerrainBlocks::from_registry`]).
    pub fn with_blocks(config: TerrainConfig, blocks: TerrainBlocks) -> Self {
        let height = Fbm::<Perlin>::new(config.seed)
            .set_octaves(4)
            .set_frequency(1.0 / config.hill_size);
        Self {
            config,
            height,
            blocks,
        }
    }

    /// The configuration this generator was made with.
    pub fn config(&self) -> &TerrainConfig {
        &self.config
    }

    /// The blocks it places.
    pub fn blocks(&self) -> &TerrainBlocks {
        &self.blocks
    }

    /// Whether chunks of this generator hold the blocks they mean in `registry`
    /// ([`TerrainBlocks::check`]): a streamer or world over `registry` should ask first.
    pub fn check(&self, registry: &BlockRegistry) -> crate::Result<()> {
        self.blocks.check(registry, &self.config)
    }

    fn block(&self, role: TerrainRole) -> BlockId {
        self.blocks.get(role)
    }

    /// World y of the top ground block of column `(x, z)`.
    pub fn height_at(&self, x: i64, z: i64) -> i64 {
        let n = self.height.get([x as f64, z as f64]).clamp(-1.0, 1.0);
        i64::from(self.config.base_height) + (n * self.config.amplitude).round() as i64
    }

    fn sea(&self) -> i64 {
        i64::from(self.config.sea_level)
    }

    /// The structure of region `(rx, rz)`, if its shore has room for one: the first of eight
    /// hashed spots whose ground is within a few blocks of sea level and that has open water
    /// 12 blocks away.
    pub fn site_in_region(&self, rx: i64, rz: i64) -> Option<Site> {
        if !self.config.structures {
            return None;
        }
        let sea = self.sea();
        let dirs = [
            [1, 0],
            [-1, 0],
            [0, 1],
            [0, -1],
            [1, 1],
            [-1, 1],
            [1, -1],
            [-1, -1],
        ];
        (0..8u64).find_map(|k| {
            let r = hash(self.config.seed, rx, rz, 100 + k);
            let x = rx * REGION + 16 + (r % (REGION as u64 - 32)) as i64;
            let z = rz * REGION + 16 + ((r >> 20) % (REGION as u64 - 32)) as i64;
            let h = self.height_at(x, z);
            if !(sea - 1..=sea + 3).contains(&h) {
                return None;
            }
            let water_dir = dirs.into_iter().find(|[dx, dz]| {
                self.height_at(x + 12 * i64::from(*dx), z + 12 * i64::from(*dz)) < sea - 1
            })?;
            let kind = if (r >> 40) & 1 == 0 {
                SiteKind::Greenhouse
            } else {
                SiteKind::Pavilion
            };
            Some(Site {
                kind,
                center: [x, h.max(sea) + 1, z],
                water_dir,
            })
        })
    }

    /// Every structure whose region overlaps the square `[x0, x1) × [z0, z1)`.
    pub fn sites_in(&self, x0: i64, z0: i64, x1: i64, z1: i64) -> Vec<Site> {
        let r = |v: i64| v.div_euclid(REGION);
        let mut out = Vec::new();
        for rx in r(x0)..=r(x1 - 1) {
            for rz in r(z0)..=r(z1 - 1) {
                out.extend(self.site_in_region(rx, rz));
            }
        }
        out
    }

    /// Generates the chunk at `pos`. Never panics: positions near the `i32` limits work.
    pub fn generate_chunk(&self, pos: ChunkPos) -> Chunk {
        self.generate_level_chunk(0, pos)
    }

    /// Generates chunk `pos` of level of detail `level` (0 to [`MAX_LEVEL`]; larger levels
    /// are taken as [`MAX_LEVEL`]): [`CHUNK_SIZE`]³ cells, each `2^level` blocks wide in x
    /// and z and one block high, so that the chunk covers the blocks from
    /// [`level_origin`]`(level, pos)` on, `32 · 2^level` wide and 32 high. Straight from
    /// the generator, without the full-detail chunks it covers: each cell holds the block
    /// the full-detail world has at its *sample column*, the column
    /// `2^(level−1)` blocks into the cell on x and z (the cell's own column at level 0), at
    /// the cell's height. Level 0 is [`TerrainGenerator::generate_chunk`] exactly.
    ///
    /// Heights stay exact (a cell is one block high), so the sea's surface, a lake's floor
    /// under its surface and a structure's roof lie at the same height at every level; only
    /// the horizontal detail thins out, as Distant Horizons' column spans do. Trees and
    /// structures are sampled as the ground is: a coarse level keeps the fraction of the
    /// ground they cover, not each one (a 5-block canopy shows in some cells of level 2's
    /// 4-block cells and not in others).
    pub fn generate_level_chunk(&self, level: u8, pos: ChunkPos) -> Chunk {
        let column = self.generate_level_column(level, pos.x, pos.z, pos.y..=pos.y);
        column.into_iter().next().unwrap_or_default()
    }

    /// The chunks of level `level` at x `x` and z `z` (the level's chunk coordinates), one
    /// for each chunk height of `ys`, bottom first: each is
    /// [`TerrainGenerator::generate_level_chunk`] of its position, made at the cost of
    /// about one (the ground's heights, trees and structures are found once for the column).
    pub fn generate_level_column(
        &self,
        level: u8,
        x: i32,
        z: i32,
        ys: std::ops::RangeInclusive<i32>,
    ) -> Vec<Chunk> {
        let scale = level_scale(level);
        let n = CHUNK_SIZE as i64;
        // World blocks: the column's first block, and a cell's sample column.
        let [ox, _, oz] = level_origin_scaled(scale, ChunkPos::new(x, 0, z));
        let sample = |o: i64, c: usize| o + c as i64 * scale + scale / 2;
        let heights: Vec<i64> = (0..CHUNK_SIZE * CHUNK_SIZE)
            .map(|i| self.height_at(sample(ox, i / CHUNK_SIZE), sample(oz, i % CHUNK_SIZE)))
            .collect();
        let boxes = self.cell_boxes(ox, oz, scale);
        ys.map(|y| self.fill_cells(&heights, &boxes, [ox, i64::from(y) * n, oz], scale))
            .collect()
    }

    /// The chunk of `scale`-block-wide cells whose first block is `origin`, over the
    /// ground's `heights` at its sample columns (x-major) and with the trees' and
    /// structures' `boxes`.
    fn fill_cells(
        &self,
        heights: &[i64],
        boxes: &[WorldBox],
        [ox, oy, oz]: [i64; 3],
        scale: i64,
    ) -> Chunk {
        let n = CHUNK_SIZE as i64;
        let mut chunk = Chunk::default();
        let sea = self.sea();
        let local = |y: i64| (y - oy).clamp(0, n) as usize;
        let [stone, water] = [TerrainRole::Stone, TerrainRole::Water].map(|r| self.block(r));
        let [sand, grass, dirt] =
            [TerrainRole::Sand, TerrainRole::Grass, TerrainRole::Dirt].map(|r| self.block(r));

        // Ground and sea, a column run at a time.
        for x in 0..CHUNK_SIZE {
            for z in 0..CHUNK_SIZE {
                let h = heights[x * CHUNK_SIZE + z];
                let shore = h <= sea + 1;
                let top = if shore { sand } else { grass };
                let soil = if shore { sand } else { dirt };
                for (y0, y1, id) in [
                    (i64::MIN, h - 3, stone),
                    (h - 3, h, soil),
                    (h, h + 1, top),
                    (h + 1, sea + 1, water),
                ] {
                    let (a, b) = (local(y0.max(oy)), local(y1));
                    if a < b {
                        // In range by construction: a < b <= 32.
                        let _ = chunk.fill_column(x, z, a..b, id);
                    }
                }
            }
        }
        // The cells whose sample column lies in a box's `[min, max]` on x and z (on y, the
        // cells are blocks).
        let first = |min: i64, o: i64| (min - o - scale / 2 + scale - 1).div_euclid(scale);
        let last = |max: i64, o: i64| (max - o - scale / 2).div_euclid(scale);
        for b in boxes {
            let min = [first(b.min[0], ox), b.min[1] - oy, first(b.min[2], oz)].map(|v| v.max(0));
            let max = [last(b.max[0], ox), b.max[1] - oy, last(b.max[2], oz)].map(|v| v.min(n - 1));
            if min.iter().zip(&max).all(|(a, b)| a <= b) {
                // Clipped to the chunk above, so always in range.
                let id = b.role.map_or(BlockId::AIR, |r| self.block(r));
                let _ = chunk.fill_box(min.map(|v| v as usize), max.map(|v| v as usize), id);
            }
        }
        chunk
    }

    /// The boxes of the trees and structures that place a cell in the column of
    /// `scale`-block-wide cells starting at world `(ox, oz)`.
    fn cell_boxes(&self, ox: i64, oz: i64, scale: i64) -> Vec<WorldBox> {
        let n = CHUNK_SIZE as i64;
        let sample = |o: i64, c: usize| o + c as i64 * scale + scale / 2;
        let (w, margin) = (n * scale, CLEARING + 8);
        let sites = self.sites_in(ox - margin, oz - margin, ox + w + margin, oz + w + margin);
        let mut boxes = Vec::new();
        let cell = |v: i64| v.div_euclid(TREE_CELL);
        let mut cells = Vec::new();
        if scale <= 2 {
            // Every tree cell whose canopy may reach into the chunk.
            for cx in cell(ox - CANOPY)..=cell(ox + w + CANOPY) {
                for cz in cell(oz - CANOPY)..=cell(oz + w + CANOPY) {
                    cells.push((cx, cz));
                }
            }
        } else {
            // Only the cells whose canopy may reach a sample column (at most four each).
            for x in 0..CHUNK_SIZE {
                let sx = sample(ox, x);
                for z in 0..CHUNK_SIZE {
                    let sz = sample(oz, z);
                    for cx in cell(sx - CANOPY)..=cell(sx + CANOPY) {
                        for cz in cell(sz - CANOPY)..=cell(sz + CANOPY) {
                            cells.push((cx, cz));
                        }
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
        }
        // A tree counts only where its canopy reaches a sample column (at level 0 and 1
        // every tree near the chunk does): the others would place no cell, and their ground
        // height is the dearest part of a coarse chunk.
        let reaches = |o: i64, t: i64| {
            let (a, b) = (
                (t - CANOPY - o - scale / 2 + scale - 1)
                    .div_euclid(scale)
                    .max(0),
                (t + CANOPY - o - scale / 2).div_euclid(scale).min(n - 1),
            );
            a <= b
        };
        self.trees(&cells, &sites, &mut boxes, |tx, tz| {
            reaches(ox, tx) && reaches(oz, tz)
        });
        for site in &sites {
            structure(site, &mut boxes);
        }
        boxes
    }

    /// The trees of tree cells `cells` whose trunk `reaches` (at `(tx, tz)`), as boxes
    /// (leaves first, so the trunk wins where they overlap).
    fn trees(
        &self,
        cells: &[(i64, i64)],
        sites: &[Site],
        out: &mut Vec<WorldBox>,
        reaches: impl Fn(i64, i64) -> bool,
    ) {
        let sea = self.sea();
        for &(cx, cz) in cells {
            let r = hash(self.config.seed, cx, cz, 1);
            if (r % 10_000) as f64 >= self.config.tree_density * 10_000.0 {
                continue;
            }
            let tx = cx * TREE_CELL + 1 + ((r >> 16) % (TREE_CELL as u64 - 2)) as i64;
            let tz = cz * TREE_CELL + 1 + ((r >> 24) % (TREE_CELL as u64 - 2)) as i64;
            if !reaches(tx, tz) {
                continue;
            }
            let near_site = sites.iter().any(|s| {
                let [hx, hz] = s.half_extent();
                (tx - s.center[0]).abs() <= hx + CLEARING
                    && (tz - s.center[2]).abs() <= hz + CLEARING
            });
            let h = self.height_at(tx, tz);
            if near_site || h <= sea + 1 {
                continue;
            }
            let top = h + 4 + ((r >> 32) % 3) as i64;
            out.push(bx(
                [tx - 2, top - 2, tz - 2],
                [tx + 2, top - 1, tz + 2],
                LEAVES,
            ));
            out.push(bx([tx - 1, top, tz - 1], [tx + 1, top, tz + 1], LEAVES));
            out.push(bx([tx - 1, top + 1, tz], [tx + 1, top + 1, tz], LEAVES));
            out.push(bx([tx, top + 1, tz - 1], [tx, top + 1, tz + 1], LEAVES));
            // Corners of the wide layers are cut at random, as trees look less boxy so.
            for (i, (dx, dz)) in [(-2, -2), (2, -2), (-2, 2), (2, 2)].into_iter().enumerate() {
                let y = top - 1 - ((r >> (40 + i)) & 1) as i64;
                out.push(air([tx + dx, y, tz + dz], [tx + dx, top - 1, tz + dz]));
            }
            out.push(bx([tx, h + 1, tz], [tx, top, tz], WOOD));
        }
    }

    /// Generates every chunk of the box `min..=max` (chunk coordinates) in parallel into a
    /// new world over `registry`. Fails when `registry` does not hold the generator's
    /// blocks ([`TerrainGenerator::check`]).
    pub fn generate_world(
        &self,
        registry: Arc<BlockRegistry>,
        min: ChunkPos,
        max: ChunkPos,
    ) -> crate::Result<World> {
        self.check(&registry)?;
        let mut positions = Vec::new();
        for x in min.x..=max.x {
            for y in min.y..=max.y {
                for z in min.z..=max.z {
                    positions.push(ChunkPos::new(x, y, z));
                }
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        let positions = positions.into_par_iter();
        #[cfg(target_arch = "wasm32")]
        let positions = positions.into_iter();
        let chunks: Vec<_> = positions.map(|p| (p, self.generate_chunk(p))).collect();
        let mut world = World::new(registry);
        for (p, c) in chunks {
            world.insert_chunk(p, c)?;
        }
        Ok(world)
    }

    /// The default scene's world and view, which the lab and the web page both draw: terrain
    /// `radius` chunks each way (clamped to 1 to 16) and two chunks high around the
    /// greenhouse nearest the origin (else the first structure near it) over the default
    /// registry, and an eye on the land side, above the ground there, looking through the
    /// structure at the sea. `None` where no structure lies within 768 blocks of the origin.
    pub fn showcase(&self, radius: i32) -> crate::Result<Option<Showcase>> {
        let radius = radius.clamp(1, 16);
        let sites = self.sites_in(-768, -768, 768, 768);
        let Some(site) = sites
            .iter()
            .filter(|s| s.kind == SiteKind::Greenhouse)
            .min_by_key(|s| s.center[0].pow(2) + s.center[2].pow(2))
            .or_else(|| sites.first())
            .copied()
        else {
            return Ok(None);
        };
        let c = site.center;
        let (cx, cz) = (c[0].div_euclid(32) as i32, c[2].div_euclid(32) as i32);
        let world = self.generate_world(
            Arc::new(BlockRegistry::default()),
            ChunkPos::new(cx - radius, 0, cz - radius),
            ChunkPos::new(cx + radius, 1, cz + radius),
        )?;
        // The unit horizontal direction of the water (as glam's `normalize`: times the
        // reciprocal of the length).
        let (wx, wz) = (f64::from(site.water_dir[0]), f64::from(site.water_dir[1]));
        let inverse = 1.0 / (wx * wx + 0.0 * 0.0 + wz * wz).sqrt();
        let dir = [wx * inverse, 0.0, wz * inverse];
        let center = [c[0] as f64 + 0.5, c[1] as f64, c[2] as f64 + 0.5];
        // Back from the structure on the land side, above the ground there.
        let mut eye = [0, 1, 2].map(|a| center[a] - dir[a] * 18.0);
        eye[1] += 11.0;
        let ground = self.height_at(eye[0].floor() as i64, eye[2].floor() as i64) as f64;
        eye[1] = eye[1].max(ground + 3.5);
        let sea = f64::from(self.config.sea_level);
        let mut target = [0, 1, 2].map(|a| center[a] + dir[a] * 12.0);
        target[1] += sea - center[1] + 1.0;
        Ok(Some(Showcase {
            world,
            eye,
            target,
            water_dir: dir,
        }))
    }
}

/// The roles under the names the layouts below were written with.
const STONE: TerrainRole = TerrainRole::Stone;
const WOOD: TerrainRole = TerrainRole::Log;
const LEAVES: TerrainRole = TerrainRole::Leaves;
const GLASS: TerrainRole = TerrainRole::Glass;
const RED_GLASS: TerrainRole = TerrainRole::RedGlass;
const GREEN_GLASS: TerrainRole = TerrainRole::GreenGlass;
const BLUE_GLASS: TerrainRole = TerrainRole::BlueGlass;

/// The boxes of a structure, in the order they are written.
fn structure(site: &Site, out: &mut Vec<WorldBox>) {
    let [cx, fy, cz] = site.center;
    let [hx, hz] = site.half_extent();
    let (x0, x1, z0, z1) = (cx - hx, cx + hx, cz - hz, cz + hz);
    // Clear the volume (terrain, stray leaves), then a plinth so nothing floats.
    out.push(air([x0 - 1, fy, z0 - 1], [x1 + 1, fy + 9, z1 + 1]));
    match site.kind {
        SiteKind::Greenhouse => {
            let top = fy + 5;
            out.push(bx([x0, fy - 4, z0], [x1, fy - 1, z1], STONE));
            // Glass shell, then the wooden frame on its edges.
            out.push(bx([x0, fy, z0], [x1, top, z1], GLASS));
            out.push(air([x0 + 1, fy, z0 + 1], [x1 - 1, top - 1, z1 - 1]));
            for (x, z) in [(x0, z0), (x1, z0), (x0, z1), (x1, z1)] {
                out.push(bx([x, fy, z], [x, top, z], WOOD));
            }
            out.push(bx([x0, top, z0], [x1, top, z0], WOOD));
            out.push(bx([x0, top, z1], [x1, top, z1], WOOD));
            out.push(bx([x0, top, z0], [x0, top, z1], WOOD));
            out.push(bx([x1, top, z0], [x1, top, z1], WOOD));
            // A green glass partition across the middle and bushes on both sides of it.
            out.push(bx([cx, fy, z0 + 1], [cx, fy + 3, z1 - 1], GREEN_GLASS));
            out.push(bx([cx - 3, fy, z0 + 1], [cx - 2, fy + 1, z0 + 2], LEAVES));
            out.push(bx([cx + 2, fy, z1 - 2], [cx + 3, fy + 1, z1 - 1], LEAVES));
            // Door on the side away from the sea (or -z when the sea lies along x).
            let dz = if site.water_dir[1] > 0 { z0 } else { z1 };
            out.push(air([cx - 2, fy, dz], [cx - 2, fy + 1, dz]));
        }
        SiteKind::Pavilion => {
            let top = fy + 4;
            out.push(bx([x0, fy - 1, z0], [x1, fy - 1, z1], WOOD));
            for (x, z) in [(x0, z0), (x1, z0), (x0, z1), (x1, z1)] {
                out.push(bx([x, fy - 12, z], [x, top, z], WOOD));
            }
            out.push(bx([x1, fy, z0 + 1], [x1, top - 1, z1 - 1], RED_GLASS));
            out.push(bx([x0, fy, z0 + 1], [x0, top - 1, z1 - 1], BLUE_GLASS));
            out.push(bx([x0 + 1, fy, z1], [x1 - 1, top - 1, z1], GREEN_GLASS));
            out.push(bx([x0 + 1, fy, z0], [x1 - 1, top - 1, z0], GLASS));
            out.push(bx([x0, top, z0], [x1, top, z1], STONE));
            out.push(bx([cx - 1, top, cz - 1], [cx + 1, top, cz + 1], GLASS));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BlockDef;
    // Named, so that they take precedence over the roles of the same names above.
    use crate::blocks::{
        AIR, BLUE_GLASS, DIRT, GLASS, GRASS, GREEN_GLASS, LEAVES, RED_GLASS, SAND, STONE, WATER,
        WOOD,
    };

    fn generator() -> TerrainGenerator {
        TerrainGenerator::new(TerrainConfig::default())
    }

    #[test]
    fn same_seed_same_chunk_other_seed_other_chunk() {
        let g = generator();
        let p = ChunkPos::new(3, 0, -2);
        let a = g.generate_chunk(p).to_dense();
        assert_eq!(a, g.generate_chunk(p).to_dense());
        let other = TerrainGenerator::new(TerrainConfig {
            seed: 2,
            ..TerrainConfig::default()
        });
        assert_ne!(a, other.generate_chunk(p).to_dense());
    }

    #[test]
    fn columns_are_stone_soil_top_then_water_or_air() {
        let g = generator();
        let sea = i64::from(g.config().sea_level);
        let c = g.generate_chunk(ChunkPos::new(0, 0, 0));
        c.check_invariants().unwrap();
        let mut saw_water = false;
        let mut saw_grass = false;
        for x in 0..32 {
            for z in 0..32 {
                let h = g.height_at(x as i64, z as i64);
                // Skip columns a tree or a structure changed.
                let col: Vec<_> = (0..32).map(|y| c.get(x, y, z).unwrap()).collect();
                if col.iter().any(|b| [WOOD, LEAVES, GLASS].contains(b)) {
                    continue;
                }
                for (y, b) in col.iter().enumerate() {
                    let y = y as i64;
                    let want = if y < h - 3 {
                        STONE
                    } else if y < h {
                        if h <= sea + 1 { SAND } else { DIRT }
                    } else if y == h {
                        if h <= sea + 1 { SAND } else { GRASS }
                    } else if y <= sea {
                        WATER
                    } else {
                        AIR
                    };
                    if want != *b && !(y > h && *b == AIR) {
                        panic!("column ({x},{z}) y {y}: {b} but expected {want} (h {h})");
                    }
                }
                saw_water |= col.contains(&WATER);
                saw_grass |= col.contains(&GRASS);
            }
        }
        assert!(saw_grass || saw_water);
    }

    #[test]
    fn default_world_has_sea_trees_and_both_structures_near_spawn() {
        let g = generator();
        let sites = g.sites_in(-384, -384, 384, 384);
        assert!(
            sites.iter().any(|s| s.kind == SiteKind::Greenhouse),
            "{sites:?}"
        );
        assert!(
            sites.iter().any(|s| s.kind == SiteKind::Pavilion),
            "{sites:?}"
        );
        for s in &sites {
            // Open water lies in the recorded direction: a view through glass onto water.
            let [dx, dz] = s.water_dir.map(i64::from);
            assert!(g.height_at(s.center[0] + 12 * dx, s.center[2] + 12 * dz) < 23);
            // The structure's glass is there in the generated chunk.
            let pos = ChunkPos::new(
                (s.center[0].div_euclid(32)) as i32,
                (s.center[1].div_euclid(32)) as i32,
                (s.center[2].div_euclid(32)) as i32,
            );
            let c = g.generate_chunk(pos);
            let glass = [GLASS, RED_GLASS, GREEN_GLASS, BLUE_GLASS];
            assert!(glass.iter().any(|&id| c.count(id) > 0), "{s:?}");
        }
        let c = g.generate_chunk(ChunkPos::new(1, 1, 1));
        let world_leaves: usize = (-3..3)
            .flat_map(|x| (-3..3).map(move |z| (x, z)))
            .map(|(x, z)| {
                (0..2)
                    .map(|y| g.generate_chunk(ChunkPos::new(x, y, z)).count(LEAVES))
                    .sum::<usize>()
            })
            .sum();
        assert!(world_leaves > 100, "{world_leaves} leaves");
        c.check_invariants().unwrap();
    }

    /// A game's registry: its own names, its own order, an extra block first (so no id is
    /// the default registry's), and no block named like the roles.
    fn game_registry() -> (BlockRegistry, Vec<(TerrainRole, BlockId)>) {
        let mut r = BlockRegistry::new();
        let _ = r.register(BlockDef::new("amber_glass", [200, 140, 40], 0.5));
        let mut map = Vec::new();
        for role in TerrainRole::ALL.into_iter().rev() {
            let def = BlockRegistry::default()
                .get(role.default_block())
                .unwrap()
                .clone();
            let id = r
                .register(BlockDef {
                    name: format!("game_{}", role.name()),
                    ..def
                })
                .unwrap();
            map.push((role, id));
        }
        (r, map)
    }

    #[test]
    fn a_registry_lacking_roles_is_an_error_naming_them() {
        let mut r = BlockRegistry::new();
        r.register(BlockDef::new("stone", [1, 2, 3], 1.0)).unwrap();
        r.register(BlockDef::new("wood", [1, 2, 3], 1.0)).unwrap();
        let config = TerrainConfig::default();
        let err = TerrainBlocks::from_registry(&r, &config, &[])
            .unwrap_err()
            .to_string();
        for role in [
            "dirt",
            "grass",
            "sand",
            "water",
            "leaves",
            "glass",
            "blue_glass",
        ] {
            assert!(err.contains(role), "{role} missing from: {err}");
        }
        assert!(!err.contains("stone ("), "stone is there: {err}");
        assert!(!err.contains("log ("), "wood stands in for log: {err}");
        // The hint says what to do, not to call the function that failed.
        assert!(
            err.contains("named like each role") && err.contains("`map`"),
            "{err}"
        );
        assert!(!err.contains("from_registry"), "a circular hint: {err}");
        // An id the registry does not hold is named too.
        let err = TerrainBlocks::from_registry(&r, &config, &[(TerrainRole::Stone, BlockId(77))])
            .unwrap_err()
            .to_string();
        assert!(err.contains("stone (id #77"), "{err}");
        // Without structures the glass roles are not needed.
        let no_structures = TerrainConfig {
            structures: false,
            ..config
        };
        let err = TerrainBlocks::from_registry(&r, &no_structures, &[])
            .unwrap_err()
            .to_string();
        assert!(err.contains("dirt") && !err.contains("glass"), "{err}");
    }

    #[test]
    fn the_default_generator_refuses_a_game_registry() {
        let (r, _) = game_registry();
        let err = generator()
            .generate_world(Arc::new(r), ChunkPos::new(0, 0, 0), ChunkPos::new(0, 0, 0))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(r#"glass is block #8 "glass", but this registry's #8 is"#),
            "{err}"
        );
    }

    #[test]
    fn a_mapped_registry_gives_the_default_world_block_for_block() {
        let (r, map) = game_registry();
        let config = TerrainConfig::default();
        let blocks = TerrainBlocks::from_registry(&r, &config, &map).unwrap();
        let game = TerrainGenerator::with_blocks(config, blocks);
        // Around a structure, so that its glass is compared too.
        let site = generator().sites_in(-384, -384, 384, 384)[0];
        let c = site.center.map(|v| v.div_euclid(32) as i32);
        let (min, max) = (
            ChunkPos::new(c[0] - 1, 0, c[2] - 1),
            ChunkPos::new(c[0] + 1, 1, c[2] + 1),
        );
        let game_world = game.generate_world(Arc::new(r), min, max).unwrap();
        let default_world = generator()
            .generate_world(Arc::new(BlockRegistry::default()), min, max)
            .unwrap();
        // The game's id of each default id.
        let to_game = |id: BlockId| {
            if id == AIR {
                return AIR;
            }
            let role = TerrainRole::ALL
                .into_iter()
                .find(|r| r.default_block() == id)
                .unwrap();
            map.iter().find(|(r, _)| *r == role).unwrap().1
        };
        let mut roles_seen = std::collections::HashSet::new();
        for (pos, chunk) in default_world.iter() {
            let theirs = game_world.chunk(pos).unwrap().to_dense();
            let ours: Vec<BlockId> = chunk.to_dense().iter().map(|&b| to_game(b)).collect();
            assert!(ours == theirs, "chunk {pos:?} differs");
            roles_seen.extend(ours);
        }
        // The comparison covers the terrain and the structures' glass.
        assert!(roles_seen.len() >= 10, "{} block types", roles_seen.len());
    }

    #[test]
    fn chunks_at_the_i32_limits_generate() {
        let g = generator();
        for p in [
            ChunkPos::new(ChunkPos::MAX, 0, ChunkPos::MAX),
            ChunkPos::new(ChunkPos::MIN, ChunkPos::MIN, ChunkPos::MIN),
            ChunkPos::new(ChunkPos::MIN, ChunkPos::MAX, ChunkPos::MAX),
        ] {
            g.generate_chunk(p).check_invariants().unwrap();
        }
    }

    #[test]
    fn deep_and_high_chunks_are_uniform() {
        let g = generator();
        assert_eq!(
            g.generate_chunk(ChunkPos::new(0, -2, 0)).as_uniform(),
            Some(STONE)
        );
        assert_eq!(
            g.generate_chunk(ChunkPos::new(0, 3, 0)).as_uniform(),
            Some(AIR)
        );
    }

    #[test]
    fn a_level_cell_holds_the_full_detail_block_of_its_sample_column() {
        // Around the showcase's structure (glass, trees, shore and sea), at every level:
        // each cell is the block the full-detail chunks hold at its sample column.
        let g = generator();
        let site = g.sites_in(-768, -768, 768, 768)[0];
        let n = CHUNK_SIZE as i64;
        let mut kinds = std::collections::BTreeSet::new();
        for level in 0..=3u8 {
            let s = level_scale(level);
            let at = |v: i64| v.div_euclid(n * s) as i32;
            let pos = ChunkPos::new(at(site.center[0]), 0, at(site.center[2]));
            let chunk = g.generate_level_chunk(level, pos);
            let [ox, oy, oz] = level_origin(level, pos);
            // Fine chunks by position, generated once each.
            let mut fine = std::collections::HashMap::new();
            for x in (0..CHUNK_SIZE).step_by(3) {
                for z in (0..CHUNK_SIZE).step_by(3) {
                    for y in 0..CHUNK_SIZE {
                        let b = [
                            ox + x as i64 * s + s / 2,
                            oy + y as i64,
                            oz + z as i64 * s + s / 2,
                        ];
                        let c = b.map(|v| v.div_euclid(n));
                        let key = (c[0], c[1], c[2]);
                        let f = fine.entry(key).or_insert_with(|| {
                            g.generate_chunk(ChunkPos::new(c[0] as i32, c[1] as i32, c[2] as i32))
                        });
                        let l = b.map(|v| v.rem_euclid(n) as usize);
                        let want = f.get(l[0], l[1], l[2]).unwrap();
                        let got = chunk.get(x, y, z).unwrap();
                        assert_eq!(got, want, "level {level} cell {x},{y},{z} (block {b:?})");
                        kinds.insert(got.index());
                    }
                }
            }
        }
        // The sampled cells held sea, glass and leaves, not only ground.
        for id in [WATER, GLASS, LEAVES, SAND, GRASS] {
            assert!(kinds.contains(&id.index()), "no {id:?} sampled");
        }
    }

    #[test]
    fn the_sea_surface_is_at_the_same_height_at_every_level() {
        let g = generator();
        let sea = g.config().sea_level as usize;
        for level in 0..=MAX_LEVEL {
            let c = g.generate_level_chunk(level, ChunkPos::new(3, 0, -5));
            let mut water_columns = 0;
            for x in 0..CHUNK_SIZE {
                for z in 0..CHUNK_SIZE {
                    if c.get(x, sea, z).unwrap() == WATER {
                        water_columns += 1;
                        assert_ne!(c.get(x, sea + 1, z).unwrap(), WATER, "level {level}");
                    }
                }
            }
            assert!(water_columns > 0, "level {level}: no sea in the chunk");
        }
        // Levels past the coarsest are the coarsest.
        let p = ChunkPos::new(1, 0, 1);
        assert_eq!(
            g.generate_level_chunk(MAX_LEVEL + 3, p).to_dense(),
            g.generate_level_chunk(MAX_LEVEL, p).to_dense()
        );
        for p in [
            ChunkPos::new(ChunkPos::MAX, 0, ChunkPos::MIN),
            ChunkPos::new(ChunkPos::MIN, 1, ChunkPos::MAX),
        ] {
            g.generate_level_chunk(MAX_LEVEL, p)
                .check_invariants()
                .unwrap();
        }
    }

    #[test]
    fn level_cell_is_the_cell_whose_sample_column_is_the_block() {
        let n = CHUNK_SIZE as i64;
        for level in 0..=MAX_LEVEL {
            let s = level_scale(level);
            let mut held = 0;
            for x in -3 * s..3 * s {
                for (y, z) in [(-1, s / 2 + 5 * s), (40, s / 2 - 7 * s), (63, s / 2 + 1)] {
                    match level_cell(level, [x, y, z]) {
                        Some((pos, c)) => {
                            held += 1;
                            // The cell's sample column is the block's.
                            let o = level_origin(level, pos);
                            let sample = |o: i64, c: usize| o + c as i64 * s + s / 2;
                            assert_eq!(
                                [sample(o[0], c[0]), o[1] + c[1] as i64, sample(o[2], c[2])],
                                [x, y, z],
                                "level {level}"
                            );
                            assert!(c.iter().all(|&v| (v as i64) < n));
                        }
                        None => assert!(
                            (x - s / 2).rem_euclid(s) != 0 || (z - s / 2).rem_euclid(s) != 0,
                            "level {level}: ({x}, {z}) is a sample column"
                        ),
                    }
                }
            }
            // One column in `s` along x, in the two rows whose z is a sample column (the
            // third is one at level 0 only).
            let rows = if level == 0 { 3 } else { 2 };
            assert_eq!(held, 6 * rows, "level {level}");
        }
        // Level 0 holds every block; far outside the chunk coordinates, nothing.
        assert!(level_cell(0, [5, -70, -9]).is_some());
        assert_eq!(level_cell(0, [i64::MAX, 0, 0]), None);
    }

    #[test]
    fn a_level_column_is_its_chunks_generated_one_by_one() {
        let g = generator();
        let site = g.sites_in(-768, -768, 768, 768)[0];
        for level in [0, 1, 2, 4] {
            let w = CHUNK_SIZE as i64 * level_scale(level);
            let (x, z) = (
                site.center[0].div_euclid(w) as i32,
                site.center[2].div_euclid(w) as i32,
            );
            let column = g.generate_level_column(level, x, z, -1..=2);
            assert_eq!(column.len(), 4);
            for (y, c) in (-1..=2).zip(&column) {
                assert_eq!(
                    c.to_dense(),
                    g.generate_level_chunk(level, ChunkPos::new(x, y, z))
                        .to_dense(),
                    "level {level} chunk height {y}"
                );
            }
            // The column holds ground and more than ground (the site's blocks, trees).
            assert!(column.iter().map(|c| c.palette().count()).sum::<usize>() > 4);
        }
    }
}
