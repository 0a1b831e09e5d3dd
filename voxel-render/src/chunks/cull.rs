//! Frustum culling: the chunks grouped by region, the frustum and its tests, and a
//! frame's visible meshes in draw order ([`Culled`]).

use glam::{DVec3, Mat4, Vec3, Vec4};
use voxel_core::{CHUNK_SIZE, ChunkPos};

#[cfg(doc)]
use super::ChunkStore;
use super::{MeshKind, PosMap};
use crate::arena::Alloc;
use crate::layers::{LayerBuffer, Plane, VisibleLayers};

/// Chunks per region along x, y and z: 8 × 4 × 8 (Sodium's), 256 × 128 × 256 blocks. A
/// frame tests a region's box before the chunks in it.
pub(super) const REGION_CHUNKS: [i32; 3] = [8, 4, 8];

/// What culling needs of a chunk, kept with the other chunks of its region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Member {
    pub(super) pos: ChunkPos,
    /// Its level of detail (0: a chunk; see [`super::GpuChunk::level`]).
    pub(super) level: u8,
    pub(super) slot: u32,
    pub(super) meshes: [Option<Alloc>; 3],
    /// Where its translucent mesh's planes lie in its region's `planes`.
    planes: [u32; 2],
}

/// The chunks of one region.
#[derive(Debug)]
pub(super) struct Region {
    /// Region coordinates (chunk coordinates divided by [`REGION_CHUNKS`], rounded down).
    pub(super) key: [i32; 3],
    /// Block coordinates of the region's lowest corner.
    pub(super) origin: [i64; 3],
    /// The coarsest level of detail among its members (set, never lowered while the
    /// region lives): a member of level `l` reaches `2^l` chunks in x and z from its
    /// position, past the region's own box.
    pub(super) level: u8,
    pub(super) members: Vec<Member>,
    /// The translucent planes of the members ([`crate::layers`]), member by member, and
    /// how many of them belong to no member any more (compacted when more than half).
    pub(super) planes: Vec<Plane>,
    pub(super) garbage: usize,
}

impl Region {
    /// Member `index`'s planes.
    pub(super) fn planes_of(&self, index: usize) -> &[Plane] {
        let [start, end] = self.members[index].planes;
        &self.planes[start as usize..end as usize]
    }

    /// Puts `planes` at the end for member `index` (its old ones become garbage).
    fn set_planes(&mut self, index: usize, planes: &[Plane]) {
        let [start, end] = self.members[index].planes;
        self.garbage += (end - start) as usize;
        let at = self.planes.len() as u32;
        self.planes.extend_from_slice(planes);
        self.members[index].planes = [at, at + planes.len() as u32];
        self.compact_planes();
    }

    /// Copies the members' planes into a new buffer, in member order, when more than half
    /// of the old one is garbage.
    fn compact_planes(&mut self) {
        if self.garbage * 2 <= self.planes.len() {
            return;
        }
        let mut planes = Vec::with_capacity(self.planes.len() - self.garbage);
        for m in &mut self.members {
            let [start, end] = m.planes;
            let at = planes.len() as u32;
            planes.extend_from_slice(&self.planes[start as usize..end as usize]);
            m.planes = [at, planes.len() as u32];
        }
        self.planes = planes;
        self.garbage = 0;
    }
}

/// Where a slot's member is: its region and its index there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Place {
    pub(super) region: u32,
    pub(super) index: u32,
}

/// The chunks grouped by region (CPU only: what [`ChunkStore::cull`] walks).
#[derive(Debug, Default)]
pub(super) struct Regions {
    pub(super) regions: Vec<Region>,
    pub(super) by_key: PosMap<[i32; 3], u32>,
    /// Per slot, where its member is (`None`: no chunk in the slot).
    pub(super) places: Vec<Option<Place>>,
}

impl Regions {
    pub(super) fn key(pos: ChunkPos) -> [i32; 3] {
        [
            pos.x.div_euclid(REGION_CHUNKS[0]),
            pos.y.div_euclid(REGION_CHUNKS[1]),
            pos.z.div_euclid(REGION_CHUNKS[2]),
        ]
    }

