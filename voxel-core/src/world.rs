//! Chunks keyed by chunk coordinates, block access by world coordinate, and the dirty set
//! that tells the mesher what to rebuild.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use rayon::prelude::*;

use crate::{BlockId, BlockRegistry, CHUNK_SIZE, Chunk, Error, RenderClass, Result};

/// The six face directions, in the order used everywhere (mesher, quads, neighbours).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Face {
    /// +x
    PosX = 0,
    /// -x
    NegX = 1,
    /// +y (up)
    PosY = 2,
    /// -y (down)
    NegY = 3,
    /// +z
    PosZ = 4,
    /// -z
    NegZ = 5,
}

impl Face {
    /// All faces, indexed by their discriminant.
    pub const ALL: [Face; 6] = [
        Face::PosX,
        Face::NegX,
        Face::PosY,
        Face::NegY,
        Face::PosZ,
        Face::NegZ,
    ];

    /// The face with discriminant `i` (taken modulo nothing: `i` must be below 6).
    pub fn from_index(i: usize) -> Option<Face> {
        Self::ALL.get(i).copied()
    }

    /// The axis of the normal: 0 = x, 1 = y, 2 = z.
    pub fn axis(self) -> usize {
        self as usize / 2
    }

    /// Whether the normal points along +axis.
    pub fn is_positive(self) -> bool {
        (self as usize).is_multiple_of(2)
    }

    /// The outward unit normal.
    pub fn normal(self) -> [i32; 3] {
        let mut n = [0; 3];
        n[self.axis()] = if self.is_positive() { 1 } else { -1 };
        n
    }

    /// The face pointing the other way.
    pub fn opposite(self) -> Face {
        Self::ALL[self as usize ^ 1]
    }
}

/// A block position in the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WorldPos {
    /// x
    pub x: i32,
    /// y (up)
    pub y: i32,
    /// z
    pub z: i32,
}

impl WorldPos {
    /// A world position.
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// The block's lowest corner, in world units (the block fills it to `corner + 1`).
    pub fn corner(self) -> [f64; 3] {
        [self.x, self.y, self.z].map(f64::from)
    }

    /// The chunk holding this block and the block's local coordinates in it.
    /// Defined for every `i32` position (floor division, so -1 is in chunk -1 at local 31).
    pub fn split(self) -> (ChunkPos, [usize; 3]) {
        let s = CHUNK_SIZE as i32;
        let c = ChunkPos::new(
            self.x.div_euclid(s),
            self.y.div_euclid(s),
            self.z.div_euclid(s),
        );
        let l = [self.x, self.y, self.z].map(|v| v.rem_euclid(s) as usize);
        (c, l)
    }
}

/// A chunk's position in chunk units: chunk `(1, 0, 0)` holds world x `32..64`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ChunkPos {
    /// x in chunks
    pub x: i32,
    /// y in chunks
    pub y: i32,
    /// z in chunks
    pub z: i32,
}

impl ChunkPos {
    /// Smallest chunk coordinate whose blocks fit the `i32` world: -2^26.
    pub const MIN: i32 = i32::MIN / CHUNK_SIZE as i32;
    /// Largest chunk coordinate whose blocks fit the `i32` world: 2^26 - 1.
    pub const MAX: i32 = i32::MAX / CHUNK_SIZE as i32;

    /// A chunk position (not checked: see [`ChunkPos::is_valid`]).
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// Whether all of the chunk's blocks have `i32` world coordinates.
    pub fn is_valid(self) -> bool {
        [self.x, self.y, self.z]
            .iter()
            .all(|v| (Self::MIN..=Self::MAX).contains(v))
    }

    /// World coordinates of the chunk's block `(0, 0, 0)`, as `i64` so that no chunk
    /// position overflows.
    pub fn origin(self) -> [i64; 3] {
        [self.x, self.y, self.z].map(|v| i64::from(v) * CHUNK_SIZE as i64)
    }

    /// The adjacent chunk across `face`, or `None` past the edge of the `i32` world.
    pub fn neighbour(self, face: Face) -> Option<ChunkPos> {
        self.offset(face.normal())
    }

    /// The chunk `d` chunks away, or `None` past the edge of the `i32` world.
    pub fn offset(self, d: [i32; 3]) -> Option<ChunkPos> {
        let p = ChunkPos::new(
            self.x.checked_add(d[0])?,
            self.y.checked_add(d[1])?,
            self.z.checked_add(d[2])?,
        );
        p.is_valid().then_some(p)
    }
}

/// The 26 chunks around a chunk, by offset (each component -1, 0 or 1, not all 0): its 6
/// face, 12 edge and 8 corner neighbours. `None` counts as air. Face neighbours decide which
/// faces a chunk shows; ambient occlusion at a chunk's edges and corners also reads the
/// blocks of the edge and corner neighbours that touch it.
#[derive(Clone, Copy, Debug, Default)]
pub struct Neighbourhood<'a> {
    /// By `(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)`; the centre (13) stays `None`.
    chunks: [Option<&'a Chunk>; 27],
}

