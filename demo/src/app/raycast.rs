//! Picking the block the camera aims at.

use glam::DVec3;
use voxel_core::WorldPos;

/// Walks the voxels along a ray (Amanatides & Woo) and returns the first solid block and the
/// cell just before it.
pub fn raycast(
    origin: DVec3,
    dir: DVec3,
    max: f64,
    solid: impl Fn(WorldPos) -> bool,
) -> Option<(WorldPos, WorldPos)> {
    let dir = dir.normalize_or_zero();
    if dir == DVec3::ZERO || !origin.is_finite() {
        return None;
    }
    let mut cell = origin.floor();
    let step = dir.signum();
    let next = |c: f64, s: f64| if s > 0.0 { c + 1.0 } else { c };
    let mut t_max = DVec3::new(
        if dir.x != 0.0 {
            (next(cell.x, step.x) - origin.x) / dir.x
        } else {
            f64::INFINITY
        },
        if dir.y != 0.0 {
            (next(cell.y, step.y) - origin.y) / dir.y
        } else {
            f64::INFINITY
        },
        if dir.z != 0.0 {
            (next(cell.z, step.z) - origin.z) / dir.z
        } else {
            f64::INFINITY
        },
    );
    let delta = DVec3::new(
        if dir.x != 0.0 {
            (1.0 / dir.x).abs()
        } else {
            f64::INFINITY
        },
        if dir.y != 0.0 {
            (1.0 / dir.y).abs()
        } else {
            f64::INFINITY
        },
        if dir.z != 0.0 {
            (1.0 / dir.z).abs()
        } else {
            f64::INFINITY
        },
    );
    let to_pos = |c: DVec3| -> Option<WorldPos> {
        let ok = |v: f64| v >= f64::from(i32::MIN) && v <= f64::from(i32::MAX);
        (ok(c.x) && ok(c.y) && ok(c.z)).then(|| WorldPos::new(c.x as i32, c.y as i32, c.z as i32))
    };
    let mut before = to_pos(cell)?;
    loop {
        let t = t_max.min_element();
        if t > max {
            return None;
        }
        if t_max.x == t {
            cell.x += step.x;
            t_max.x += delta.x;
        } else if t_max.y == t {
            cell.y += step.y;
            t_max.y += delta.y;
        } else {
            cell.z += step.z;
            t_max.z += delta.z;
        }
        let p = to_pos(cell)?;
        if solid(p) {
            return Some((p, before));
        }
        before = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raycast_hits_the_first_solid_block_and_the_cell_before() {
        let wall = |p: WorldPos| p.z == -5 && p.x.abs() < 3 && p.y.abs() < 3;
        let (hit, before) = raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::NEG_Z, 20.0, wall).unwrap();
        assert_eq!(hit, WorldPos::new(0, 0, -5));
        assert_eq!(before, WorldPos::new(0, 0, -4));
        // Diagonal rays step one axis at a time: the cell before shares a face with the hit.
        let (hit, before) = raycast(
            DVec3::new(0.2, 0.7, 0.5),
            DVec3::new(0.3, -0.2, -1.0),
            20.0,
            wall,
        )
        .unwrap();
        assert_eq!(hit.z, -5);
        let d = (hit.x - before.x).abs() + (hit.y - before.y).abs() + (hit.z - before.z).abs();
        assert_eq!(d, 1);
        assert!(
            raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::Z, 20.0, wall).is_none(),
            "behind"
        );
        assert!(
            raycast(DVec3::new(0.5, 0.5, 0.5), DVec3::NEG_Z, 3.0, wall).is_none(),
            "too far"
        );
        assert!(raycast(DVec3::new(f64::NAN, 0.0, 0.0), DVec3::NEG_Z, 3.0, wall).is_none());
        assert!(raycast(DVec3::ZERO, DVec3::ZERO, 3.0, wall).is_none());
    }
}
