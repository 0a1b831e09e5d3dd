//! Ray casts through a world: a voxel walk (Amanatides & Woo 1987) that stops at the first
//! block a caller's test accepts, its input checks, and what it hits.

use super::{Face, World, WorldPos};
use crate::{BlockDef, BlockId, Error, RenderClass, Result};

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

impl World {
    /// The first block along the ray from `origin` in `direction` (any length but zero)
    /// within `max_distance` blocks whose render class is one of `stops`, or `None`:
    /// [`World::raycast_by`] with a test of the class. `&RenderClass::VISIBLE` picks the
    /// first block that draws anything.
    ///
    /// Fails as [`World::raycast_by`] does.
    pub fn raycast(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        max_distance: f64,
        stops: &[RenderClass],
    ) -> Result<Option<RayHit>> {
        self.raycast_by(origin, direction, max_distance, |_, def| {
            stops.contains(&def.class)
        })
    }

    /// The first block along the ray from `origin` in `direction` (any length but zero)
    /// within `max_distance` blocks for which `stop(id, definition)` is true, by a voxel
    /// walk (Amanatides & Woo 1987), or `None`. `stop` is asked about every block the ray
    /// enters, in order, air included, until it says yes; so a pick can pass water and
    /// stop at glass, or stop at a block of one name. The block holding the origin is not
    /// tested: a ray cast from inside a block finds what lies beyond it. Chunks that are
    /// not loaded are air.
    ///
    /// Fails on an origin that is not finite or lies outside the `i32` world, a direction
    /// that is zero or not finite, and a `max_distance` that is negative, NaN or beyond
    /// [`MAX_RAY_DISTANCE`].
    ///
    /// ```
    /// use std::sync::Arc;
    /// use voxel_core::blocks::{GLASS, WATER};
    /// use voxel_core::{BlockRegistry, RenderClass, World, WorldPos};
    ///
    /// let mut world = World::new(Arc::new(BlockRegistry::default()));
    /// world.fill_box(WorldPos::new(0, 0, -4), WorldPos::new(0, 0, -1), WATER)?;
    /// world.set_block(WorldPos::new(0, 0, -6), GLASS)?;
    /// // Through water, up to the first other block that draws something.
    /// let hit = world.raycast_by([0.5, 0.5, 0.5], [0.0, 0.0, -1.0], 20.0, |id, def| {
    ///     id != WATER && def.class != RenderClass::Air
    /// })?;
    /// assert_eq!(hit.map(|h| (h.pos, h.block)), Some((WorldPos::new(0, 0, -6), GLASS)));
    /// # Ok::<(), voxel_core::Error>(())
    /// ```
    pub fn raycast_by(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        max_distance: f64,
        mut stop: impl FnMut(BlockId, &BlockDef) -> bool,
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
            if self.registry.get(block).is_ok_and(|def| stop(block, def)) {
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
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::BlockRegistry;
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

    /// Rays both raycasts refuse (origin, direction, distance): an origin not finite or
    /// past the world's coordinates, a direction zero or not finite, a distance negative,
    /// not a number or past the cap.
    const BAD_RAYS: [([f64; 3], [f64; 3], f64); 8] = [
        ([f64::NAN, 0.0, 0.0], [0.0, 0.0, -1.0], 5.0),
        ([3e9, 0.0, 0.0], [0.0, 0.0, -1.0], 5.0),
        ([0.0; 3], [0.0; 3], 5.0),
        ([0.0; 3], [f64::INFINITY, 0.0, 0.0], 5.0),
        ([0.0; 3], [0.0, f64::NAN, -1.0], 5.0),
        ([0.0; 3], [0.0, 0.0, -1.0], -1.0),
        ([0.0; 3], [0.0, 0.0, -1.0], f64::NAN),
        ([0.0; 3], [0.0, 0.0, -1.0], MAX_RAY_DISTANCE * 2.0),
    ];

    #[test]
    fn raycast_refuses_bad_rays_and_stops_at_the_world_edge() {
        let w = wall();
        for (origin, dir, max) in BAD_RAYS {
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

    #[test]
    fn raycast_by_passes_water_and_stops_at_glass() {
        // Water from z = -1 to z = -4 (x and y from -1 to 1), glass at z = -5, air at z = -6,
        // stone at z = -7.
        let mut w = World::new(Arc::new(BlockRegistry::default()));
        w.fill_box(WorldPos::new(-1, -1, -4), WorldPos::new(1, 1, -1), WATER)
            .unwrap();
        w.set_block(WorldPos::new(0, 0, -5), GLASS).unwrap();
        w.set_block(WorldPos::new(0, 0, -7), STONE).unwrap();
        let (o, d) = ([0.5, 0.5, 0.5], [0.0, 0.0, -1.0]);
        let through_water =
            |id: BlockId, def: &BlockDef| id != WATER && def.class != RenderClass::Air;
        let hit = w.raycast_by(o, d, 20.0, through_water).unwrap().unwrap();
        assert_eq!(
            (hit.pos, hit.block, hit.face),
            (WorldPos::new(0, 0, -5), GLASS, Face::PosZ)
        );
        assert!((hit.distance - 4.5).abs() < 1e-12, "{}", hit.distance);
        // A filter by class stops at the water's surface.
        let hit = w.raycast(o, d, 20.0, &SOLID).unwrap().unwrap();
        assert_eq!((hit.pos, hit.block), (WorldPos::new(0, 0, -1), WATER));
        // By name: through water and glass to the stone.
        let hit = w
            .raycast_by(o, d, 20.0, |_, def| def.name == "stone")
            .unwrap()
            .unwrap();
        assert_eq!((hit.pos, hit.block), (WorldPos::new(0, 0, -7), STONE));
        // From under water up to the surface: the first air block.
        let hit = w
            .raycast_by([0.5, 0.5, -2.5], [0.0, 1.0, 0.0], 20.0, |id, _| id == AIR)
            .unwrap()
            .unwrap();
        assert_eq!((hit.pos, hit.face), (WorldPos::new(0, 2, -3), Face::NegY));
        assert!((hit.distance - 1.5).abs() < 1e-12, "{}", hit.distance);
        // The test is asked about every block the ray enters, in order, air included,
        // the origin's block not.
        let mut asked = Vec::new();
        let none = w
            .raycast_by(o, d, 7.0, |id, def| {
                asked.push((id, def.class));
                false
            })
            .unwrap();
        assert_eq!(none, None);
        let want = [WATER, WATER, WATER, WATER, GLASS, AIR, STONE];
        assert_eq!(asked.iter().map(|a| a.0).collect::<Vec<_>>(), want);
        assert_eq!(asked[5].1, RenderClass::Air);
    }

    #[test]
    fn raycast_by_refuses_what_raycast_refuses() {
        let w = wall();
        for (origin, dir, max) in BAD_RAYS {
            let mut asked = 0;
            let by = w
                .raycast_by(origin, dir, max, |_, _| {
                    asked += 1;
                    true
                })
                .unwrap_err();
            let classes = w.raycast(origin, dir, max, &SOLID).unwrap_err();
            assert!(matches!(by, Error::InvalidRay(_)), "{by}");
            assert_eq!(by.to_string(), classes.to_string());
            assert_eq!(asked, 0);
        }
    }
}