impl<'a> Neighbourhood<'a> {
    /// The 26 offsets, faces first (in [`Face`] order), then edges, then corners.
    pub const OFFSETS: [[i32; 3]; 26] = {
        let mut out = [[0; 3]; 26];
        let faces = [
            [1, 0, 0],
            [-1, 0, 0],
            [0, 1, 0],
            [0, -1, 0],
            [0, 0, 1],
            [0, 0, -1],
        ];
        let mut n = 0;
        while n < 6 {
            out[n] = faces[n];
            n += 1;
        }
        // Then the offsets with two non-zero components (edges), then three (corners).
        let mut nonzero = 2;
        while nonzero <= 3 {
            let mut i = 0;
            while i < 27 {
                let d = [i / 9 - 1, i / 3 % 3 - 1, i % 3 - 1];
                if (d[0] != 0) as i32 + (d[1] != 0) as i32 + (d[2] != 0) as i32 == nonzero {
                    out[n] = d;
                    n += 1;
                }
                i += 1;
            }
            nonzero += 1;
        }
        out
    };

    fn index(d: [i32; 3]) -> Option<usize> {
        let ok = d.iter().all(|v| (-1..=1).contains(v)) && d != [0; 3];
        ok.then(|| ((d[0] + 1) * 9 + (d[1] + 1) * 3 + (d[2] + 1)) as usize)
    }

    /// Each neighbour from `get(offset)`.
    pub fn from_fn(mut get: impl FnMut([i32; 3]) -> Option<&'a Chunk>) -> Self {
        let mut n = Self::default();
        for d in Self::OFFSETS {
            if let Some(i) = Self::index(d) {
                n.chunks[i] = get(d);
            }
        }
        n
    }

    /// Only the six face neighbours (in [`Face`] order); edges and corners count as air.
    pub fn faces(faces: [Option<&'a Chunk>; 6]) -> Self {
        Self::from_fn(|d| {
            Face::ALL
                .iter()
                .position(|f| f.normal() == d)
                .and_then(|i| faces[i])
        })
    }

    /// The neighbour at offset `d`; `None` for air, the centre, or an offset beyond one
    /// chunk.
    pub fn get(&self, d: [i32; 3]) -> Option<&'a Chunk> {
        Self::index(d).and_then(|i| self.chunks[i])
    }

    /// The face neighbour across `face`.
    pub fn face(&self, face: Face) -> Option<&'a Chunk> {
        self.get(face.normal())
    }
}

impl<'a> From<[Option<&'a Chunk>; 6]> for Neighbourhood<'a> {
    fn from(faces: [Option<&'a Chunk>; 6]) -> Self {
        Self::faces(faces)
    }
}

/// The neighbours (offsets of [`Neighbourhood::OFFSETS`]) whose meshes depend on the block
/// at local `local` of a chunk: a block on a chunk's face touches that face neighbour, on
/// an edge also the edge neighbour, on a corner also the corner neighbours (ambient
/// occlusion reads diagonal blocks).
pub fn touched_neighbours(local: [usize; 3]) -> impl Iterator<Item = [i32; 3]> {
    let last = CHUNK_SIZE - 1;
    Neighbourhood::OFFSETS.into_iter().filter(move |d| {
        (0..3).all(|a| match d[a] {
            1 => local[a] == last,
            -1 => local[a] == 0,
            _ => true,
        })
    })
}

/// `v` scaled to length 1, computed so that no finite non-zero vector overflows or
/// underflows on the way (`[1e300; 3]`, `[f64::MAX, 0, 0]` and `[1e-320, 0, 0]` all have a
/// direction): first divided by its largest component, then by its length. An error that
/// says what is wrong for a vector with a NaN or infinite component, or all zero.
pub fn unit_direction(v: [f64; 3]) -> std::result::Result<[f64; 3], &'static str> {
    if !v.iter().all(|c| c.is_finite()) {
        return Err("every component must be finite");
    }
    let largest = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if largest == 0.0 {
        return Err("it is zero: a direction needs a non-zero component");
    }
    let scaled = v.map(|c| c / largest);
    let length = scaled.iter().map(|c| c * c).sum::<f64>().sqrt();
    Ok(scaled.map(|c| c / length))
}

/// The farthest [`World::raycast`] looks, in blocks: 2^16, 32 times the largest view
/// distance (64 chunks, 2048 blocks), and at most about 200 000 steps (a few milliseconds).
pub const MAX_RAY_DISTANCE: f64 = 65_536.0;

/// What [`World::raycast`] hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The block hit.
    pub pos: WorldPos,
    /// Its type.
    pub block: BlockId,
    /// The face the ray entered it through (its normal points back along the ray).
    pub face: Face,
    /// Distance from the origin to where the ray enters the block, in blocks.
    pub distance: f64,
}

impl RayHit {
    /// The cell in front of the face hit: where a block placed against that face goes
    /// (`None` past the edge of the `i32` world).
    pub fn adjacent(&self) -> Option<WorldPos> {
        let n = self.face.normal();
        let p = [self.pos.x, self.pos.y, self.pos.z];
        let q = [0, 1, 2].map(|a| i64::from(p[a]) + i64::from(n[a]));
        to_world_pos(q)
    }
}

