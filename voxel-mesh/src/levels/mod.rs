//! Far views in levels of detail: which chunks of which level cover the world around an eye
//! ([`LevelRings`]), and their meshes straight from the terrain generator
//! ([`mesh_level_chunks`]), by the same mesher into the same quads as any chunk.
//!
//! A chunk of level `k` holds 32³ cells `2^k` blocks wide in x and z and one block high
//! ([`voxel_core::TerrainGenerator::generate_level_chunk`]); level 0 is the full-detail
//! chunk. The levels lie in square rings (in x and z) around the eye, each a fixed number of
//! its own chunks wide, so that a level covers twice the distance of the one inside it
//! with as many chunks (Voxy's and clipmaps' layout): see [`LevelRings`].
//!
//! Where two levels meet, a mesh is culled against the *water* of the chunk across the
//! border (the translucent volumes the generator puts there, at the mesh's own level) and
//! against nothing else: a lake's surface runs on across the border with no wall of water
//! between the levels, and the ground's faces toward the other level are kept, so that
//! where the two levels' ground differs in height the step is closed by a wall of ground
//! (a skirt), never open to the sky.

#[cfg(not(target_arch = "wasm32"))]
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::RangeInclusive;
use std::sync::Arc;

use voxel_core::{
    BlockId, BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, Neighbourhood, RenderClass,
    TerrainGenerator, level_cell, level_scale,
};

use crate::{ChunkMeshes, Mesher, Result};

/// The layout of a far view: full detail in a square of `2 · radius + 2` chunks around the
/// eye, then one ring per level to `coarsest`, each `radius` of its own chunks from the
/// eye's, between the chunk heights `y`.
///
/// For an eye in chunk `c_k` of level `k` (`floor(eye / (32 · 2^k))` in x and z), level `k`
/// covers its chunks in the square `[2 c_{k+1} − radius, 2 c_{k+1} + radius + 1]`, less the
/// square the finer level covers, `[c_k − radius/2, c_k + radius/2]` (level `k`'s chunks,
/// which is level `k − 1`'s square exactly: `radius` is even). The eye is at least `radius`
/// chunks of level `k` from the outer edge of level `k`, so at least `radius · 2^k`
/// full-detail chunks: the view distance is `radius · 2^coarsest` chunks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LevelRings {
    /// Chunks of its own level from the eye's chunk to the edge of each level, even, 2 to
    /// 256.
    pub radius: i32,
    /// The coarsest level, 0 (full detail only) to [`voxel_core::MAX_LEVEL`].
    pub coarsest: u8,
    /// The finest level drawn, 0 to `coarsest`: it fills its whole square, the eye's
    /// chunks included (0 for a finished view; coarser while a view is built coarse first,
    /// see [`LevelRings::coarse_first`]).
    pub finest: u8,
    /// The chunk heights (y) of every level.
    pub y: RangeInclusive<i32>,
}

impl LevelRings {
    /// Rings reaching at least `view_distance` chunks from the eye with full detail to
    /// `full_detail` chunks (rounded up to an even number), for the default terrain's
    /// heights (chunks 0 and 1).
    pub fn reaching(full_detail: u32, view_distance: u32) -> Self {
        let radius = (full_detail.clamp(2, 256) as i32 + 1) & !1;
        let mut coarsest = 0u8;
        while (i64::from(radius) << coarsest) < i64::from(view_distance)
            && coarsest < voxel_core::MAX_LEVEL
        {
            coarsest += 1;
        }
        Self {
            radius,
            coarsest,
            finest: 0,
            y: 0..=1,
        }
    }