    /// Adds the chunk of `slot`, or updates its meshes and, when given, the planes of its
    /// translucent mesh (`None` keeps them: the meshes moved, the quads did not change; the
    /// position of a slot never changes while it is held).
    pub(super) fn set(
        &mut self,
        slot: u32,
        pos: ChunkPos,
        level: u8,
        meshes: [Option<Alloc>; 3],
        planes: Option<&[Plane]>,
    ) {
        let s = slot as usize;
        if s >= self.places.len() {
            self.places.resize(s + 1, None);
        }
        if let Some(p) = self.places[s] {
            let region = &mut self.regions[p.region as usize];
            let m = &region.members[p.index as usize];
            if m.pos == pos && m.level == level {
                region.members[p.index as usize].meshes = meshes;
                if let Some(planes) = planes {
                    region.set_planes(p.index as usize, planes);
                }
                return;
            }
            self.remove(slot);
        }
        let key = Self::key(pos);
        let region = *self.by_key.entry(key).or_insert_with(|| {
            let n = CHUNK_SIZE as i64;
            self.regions.push(Region {
                key,
                origin: [0, 1, 2].map(|k| i64::from(key[k]) * i64::from(REGION_CHUNKS[k]) * n),
                level: 0,
                members: Vec::new(),
                planes: Vec::new(),
                garbage: 0,
            });
            self.regions.len() as u32 - 1
        });
        let r = &mut self.regions[region as usize];
        r.level = r.level.max(level);
        let index = r.members.len();
        self.places[s] = Some(Place {
            region,
            index: index as u32,
        });
        let at = r.planes.len() as u32;
        r.members.push(Member {
            pos,
            level,
            slot,
            meshes,
            planes: [at, at],
        });
        r.set_planes(index, planes.unwrap_or_default());
    }

    /// Removes the chunk of `slot` (an empty region goes with it).
    pub(super) fn remove(&mut self, slot: u32) {
        let Some(p) = self.places.get_mut(slot as usize).and_then(Option::take) else {
            return;
        };
        let region = &mut self.regions[p.region as usize];
        let [start, end] = region.members.swap_remove(p.index as usize).planes;
        region.garbage += (end - start) as usize;
        if let Some(moved) = region.members.get(p.index as usize) {
            self.places[moved.slot as usize] = Some(p);
        }
        if !region.members.is_empty() {
            region.compact_planes();
            return;
        }
        // The last region takes the empty one's index.
        let gone = self.regions.swap_remove(p.region as usize);
        self.by_key.remove(&gone.key);
        if let Some(r) = self.regions.get(p.region as usize) {
            self.by_key.insert(r.key, p.region);
            for m in &r.members {
                if let Some(place) = self.places[m.slot as usize].as_mut() {
                    place.region = p.region;
                }
            }
        }
    }

    /// Calls `visit` with every chunk whose box is not wholly outside one of the frustum's
    /// planes, its distance ([`Frustum::level_chunk_distance`]: the same chunks, the same
    /// numbers) and its translucent planes, region by region.
    pub(super) fn cull(&self, frustum: &Frustum, mut visit: impl FnMut(&Member, f64, &[Plane])) {
        let n = CHUNK_SIZE as i64;
        for r in &self.regions {
            // Its box, reaching as far as its widest member does past it.
            let reach = (voxel_core::level_scale(r.level) - 1) * n;
            let size =
                [0, 1, 2].map(|k| i64::from(REGION_CHUNKS[k]) * n + if k == 1 { 0 } else { reach });
            match frustum.region_cover(r.origin, size) {
                Cover::Outside => {}
                Cover::Inside => {
                    for (i, m) in r.members.iter().enumerate() {
                        visit(m, frustum.centre_distance(m.pos, m.level), r.planes_of(i));
                    }
                }
                Cover::Partial => {
                    for (i, m) in r.members.iter().enumerate() {
                        if let Some(d) = frustum.level_chunk_distance(m.pos, m.level) {
                            visit(m, d, r.planes_of(i));
                        }
                    }
                }
            }
        }
    }
}