/// A cell as a world position, if it lies in the `i32` world.
fn to_world_pos(c: [i64; 3]) -> Option<WorldPos> {
    Some(WorldPos::new(
        i32::try_from(c[0]).ok()?,
        i32::try_from(c[1]).ok()?,
        i32::try_from(c[2]).ok()?,
    ))
}

/// A sparse world of chunks over one block registry. Chunks are shared (`Arc`): cloning a
/// world, or handing a chunk to a meshing job ([`World::shared`]), copies no blocks; an
/// edit copies a chunk only while someone else still holds it.
#[derive(Debug, Clone)]
pub struct World {
    registry: Arc<BlockRegistry>,
    chunks: HashMap<ChunkPos, Arc<Chunk>>,
    dirty: HashSet<ChunkPos>,
}

impl World {
    /// An empty world. Missing chunks read as air.
    pub fn new(registry: Arc<BlockRegistry>) -> Self {
        Self {
            registry,
            chunks: HashMap::new(),
            dirty: HashSet::new(),
        }
    }

    /// The block registry every chunk's ids refer to.
    pub fn registry(&self) -> &Arc<BlockRegistry> {
        &self.registry
    }

    /// The translucent block type at `point` (world block units; the block containing
    /// it), or the medium a block there stands in ([`crate::BlockDef::medium`]), or `None`
    /// when neither, or the point is not finite or lies outside the `i32` world: what an
    /// eye at `point` is immersed in.
    pub fn medium_at(&self, point: [f64; 3]) -> Option<BlockId> {
        let inside =
            |v: f64| v.is_finite() && v >= f64::from(i32::MIN) && v < f64::from(i32::MAX) + 1.0;
        if !point.iter().all(|&v| inside(v)) {
            return None;
        }
        let p = point.map(|v| v.floor() as i32);
        let id = self.get_block(WorldPos::new(p[0], p[1], p[2]));
        let def = self.registry.get(id).ok()?;
        // A block standing in a medium (waterlogged kelp) is in that medium.
        def.medium
            .or((def.class == crate::RenderClass::Translucent).then_some(id))
    }

    /// The block at `pos`; air where no chunk is loaded.
    pub fn get_block(&self, pos: WorldPos) -> BlockId {
        let (c, [x, y, z]) = pos.split();
        self.chunks
            .get(&c)
            .and_then(|chunk| chunk.get(x, y, z).ok())
            .unwrap_or(BlockId::AIR)
    }