    /// Checks the fields against their ranges.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if !(2..=256).contains(&self.radius) || self.radius % 2 != 0 {
            return Err(format!(
                "ring radius {}: it must be even, from 2 to 256 chunks",
                self.radius
            ));
        }
        if self.coarsest > voxel_core::MAX_LEVEL {
            return Err(format!(
                "coarsest level {}: at most {}",
                self.coarsest,
                voxel_core::MAX_LEVEL
            ));
        }
        if self.finest > self.coarsest {
            return Err(format!(
                "finest level {} over the coarsest {}",
                self.finest, self.coarsest
            ));
        }
        if self.y.is_empty() {
            return Err(format!("empty chunk heights {:?}", self.y));
        }
        Ok(())
    }

    /// The view distance in full-detail chunks: how far the coarsest level reaches from the
    /// eye at least.
    pub fn view_distance(&self) -> i64 {
        i64::from(self.radius) << self.coarsest
    }

    /// The eye's chunk at level `level` along x and z (clamped to the `i32` chunks).
    fn eye_chunk(level: u8, eye: [f64; 3]) -> [i64; 2] {
        let w = (CHUNK_SIZE as i64 * level_scale(level)) as f64;
        let c = |v: f64| {
            let c = (v / w).floor();
            if c.is_nan() {
                0
            } else {
                c.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i64
            }
        };
        [c(eye[0]), c(eye[2])]
    }

    /// The square of level `level`'s chunks its ring fills (x and z, inclusive) and the
    /// square inside it it leaves to the finer level (none at level 0).
    fn squares(&self, level: u8, eye: [f64; 3]) -> ([[i64; 2]; 2], Option<[[i64; 2]; 2]>) {
        let r = i64::from(self.radius);
        let up = Self::eye_chunk(level + 1, eye);
        let outer = up.map(|c| [2 * c - r, 2 * c + r + 1]);
        let inner = (level > self.finest)
            .then(|| Self::eye_chunk(level, eye).map(|c| [c - r / 2, c + r / 2]));
        (outer, inner)
    }

    /// Whether chunk `pos` of level `level` is drawn for an eye at `eye` (world blocks).
    pub fn contains(&self, level: u8, pos: ChunkPos, eye: [f64; 3]) -> bool {
        if level > self.coarsest || level < self.finest || !self.y.contains(&pos.y) {
            return false;
        }
        let (outer, inner) = self.squares(level, eye);
        let p = [i64::from(pos.x), i64::from(pos.z)];
        let within = |s: [[i64; 2]; 2]| (0..2).all(|k| (s[k][0]..=s[k][1]).contains(&p[k]));
        within(outer) && !inner.is_some_and(within)
    }

    /// The chunks of level `level` drawn for an eye at `eye`, nearest first.
    pub fn chunks(&self, level: u8, eye: [f64; 3]) -> Vec<ChunkPos> {
        if level > self.coarsest || level < self.finest {
            return Vec::new();
        }
        let (outer, _) = self.squares(level, eye);
        let c = Self::eye_chunk(level, eye);
        let mut out = Vec::new();
        for x in outer[0][0]..=outer[0][1] {
            for z in outer[1][0]..=outer[1][1] {
                let (Ok(xi), Ok(zi)) = (i32::try_from(x), i32::try_from(z)) else {
                    continue;
                };
                for y in self.y.clone() {
                    let p = ChunkPos::new(xi, y, zi);
                    if p.is_valid() && self.contains(level, p, eye) {
                        out.push(p);
                    }
                }
            }
        }
        out.sort_by_key(|p| {
            let d = [i64::from(p.x) - c[0], i64::from(p.z) - c[1]];
            (d[0] * d[0] + d[1] * d[1], *p)
        });
        out
    }

    /// Every level's chunks for an eye at `eye`: coarsest level first (the horizon comes
    /// first), each level's nearest first.
    pub fn all(&self, eye: [f64; 3]) -> Vec<(u8, ChunkPos)> {
        (self.finest..=self.coarsest)
            .rev()
            .flat_map(|l| self.chunks(l, eye).into_iter().map(move |p| (l, p)))
            .collect()
    }
}

impl LevelRings {
    /// The same rings with level `finest` the finest drawn, filling its square: the view a
    /// far view is built through, coarse first (its coarsest level alone, then one level
    /// finer at a time), each a whole view with no hole and nothing drawn twice.
    pub fn coarse_first(&self, finest: u8) -> Self {
        Self {
            finest: finest.min(self.coarsest),
            ..self.clone()
        }
    }

    /// Which of the 26 neighbours of chunk `pos` of level `level` the rings hold at that
    /// level or lie above or below the rings' heights (bit `i`:
    /// [`Neighbourhood::OFFSETS`]`[i]`): what its mesh depends on besides the terrain (a
    /// neighbour across a level border counts by its water only).
    pub fn neighbours_held(&self, level: u8, pos: ChunkPos, eye: [f64; 3]) -> u32 {
        Neighbourhood::OFFSETS
            .iter()
            .enumerate()
            .filter(|(_, d)| {
                pos.offset(**d)
                    .is_some_and(|n| self.contains(level, n, eye) || !self.y.contains(&n.y))
            })
            .fold(0, |m, (i, _)| m | 1 << i)
    }
}

/// Generated level chunks kept between calls of [`mesh_level_chunks_with`]: the
/// neighbours one batch of chunks reads are mostly the chunks of the next, generated once.
/// Holds at most [`LevelCache::LIMIT`] chunks (emptied when full), and the edits made to the
/// generated terrain ([`LevelCache::edit`]), which every chunk it generates carries.
#[derive(Debug, Default)]
pub struct LevelCache {
    chunks: HashMap<(u8, ChunkPos), Arc<Chunk>>,
    /// Edited cells (within their chunk) by level chunk.
    edits: HashMap<(u8, ChunkPos), HashMap<[usize; 3], BlockId>>,
    edit_count: u64,
}