/// A visible opaque or cutout mesh in a frame's list: its sort key (page, distance, slot;
/// see [`Culled`]) and where it lives.
#[derive(Clone, Copy, Debug)]
pub(super) struct NearEntry {
    pub(super) key: u128,
    pub(super) mesh: Alloc,
}

/// A visible translucent mesh in a frame's list.
#[derive(Clone, Copy, Debug)]
pub(super) struct FarEntry {
    /// [`voxel_mesh::order::chunk_order_key`].
    pub(super) key: u128,
    pub(super) pos: ChunkPos,
    pub(super) slot: u32,
    pub(super) mesh: Alloc,
}

/// One frame's visible meshes of every kind, from `ChunkStore::cull`, in draw order:
/// opaque and cutout meshes by page, then front to back (early depth rejection; equal
/// distances by slot), translucent ones farthest first by
/// [`voxel_mesh::order::chunk_order_key`] (equal keys by position). Keep one between
/// frames: its vectors keep their room.
#[derive(Debug, Default)]
pub(crate) struct Culled {
    pub(super) near: [Vec<NearEntry>; 2],
    pub(super) far: Vec<FarEntry>,
    pub(super) positions: Vec<ChunkPos>,
    pub(super) keys: Vec<u128>,
    /// The visible translucent chunks' planes, when asked for.
    pub(super) layers: LayerBuffer,
}

impl Culled {
    /// The meshes of `kind` in draw order: (slot, place).
    pub(crate) fn meshes(&self, kind: MeshKind) -> impl Iterator<Item = (u32, Alloc)> + '_ {
        let (near, far): (&[NearEntry], &[FarEntry]) = match kind {
            MeshKind::Opaque => (&self.near[0], &[]),
            MeshKind::Cutout => (&self.near[1], &[]),
            MeshKind::Translucent => (&[], &self.far),
        };
        near.iter()
            .map(|e| (e.key as u32, e.mesh))
            .chain(far.iter().map(|e| (e.slot, e.mesh)))
    }

    /// The positions of the visible translucent meshes, farthest first.
    pub(crate) fn translucent_positions(&self) -> &[ChunkPos] {
        &self.positions
    }

    /// The [`voxel_mesh::order::chunk_order_key`] of each visible translucent mesh, in
    /// the order of [`Culled::translucent_positions`] (largest first).
    pub(crate) fn translucent_keys(&self) -> &[u128] {
        &self.keys
    }

    /// The store's slot of each visible translucent mesh, in the order of
    /// [`Culled::translucent_positions`] ([`ChunkStore::by_slot`]).
    pub(crate) fn translucent_slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.far.iter().map(|e| e.slot)
    }

    /// The planes of the visible translucent meshes ([`crate::layers`]; in no particular
    /// order), when [`ChunkStore::cull`] was asked for them (else empty).
    pub(crate) fn translucent_layers(&self) -> VisibleLayers<'_> {
        self.layers.view()
    }
}

/// The sort key of a near-first list: page, then distance, then slot; the distance (never
/// negative: its bits order like the number) in the middle.
pub(super) fn near_key(page: u32, distance: f64, slot: u32) -> u128 {
    (u128::from(page) << 96) | (u128::from(distance.to_bits()) << 32) | u128::from(slot)
}

/// The six planes of a camera-relative view frustum, and the eye they are relative to.
#[derive(Clone, Debug)]
pub(crate) struct Frustum {
    planes: [Vec4; 6],
    pub(super) eye: DVec3,
}

impl Frustum {
    /// From a camera-relative view-projection (clip z in [0, w], either direction).
    pub(crate) fn new(view_proj: Mat4, eye: DVec3) -> Self {
        let r = [
            view_proj.row(0),
            view_proj.row(1),
            view_proj.row(2),
            view_proj.row(3),
        ];
        let planes = [
            r[3] + r[0],
            r[3] - r[0],
            r[3] + r[1],
            r[3] - r[1],
            r[2],
            r[3] - r[2],
        ];
        Self { planes, eye }
    }