    /// Sets the block at `pos` (creating an air chunk if needed) and returns the old one.
    /// Marks the chunk dirty, and each loaded neighbour whose border the block touches.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> Result<BlockId> {
        if !self.registry.contains(id) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        let (c, [x, y, z]) = pos.split();
        if id == BlockId::AIR && !self.chunks.contains_key(&c) {
            return Ok(BlockId::AIR);
        }
        let old = Arc::make_mut(self.chunks.entry(c).or_default()).set(x, y, z, id)?;
        if old != id {
            self.dirty.insert(c);
            for d in touched_neighbours([x, y, z]) {
                if let Some(n) = c.offset(d).filter(|n| self.chunks.contains_key(n)) {
                    self.dirty.insert(n);
                }
            }
        }
        Ok(old)
    }

    /// Sets every block of the box `min..=max` to `id`, a chunk at a time. Marks the
    /// touched chunks and their loaded neighbours dirty. Chunks are created only to hold a
    /// block that is not air.
    pub fn fill_box(&mut self, min: WorldPos, max: WorldPos, id: BlockId) -> Result<()> {
        if !self.registry.contains(id) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        if min.x > max.x || min.y > max.y || min.z > max.z {
            return Ok(());
        }
        let (c0, _) = min.split();
        let (c1, _) = max.split();
        let last = CHUNK_SIZE as i64 - 1;
        for cx in c0.x..=c1.x {
            for cy in c0.y..=c1.y {
                for cz in c0.z..=c1.z {
                    let pos = ChunkPos::new(cx, cy, cz);
                    let o = pos.origin();
                    let lo = [min.x, min.y, min.z]
                        .iter()
                        .zip(o)
                        .map(|(&m, o)| (i64::from(m) - o).clamp(0, last) as usize)
                        .collect::<Vec<_>>();
                    let hi = [max.x, max.y, max.z]
                        .iter()
                        .zip(o)
                        .map(|(&m, o)| (i64::from(m) - o).clamp(0, last) as usize)
                        .collect::<Vec<_>>();
                    if id == BlockId::AIR && !self.chunks.contains_key(&pos) {
                        continue;
                    }
                    Arc::make_mut(self.chunks.entry(pos).or_default()).fill_box(
                        [lo[0], lo[1], lo[2]],
                        [hi[0], hi[1], hi[2]],
                        id,
                    )?;
                    self.mark_with_neighbours(pos);
                }
            }
        }
        Ok(())
    }

    /// Puts a whole chunk in place (returning the one it replaces) and marks it and its
    /// loaded neighbours dirty. Fails on a position outside the `i32` world or a block id the
    /// registry does not hold.
    pub fn insert_chunk(&mut self, pos: ChunkPos, chunk: Chunk) -> Result<Option<Chunk>> {
        if !pos.is_valid() {
            return Err(Error::ChunkOutOfRange(pos));
        }
        if let Some((id, _)) = chunk.palette().find(|(id, _)| !self.registry.contains(*id)) {
            return Err(Error::UnknownBlock(id, self.registry.len()));
        }
        self.mark_with_neighbours(pos);
        Ok(self
            .chunks
            .insert(pos, Arc::new(chunk))
            .map(Arc::unwrap_or_clone))
    }

    /// Unloads a chunk; it and its loaded neighbours become dirty (the mesher then returns
    /// empty meshes for it).
    pub fn remove_chunk(&mut self, pos: ChunkPos) -> Option<Chunk> {
        let old = self.chunks.remove(&pos).map(Arc::unwrap_or_clone);
        if old.is_some() {
            self.mark_with_neighbours(pos);
        }
        old
    }

    /// Marks `pos` and its loaded neighbours (all 26: ambient occlusion reads diagonal
    /// blocks) dirty.
    fn mark_with_neighbours(&mut self, pos: ChunkPos) {
        self.dirty.insert(pos);
        for d in Neighbourhood::OFFSETS {
            if let Some(n) = pos.offset(d).filter(|n| self.chunks.contains_key(n)) {
                self.dirty.insert(n);
            }
        }
    }

    /// The chunk at `pos`, if loaded.
    pub fn chunk(&self, pos: ChunkPos) -> Option<&Chunk> {
        self.chunks.get(&pos).map(|c| &**c)
    }

    /// The chunk at `pos` as a shared handle (for a job on another thread), if loaded.
    pub fn shared(&self, pos: ChunkPos) -> Option<Arc<Chunk>> {
        self.chunks.get(&pos).cloned()
    }

    /// Puts `chunk` at `pos` in place of `expected` (the same blocks in another form, say
    /// packed by a meshing job), if the chunk there is still exactly `expected`: an edit or
    /// a replacement since wins. Nothing becomes dirty. Returns whether it was replaced.
    pub fn replace_shared(&mut self, pos: ChunkPos, expected: &Arc<Chunk>, chunk: Chunk) -> bool {
        match self.chunks.get_mut(&pos) {
            Some(c) if Arc::ptr_eq(c, expected) => {
                *c = Arc::new(chunk);
                true
            }
            _ => false,
        }
    }

    /// Converts the chunk at `pos` to the compact packed form (see [`Chunk::pack`]), e.g.
    /// once a streamer has meshed it. Blocks do not change, so nothing becomes dirty.
    /// Returns whether a chunk is loaded there.
    pub fn pack_chunk(&mut self, pos: ChunkPos) -> bool {
        self.chunks
            .get_mut(&pos)
            .map(|c| Arc::make_mut(c).pack())
            .is_some()
    }

    /// Converts the chunk at `pos` to the mask form (see [`Chunk::unpack`]), e.g. for a chunk
    /// about to be edited and remeshed often. Returns whether a chunk is loaded there.
    pub fn unpack_chunk(&mut self, pos: ChunkPos) -> bool {
        self.chunks
            .get_mut(&pos)
            .map(|c| Arc::make_mut(c).unpack())
            .is_some()
    }

    /// Packs every loaded chunk, in parallel.
    pub fn pack_all(&mut self) {
        self.chunks
            .par_iter_mut()
            .for_each(|(_, c)| Arc::make_mut(c).pack());
    }

    /// Heap and inline bytes of the loaded chunks ([`Chunk::memory_bytes`] summed; the map
    /// itself not counted).
    pub fn chunk_memory_bytes(&self) -> usize {
        self.chunks.values().map(|c| c.memory_bytes()).sum()
    }

    /// What the loaded chunks would take as packed-index palettes
    /// ([`Chunk::packed_index_bytes`] summed): the baseline of [`World::chunk_memory_bytes`].
    pub fn packed_index_bytes(&self) -> usize {
        self.chunks.values().map(|c| c.packed_index_bytes()).sum()
    }

    /// The first block along the ray from `origin` in `direction` (any length but zero)
    /// within `max_distance` blocks whose render class is one of `stops`, by a voxel walk
    /// (Amanatides & Woo 1987), or `None`. The block holding the origin is not tested: a
    /// ray cast from inside a block finds what lies beyond it. Chunks that are not loaded
    /// are air.
    ///
    /// Fails on an origin that is not finite or lies outside the `i32` world, a direction
    /// that is zero or not finite, and a `max_distance` that is negative, NaN or beyond
    /// [`MAX_RAY_DISTANCE`].
    pub fn raycast(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        max_distance: f64,
        stops: &[RenderClass],
    ) -> Result<Option<RayHit>> {
        let bad = |reason: String| Err(Error::InvalidRay(reason));
        let inside = |v: f64| v >= f64::from(i32::MIN) && v < f64::from(i32::MAX) + 1.0;
        if !origin.iter().all(|&v| v.is_finite() && inside(v)) {
            return bad(format!(
                "origin {origin:?} must be finite and inside the i32 world"
            ));
        }
        let dir = match unit_direction(direction) {
            Ok(dir) => dir,
            Err(why) => return bad(format!("direction {direction:?}: {why}")),
        };
        if !(0.0..=MAX_RAY_DISTANCE).contains(&max_distance) {
            return bad(format!(
                "max distance {max_distance} must be from 0 to {MAX_RAY_DISTANCE} blocks"
            ));
        }
        let mut cell = origin.map(|v| v.floor() as i64);
        let step = dir.map(|d| if d > 0.0 { 1 } else { -1 });
        // Distance along the ray to the next cell boundary on each axis, and between
        // boundaries.
        let mut t_max = [0.0; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for a in 0..3 {
            t_max[a] = if dir[a] == 0.0 {
                f64::INFINITY
            } else {
                let next = cell[a] as f64 + if dir[a] > 0.0 { 1.0 } else { 0.0 };
                t_delta[a] = 1.0 / dir[a].abs();
                (next - origin[a]) / dir[a]
            };
        }
        loop {
            let axis = (0..3)
                .min_by(|&a, &b| t_max[a].total_cmp(&t_max[b]))
                .unwrap_or(0);
            let t = t_max[axis];
            if t > max_distance {
                return Ok(None);
            }
            cell[axis] += step[axis];
            t_max[axis] += t_delta[axis];
            let Some(pos) = to_world_pos(cell) else {
                return Ok(None);
            };
            let block = self.get_block(pos);
            if self.registry.class(block).is_ok_and(|c| stops.contains(&c)) {
                let face = Face::ALL[2 * axis + usize::from(step[axis] > 0)];
                return Ok(Some(RayHit {
                    pos,
                    block,
                    face,
                    distance: t,
                }));
            }
        }
    }

    /// The 26 chunks around `pos` (what the mesher needs); `None` where not loaded.
    pub fn neighbourhood(&self, pos: ChunkPos) -> Neighbourhood<'_> {
        Neighbourhood::from_fn(|d| pos.offset(d).and_then(|n| self.chunk(n)))
    }

    /// All loaded chunks, in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = (ChunkPos, &Chunk)> {
        self.chunks.iter().map(|(p, c)| (*p, &**c))
    }

    /// Number of loaded chunks.
    pub fn len(&self) -> usize {
        self.chunks.len()
    }

    /// Whether no chunk is loaded.
    pub fn is_empty(&self) -> bool {
        self.chunks.is_empty()
    }

    /// Chunks waiting to be remeshed.
    pub fn dirty(&self) -> &HashSet<ChunkPos> {
        &self.dirty
    }

    /// Marks a chunk for remeshing.
    pub fn mark_dirty(&mut self, pos: ChunkPos) {
        self.dirty.insert(pos);
    }

    /// Empties the dirty set and returns it, sorted so that work is reproducible.
    pub fn take_dirty(&mut self) -> Vec<ChunkPos> {
        let mut v: Vec<_> = self.dirty.drain().collect();
        v.sort_unstable();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blocks::*;

    const SOLID: [RenderClass; 3] = RenderClass::VISIBLE;

    /// A 5 x 5 wall of stone at z = -5 with a glass block in front of its centre at z = -3.
    fn wall() -> World {
        let mut w = World::new(Arc::new(BlockRegistry::default()));
        w.fill_box(WorldPos::new(-2, -2, -5), WorldPos::new(2, 2, -5), STONE)
            .unwrap();
        w.set_block(WorldPos::new(0, 0, -3), GLASS).unwrap();
        w
    }

    #[test]
    fn raycast_finds_the_first_block_of_the_classes_asked() {
        let w = wall();
        let o = [0.5, 0.5, 0.5];
        let hit = w
            .raycast(o, [0.0, 0.0, -2.0], 20.0, &SOLID)
            .unwrap()
            .unwrap();
        assert_eq!(
            (hit.pos, hit.block, hit.face),
            (WorldPos::new(0, 0, -3), GLASS, Face::PosZ)
        );
        assert!((hit.distance - 2.5).abs() < 1e-12, "{}", hit.distance);
        assert_eq!(hit.adjacent(), Some(WorldPos::new(0, 0, -2)));
        // Glass does not stop a ray that asks only for opaque blocks.
        let hit = w
            .raycast(o, [0.0, 0.0, -1.0], 20.0, &[RenderClass::Opaque])
            .unwrap()
            .unwrap();
        assert_eq!((hit.pos, hit.block), (WorldPos::new(0, 0, -5), STONE));
        assert!((hit.distance - 4.5).abs() < 1e-12);
        // A diagonal ray steps one axis at a time: the cell before shares the hit face.
        let hit = w
            .raycast(
                [0.2, 0.7, 0.5],
                [0.3, -0.2, -1.0],
                20.0,
                &[RenderClass::Opaque],
            )
            .unwrap()
            .unwrap();
        assert_eq!(hit.pos.z, -5);
        assert_eq!(hit.face, Face::PosZ);
        // Rays from the side and from above name the face they enter through.
        let hit = w
            .raycast([-6.5, 0.5, -4.5], [1.0, 0.1, 0.0], 20.0, &SOLID)
            .unwrap()
            .unwrap();
        assert_eq!((hit.pos, hit.face), (WorldPos::new(-2, 0, -5), Face::NegX));
        let hit = w
            .raycast([1.5, 9.0, -4.5], [0.0, -1.0, 0.0], 20.0, &SOLID)
            .unwrap()
            .unwrap();
        assert_eq!((hit.pos, hit.face), (WorldPos::new(1, 2, -5), Face::PosY));
        assert!((hit.distance - 6.0).abs() < 1e-12);
        // Behind, too far, and the origin's own block skipped.
        assert_eq!(w.raycast(o, [0.0, 0.0, 1.0], 20.0, &SOLID).unwrap(), None);
        assert_eq!(w.raycast(o, [0.0, 0.0, -1.0], 2.4, &SOLID).unwrap(), None);
        let inside = w
            .raycast([0.5, 0.5, -2.5], [0.0, 0.0, -1.0], 20.0, &SOLID)
            .unwrap()
            .unwrap();
        assert_eq!(inside.pos, WorldPos::new(0, 0, -5));
    }

    #[test]
    fn unit_directions_survive_any_finite_length() {
        for (v, want) in [
            ([3.0, 0.0, -4.0], [0.6, 0.0, -0.8]),
            ([1e38, 1e38, 1e38], [1.0 / 3f64.sqrt(); 3]),
            ([f64::MAX, 0.0, 0.0], [1.0, 0.0, 0.0]),
            (
                [f64::MAX, f64::MAX, 0.0],
                [0.5f64.sqrt(), 0.5f64.sqrt(), 0.0],
            ),
            ([0.0, -5e-324, 0.0], [0.0, -1.0, 0.0]),
        ] {
            let u = unit_direction(v).unwrap();
            for k in 0..3 {
                assert!((u[k] - want[k]).abs() < 1e-15, "{v:?}: {u:?}");
            }
        }
        assert!(unit_direction([0.0; 3]).unwrap_err().contains("zero"));
        assert!(
            unit_direction([f64::INFINITY, 0.0, 0.0])
                .unwrap_err()
                .contains("finite")
        );
        assert!(
            unit_direction([f64::NAN, 1.0, 0.0])
                .unwrap_err()
                .contains("finite")
        );
    }

    #[test]
    fn raycast_refuses_bad_rays_and_stops_at_the_world_edge() {
        let w = wall();
        for (origin, dir, max) in [
            ([f64::NAN, 0.0, 0.0], [0.0, 0.0, -1.0], 5.0),
            ([3e9, 0.0, 0.0], [0.0, 0.0, -1.0], 5.0),
            ([0.0; 3], [0.0; 3], 5.0),
            ([0.0; 3], [f64::INFINITY, 0.0, 0.0], 5.0),
            ([0.0; 3], [0.0, 0.0, -1.0], -1.0),
            ([0.0; 3], [0.0, 0.0, -1.0], f64::NAN),
            ([0.0; 3], [0.0, 0.0, -1.0], MAX_RAY_DISTANCE * 2.0),
        ] {
            let err = w.raycast(origin, dir, max, &SOLID).unwrap_err();
            assert!(matches!(err, Error::InvalidRay(_)), "{err}");
        }
        let e = w
            .raycast([0.0; 3], [0.0, f64::NAN, -1.0], 5.0, &SOLID)
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite") && !e.contains("zero"), "{e}");
        let e = w
            .raycast([0.0; 3], [0.0; 3], 5.0, &SOLID)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zero"), "{e}");
        // Finite directions whose squared length overflows or underflows are directions.
        let o = [0.5, 0.5, 0.5];
        for dir in [
            [0.0, 0.0, -1e300],
            [0.0, 0.0, -f64::MAX],
            [0.0, 0.0, -1e-320],
        ] {
            let hit = w.raycast(o, dir, 20.0, &SOLID).unwrap().unwrap();
            assert_eq!(hit.pos, WorldPos::new(0, 0, -3), "{dir:?}");
            assert!(
                (hit.distance - 2.5).abs() < 1e-12,
                "{dir:?}: {}",
                hit.distance
            );
        }
        let edge = f64::from(i32::MAX) - 3.5;
        assert_eq!(
            w.raycast([edge, 0.0, 0.0], [1.0, 0.0, 0.0], 100.0, &SOLID)
                .unwrap(),
            None
        );
    }

    fn world() -> World {
        World::new(Arc::new(BlockRegistry::default()))
    }

    #[test]
    fn split_floors_negative_coordinates() {
        assert_eq!(
            WorldPos::new(-1, 0, 33).split(),
            (ChunkPos::new(-1, 0, 1), [31, 0, 1])
        );
        let (c, l) = WorldPos::new(i32::MIN, i32::MAX, 0).split();
        assert_eq!(c, ChunkPos::new(ChunkPos::MIN, ChunkPos::MAX, 0));
        assert_eq!(l, [0, 31, 0]);
        assert!(c.is_valid());
    }

    #[test]
    fn neighbours_stop_at_the_edge_of_the_i32_world() {
        let edge = ChunkPos::new(ChunkPos::MAX, 0, ChunkPos::MIN);
        assert_eq!(edge.neighbour(Face::PosX), None);
        assert_eq!(edge.neighbour(Face::NegZ), None);
        assert_eq!(
            edge.neighbour(Face::NegX),
            Some(ChunkPos::new(ChunkPos::MAX - 1, 0, ChunkPos::MIN))
        );
        assert_eq!(ChunkPos::new(i32::MAX, 0, 0).neighbour(Face::PosX), None);
        assert_eq!(edge.origin()[0], i64::from(i32::MAX) - 31);
    }

    #[test]
    fn set_get_at_the_i32_limits() {
        let mut w = world();
        for p in [
            WorldPos::new(i32::MAX, i32::MAX, i32::MAX),
            WorldPos::new(i32::MIN, i32::MIN, i32::MIN),
        ] {
            w.set_block(p, GLASS).unwrap();
            assert_eq!(w.get_block(p), GLASS);
        }
        assert_eq!(w.len(), 2);
    }

    #[test]
    fn unknown_block_is_rejected() {
        let mut w = world();
        assert_eq!(
            w.set_block(WorldPos::new(0, 0, 0), BlockId(500)),
            Err(Error::UnknownBlock(BlockId(500), 13))
        );
        let mut c = Chunk::default();
        c.set(0, 0, 0, BlockId(77)).unwrap();
        assert!(matches!(
            w.insert_chunk(ChunkPos::new(0, 0, 0), c),
            Err(Error::UnknownBlock(BlockId(77), _))
        ));
        assert!(matches!(
            w.insert_chunk(ChunkPos::new(1 << 26, 0, 0), Chunk::default()),
            Err(Error::ChunkOutOfRange(p)) if p == ChunkPos::new(1 << 26, 0, 0)
        ));
    }

    #[test]
    fn border_edits_dirty_the_neighbour() {
        let mut w = world();
        for x in -1..=1 {
            w.insert_chunk(ChunkPos::new(x, 0, 0), Chunk::default())
                .unwrap();
        }
        w.take_dirty();
        // Interior edit: only the chunk itself.
        w.set_block(WorldPos::new(5, 5, 5), STONE).unwrap();
        assert_eq!(w.take_dirty(), vec![ChunkPos::new(0, 0, 0)]);
        // Setting the same block again changes nothing.
        w.set_block(WorldPos::new(5, 5, 5), STONE).unwrap();
        assert!(w.take_dirty().is_empty());
        // Edit on the -x border: the -x neighbour too; the +y neighbour is not loaded.
        w.set_block(WorldPos::new(0, 31, 5), STONE).unwrap();
        assert_eq!(
            w.take_dirty(),
            vec![ChunkPos::new(-1, 0, 0), ChunkPos::new(0, 0, 0)]
        );
        w.set_block(WorldPos::new(31, 3, 3), WATER).unwrap();
        assert_eq!(
            w.take_dirty(),
            vec![ChunkPos::new(0, 0, 0), ChunkPos::new(1, 0, 0)]
        );
    }

    #[test]
    fn edge_and_corner_edits_dirty_the_diagonal_neighbours() {
        let mut w = world();
        for d in Neighbourhood::OFFSETS.into_iter().chain([[0; 3]]) {
            w.insert_chunk(ChunkPos::new(d[0], d[1], d[2]), Chunk::default())
                .unwrap();
        }
        w.take_dirty();
        // On the +x face only: the chunk and its +x neighbour.
        w.set_block(WorldPos::new(31, 5, 5), STONE).unwrap();
        assert_eq!(w.take_dirty().len(), 2);
        // On the +x/-z edge: + the -z and the (+x, -z) edge neighbour.
        w.set_block(WorldPos::new(31, 5, 0), STONE).unwrap();
        let dirty = w.take_dirty();
        assert_eq!(dirty.len(), 4, "{dirty:?}");
        assert!(dirty.contains(&ChunkPos::new(1, 0, -1)));
        // On the (-x, +y, +z) corner: all 7 chunks that touch it, and the chunk.
        w.set_block(WorldPos::new(0, 31, 31), STONE).unwrap();
        let dirty = w.take_dirty();
        assert_eq!(dirty.len(), 8, "{dirty:?}");
        assert!(dirty.contains(&ChunkPos::new(-1, 1, 1)));
        assert_eq!(touched_neighbours([0, 31, 31]).count(), 7);
        assert_eq!(touched_neighbours([4, 31, 31]).count(), 3);
        assert_eq!(touched_neighbours([4, 4, 4]).count(), 0);
    }

    #[test]
    fn neighbourhood_offsets_are_the_26_around_a_chunk() {
        let set: HashSet<[i32; 3]> = Neighbourhood::OFFSETS.into_iter().collect();
        assert_eq!(set.len(), 26);
        assert!(!set.contains(&[0, 0, 0]));
        for (i, f) in Face::ALL.iter().enumerate() {
            assert_eq!(Neighbourhood::OFFSETS[i], f.normal());
        }
        let stone = Chunk::uniform(STONE);
        let n = Neighbourhood::faces([Some(&stone), None, None, None, None, None]);
        assert!(n.face(Face::PosX).is_some());
        assert!(n.get([1, 1, 0]).is_none());
        assert!(n.get([0, 0, 0]).is_none());
        assert!(n.get([2, 0, 0]).is_none());
        let all = Neighbourhood::from_fn(|_| Some(&stone));
        assert!(Neighbourhood::OFFSETS.iter().all(|&d| all.get(d).is_some()));
    }

    #[test]
    fn insert_and_remove_dirty_neighbours() {
        let mut w = world();
        w.insert_chunk(ChunkPos::new(0, 0, 0), Chunk::default())
            .unwrap();
        w.take_dirty();
        w.insert_chunk(ChunkPos::new(0, 1, 0), Chunk::uniform(STONE))
            .unwrap();
        assert_eq!(
            w.take_dirty(),
            vec![ChunkPos::new(0, 0, 0), ChunkPos::new(0, 1, 0)]
        );
        assert!(w.remove_chunk(ChunkPos::new(0, 1, 0)).is_some());
        assert_eq!(
            w.take_dirty(),
            vec![ChunkPos::new(0, 0, 0), ChunkPos::new(0, 1, 0)]
        );
        let around = w.neighbourhood(ChunkPos::new(0, 0, 0));
        assert!(
            Neighbourhood::OFFSETS
                .iter()
                .all(|&d| around.get(d).is_none())
        );
    }

    #[test]
    fn fill_box_matches_setting_each_block() {
        let mut a = world();
        let mut b = world();
        let (min, max) = (WorldPos::new(-40, -3, 5), WorldPos::new(70, 33, 6));
        a.fill_box(min, max, GLASS).unwrap();
        for x in min.x..=max.x {
            for y in min.y..=max.y {
                for z in min.z..=max.z {
                    b.set_block(WorldPos::new(x, y, z), GLASS).unwrap();
                }
            }
        }
        assert_eq!(a.len(), b.len());
        for (pos, chunk) in a.iter() {
            assert_eq!(
                chunk.to_dense(),
                b.chunk(pos).unwrap().to_dense(),
                "{pos:?}"
            );
        }
        assert!(a.fill_box(min, max, BlockId(99)).is_err());
        a.fill_box(WorldPos::new(0, 0, 0), WorldPos::new(-1, 0, 0), STONE)
            .unwrap();
        a.fill_box(WorldPos::new(500, 0, 0), WorldPos::new(600, 0, 0), AIR)
            .unwrap();
        assert_eq!(
            a.len(),
            b.len(),
            "empty boxes and air in missing chunks load nothing"
        );
    }

    #[test]
    fn packed_chunks_read_and_edit_like_any_other() {
        let mut w = world();
        w.fill_box(WorldPos::new(-3, -3, -3), WorldPos::new(40, 2, 4), STONE)
            .unwrap();
        w.set_block(WorldPos::new(0, 0, 0), WATER).unwrap();
        let before: Vec<_> = {
            let mut v: Vec<_> = w.iter().map(|(p, c)| (p, c.to_dense())).collect();
            v.sort_by_key(|(p, _)| *p);
            v
        };
        let mask_bytes = w.chunk_memory_bytes();
        w.take_dirty();
        w.pack_all();
        assert!(w.dirty().is_empty(), "packing changes no block");
        assert!(
            w.iter()
                .all(|(_, c)| c.is_packed() || c.as_uniform().is_some())
        );
        assert!(w.chunk_memory_bytes() * 3 < mask_bytes);
        for (p, dense) in &before {
            assert_eq!(&w.chunk(*p).unwrap().to_dense(), dense);
        }
        assert_eq!(w.get_block(WorldPos::new(0, 0, 0)), WATER);
        assert_eq!(w.get_block(WorldPos::new(-1, -1, -1)), STONE);
        assert_eq!(w.set_block(WorldPos::new(1, 1, 1), GLASS).unwrap(), STONE);
        let c = ChunkPos::new(0, 0, 0);
        assert!(w.chunk(c).unwrap().is_packed(), "an edit keeps the form");
        w.chunk(c).unwrap().check_invariants().unwrap();
        assert!(w.unpack_chunk(c));
        assert!(!w.chunk(c).unwrap().is_packed());
        assert_eq!(w.get_block(WorldPos::new(1, 1, 1)), GLASS);
        assert!(w.pack_chunk(c));
        assert!(w.chunk(c).unwrap().is_packed());
        assert!(!w.pack_chunk(ChunkPos::new(9, 9, 9)));
        assert!(!w.unpack_chunk(ChunkPos::new(9, 9, 9)));
    }

    #[test]
    fn setting_air_in_a_missing_chunk_loads_nothing() {
        let mut w = world();
        assert_eq!(w.set_block(WorldPos::new(1, 2, 3), AIR).unwrap(), AIR);
        assert!(w.is_empty());
        assert!(w.dirty().is_empty());
    }

    #[test]
    fn the_medium_at_a_point_is_its_translucent_block() {
        let mut w = World::new(Arc::new(BlockRegistry::default()));
        w.set_block(WorldPos::new(0, -1, 0), WATER).unwrap();
        w.set_block(WorldPos::new(0, 0, 0), STONE).unwrap();
        assert_eq!(w.medium_at([0.5, -0.5, 0.5]), Some(WATER));
        assert_eq!(
            w.medium_at([0.5, -1.0, 0.99]),
            Some(WATER),
            "the bottom face is inside"
        );
        assert_eq!(w.medium_at([0.5, 0.0, 0.5]), None, "stone is no medium");
        assert_eq!(w.medium_at([0.5, 1.5, 0.5]), None, "air");
        assert_eq!(w.medium_at([f64::NAN, 0.0, 0.0]), None);
        assert_eq!(w.medium_at([3e9, 0.0, 0.0]), None);
    }
}