impl LevelCache {
    /// The most chunks kept: about 64 MiB of generated terrain.
    pub const LIMIT: usize = 4096;

    /// Chunks held.
    pub fn len(&self) -> usize {
        self.chunks.len()
    }

    /// Whether it holds nothing.
    pub fn is_empty(&self) -> bool {
        self.chunks.is_empty()
    }

    /// Sets the world block at `block` to `id` in the terrain of every level that holds it
    /// (every level whose cell samples that block's column: [`voxel_core::level_cell`]);
    /// the chunks it generates from now on carry the edit, and those it held that the edit
    /// changes are dropped. A later edit of the same block replaces it.
    pub fn edit(&mut self, block: [i64; 3], id: BlockId) {
        self.edit_count += 1;
        for level in 0..=voxel_core::MAX_LEVEL {
            if let Some((pos, cell)) = level_cell(level, block) {
                self.edits.entry((level, pos)).or_default().insert(cell, id);
                self.chunks.remove(&(level, pos));
            }
        }
    }

    /// How many edits [`LevelCache::edit`] took so far.
    pub fn edit_count(&self) -> u64 {
        self.edit_count
    }

    /// The chunks of level `level` at x and z of `first`, from `first`'s height to
    /// `last_y`, of `generator`'s terrain with the edits made to them (a column generated
    /// at once: [`TerrainGenerator::generate_level_column`]).
    fn generate(
        &self,
        generator: &TerrainGenerator,
        level: u8,
        first: ChunkPos,
        last_y: i32,
    ) -> Vec<((u8, ChunkPos), Arc<Chunk>)> {
        let column = generator.generate_level_column(level, first.x, first.z, first.y..=last_y);
        (first.y..=last_y)
            .zip(column)
            .map(|(y, mut chunk)| {
                let pos = ChunkPos::new(first.x, y, first.z);
                if let Some(edits) = self.edits.get(&(level, pos)) {
                    for (&[x, y, z], &id) in edits {
                        // Cells of a chunk: always in range.
                        let _ = chunk.set(x, y, z, id);
                    }
                    chunk.pack();
                }
                ((level, pos), Arc::new(chunk))
            })
            .collect()
    }
}

/// The level chunks whose meshes an edit of the world block at `block` changes: at every
/// level that holds it ([`voxel_core::level_cell`]), the chunk of its cell and those beside
/// it that cull and shade against that cell (the cell on their border, diagonals included).
pub fn chunks_an_edit_changes(block: [i64; 3]) -> Vec<(u8, ChunkPos)> {
    let n = CHUNK_SIZE as i64;
    let mut out = Vec::new();
    for level in 0..=voxel_core::MAX_LEVEL {
        let Some((pos, cell)) = level_cell(level, block) else {
            continue;
        };
        // Per axis, the chunk offsets whose 1-cell margin holds the cell.
        let reach = |c: usize| match c as i64 {
            0 => -1..=0,
            c if c == n - 1 => 0..=1,
            _ => 0..=0,
        };
        for dx in reach(cell[0]) {
            for dy in reach(cell[1]) {
                for dz in reach(cell[2]) {
                    if let Some(p) = pos.offset([dx, dy, dz]) {
                        out.push((level, p));
                    }
                }
            }
        }
    }
    out
}

/// The meshes of the level chunks `chunks` of generator `generator` (over `registry`), for
/// rings `rings` and an eye at `eye`: each culled against its level's chunks around it where
/// the rings hold them, against only the water of the chunk across a level border (see the
/// module docs), and against air above and below the rings' heights. Generated and meshed
/// in parallel (one after another on wasm32), with ambient occlusion at every level: a
/// coarse cell's occlusion spans the cell, which darkens a far slope about as much as the
/// fine steps it replaces do on average (without it the far ground came out 5.4/255 lighter
/// than full detail; with it 1.4/255: `demo far --compare`).
pub fn mesh_level_chunks(
    generator: &TerrainGenerator,
    registry: &BlockRegistry,
    rings: &LevelRings,
    eye: [f64; 3],
    chunks: &[(u8, ChunkPos)],
) -> Result<Vec<(u8, ChunkPos, ChunkMeshes)>> {
    let mut cache = LevelCache::default();
    mesh_level_chunks_with(&mut cache, generator, registry, rings, eye, chunks)
}