    /// Distance from the eye to the chunk's centre, or `None` when the chunk's box lies
    /// wholly outside one plane.
    #[cfg(test)]
    pub(crate) fn chunk_distance(&self, pos: ChunkPos) -> Option<f64> {
        self.level_chunk_distance(pos, 0)
    }

    /// [`Frustum::level_chunk_distance`] of the chunk keyed `pos` of level of detail `level`
    /// (its box `2^level` chunks wide in x and z).
    pub(crate) fn level_chunk_distance(&self, pos: ChunkPos, level: u8) -> Option<f64> {
        let min = self.relative(pos);
        let lo = min.as_vec3();
        let hi = (min + Self::extent(level)).as_vec3();
        for p in &self.planes {
            let n = p.truncate();
            // The box corner farthest along the plane normal.
            let v = Vec3::select(n.cmpge(Vec3::ZERO), hi, lo);
            if n.dot(v) + p.w < 0.0 {
                return None;
            }
        }
        Some(self.centre_distance(pos, level))
    }

    /// The size of a chunk of level `level`, blocks.
    fn extent(level: u8) -> DVec3 {
        DVec3::from(crate::layers::cell_scale(level)) * CHUNK_SIZE as f64
    }

    /// The chunk's lowest corner relative to the eye.
    fn relative(&self, pos: ChunkPos) -> DVec3 {
        let o = pos.origin();
        DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) - self.eye
    }

    /// Distance from the eye to the chunk's centre (the number
    /// [`Frustum::level_chunk_distance`] gives).
    fn centre_distance(&self, pos: ChunkPos, level: u8) -> f64 {
        (self.relative(pos) + Self::extent(level) / 2.0).length()
    }

    /// Where the box from block `origin` of `size` blocks lies: wholly outside one plane,
    /// wholly inside all of them, or neither, decided only where the decision holds for
    /// [`Frustum::level_chunk_distance`]'s test of every chunk in the box despite rounding. That
    /// test rounds the box corners to f32 and sums three products and the plane's offset
    /// in f32: at most about 3.2·10⁻⁷ of `S` = Σ|nᵢ|·|corner coordinateᵢ| + |w| off the
    /// exact value, and so is this one's. A chunk's exact value lies between this box's
    /// nearest and farthest exact values, so with a margin of 4·10⁻⁶·`S` (over ten times
    /// both errors) "outside" and "inside" here are what the chunk test finds too; closer
    /// calls are [`Cover::Partial`], left to the chunk test.
    pub(super) fn region_cover(&self, origin: [i64; 3], size: [i64; 3]) -> Cover {
        let min = DVec3::new(origin[0] as f64, origin[1] as f64, origin[2] as f64) - self.eye;
        let max = min + DVec3::new(size[0] as f64, size[1] as f64, size[2] as f64);
        let (lo, hi) = (min.as_vec3(), max.as_vec3());
        let reach = lo.abs().max(hi.abs());
        let mut inside = true;
        for p in &self.planes {
            let n = p.truncate();
            let positive = n.cmpge(Vec3::ZERO);
            let margin = 4e-6 * (n.abs().dot(reach) + p.w.abs());
            let far = Vec3::select(positive, hi, lo);
            if n.dot(far) + p.w < -margin {
                return Cover::Outside;
            }
            let near = Vec3::select(positive, lo, hi);
            // NaN counts as "not sure".
            inside &= n.dot(near) + p.w > margin;
        }
        if inside {
            Cover::Inside
        } else {
            Cover::Partial
        }
    }
}

/// Where a region's box lies against the frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Cover {
    /// Wholly outside one plane: none of its chunks is visible.
    Outside,
    /// Wholly inside every plane: all of its chunks are.
    Inside,
    /// Cut by a plane (or too close to call): test its chunks one by one.
    Partial,
}