/// [`mesh_level_chunks`], generating only the chunks `cache` lacks (and keeping them).
pub fn mesh_level_chunks_with(
    cache: &mut LevelCache,
    generator: &TerrainGenerator,
    registry: &BlockRegistry,
    rings: &LevelRings,
    eye: [f64; 3],
    chunks: &[(u8, ChunkPos)],
) -> Result<Vec<(u8, ChunkPos, ChunkMeshes)>> {
    // Every chunk a mesh reads: its own and its 26 neighbours within the rings' heights,
    // each at the mesh's level.
    let mut needed: Vec<(u8, ChunkPos)> = chunks
        .iter()
        .flat_map(|&(l, p)| {
            Neighbourhood::OFFSETS
                .iter()
                .filter_map(move |&d| p.offset(d).map(|n| (l, n)))
                .chain([(l, p)])
        })
        .filter(|(_, p)| rings.y.contains(&p.y))
        .collect();
    needed.sort_unstable();
    needed.dedup();
    let lacking: Vec<(u8, ChunkPos)> = needed
        .iter()
        .filter(|k| !cache.chunks.contains_key(k))
        .copied()
        .collect();
    if cache.chunks.len() + lacking.len() > LevelCache::LIMIT {
        cache.chunks.retain(|k, _| needed.binary_search(k).is_ok());
    }
    // Generated a column at a time (the heights and trees found once for the chunks
    // above each other): runs of lacking chunks that differ only in y, adjacent once
    // sorted by level, x, z and y.
    let mut by_column = lacking;
    by_column.sort_unstable_by_key(|&(l, p)| (l, p.x, p.z, p.y));
    let mut columns: Vec<(u8, ChunkPos, i32)> = Vec::new();
    for &(l, p) in &by_column {
        match columns.last_mut() {
            Some((cl, c, last)) if *cl == l && c.x == p.x && c.z == p.z && *last + 1 == p.y => {
                *last = p.y;
            }
            _ => columns.push((l, p, p.y)),
        }
    }
    let made = &*cache;
    let make = |&(l, p, last): &(u8, ChunkPos, i32)| made.generate(generator, l, p, last);
    #[cfg(not(target_arch = "wasm32"))]
    let new: Vec<_> = columns.par_iter().flat_map_iter(make).collect();
    #[cfg(target_arch = "wasm32")]
    let new: Vec<_> = columns.iter().flat_map(make).collect();
    cache.chunks.extend(new);

    let mut water = vec![false; registry.len()];
    for (id, d) in registry.iter() {
        if let Some(w) = water.get_mut(id.index()) {
            *w = d.class == RenderClass::Translucent && d.absorption > 0.0;
        }
    }
    // Across a level border (in x or z) only the water counts.
    let across: HashMap<(u8, ChunkPos), Chunk> = needed
        .iter()
        .filter(|&&(l, p)| !rings.contains(l, p, eye))
        .filter_map(|k| cache.chunks.get(k).map(|c| (*k, only(c, &water))))
        .collect();
    let made = &cache.chunks;
    let get = |k: &(u8, ChunkPos)| across.get(k).or_else(|| made.get(k).map(|c| &**c));
    let mesh = |mesher: &mut Mesher, &(l, p): &(u8, ChunkPos)| {
        let around = Neighbourhood::from_fn(|d| p.offset(d).and_then(|n| get(&(l, n))));
        let meshes = match get(&(l, p)) {
            Some(c) => mesher.mesh(c, around)?,
            None => ChunkMeshes::default(),
        };
        Ok((l, p, meshes))
    };
    #[cfg(not(target_arch = "wasm32"))]
    let out = chunks
        .par_iter()
        .map_init(|| Mesher::new(registry), mesh)
        .collect();
    #[cfg(target_arch = "wasm32")]
    let out = {
        let mut m = Mesher::new(registry);
        chunks.iter().map(|c| mesh(&mut m, c)).collect()
    };
    out
}

/// `chunk` with only the blocks `keep` marks (by id), air elsewhere.
fn only(chunk: &Chunk, keep: &[bool]) -> Chunk {
    let kept = |id: voxel_core::BlockId| keep.get(id.index()).copied().unwrap_or(false);
    if !chunk.palette().any(|(id, _)| kept(id)) {
        return Chunk::default();
    }
    let mut out = Chunk::default();
    for x in 0..CHUNK_SIZE {
        for z in 0..CHUNK_SIZE {
            for y in 0..CHUNK_SIZE {
                if let Ok(id) = chunk.get(x, y, z)
                    && kept(id)
                {
                    // In range: the loops stay inside the chunk.
                    let _ = out.set(x, y, z, id);
                }
            }
        }
    }
    out.pack();
    out
}

#[cfg(test)]
mod tests;
