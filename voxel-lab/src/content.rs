//! What the lab's CPU ray march (the `raymarch` module) and its scene files need of a game's
//! content besides its description (`voxel_render::content`): the light of a box's face and
//! of a particle, a box's face normals, and rotations given in degrees. The ray march shares
//! no code with the rasteriser: these are its own.

use glam::{DQuat, DVec3, Mat3};
use voxel_render::content::Entity;

/// The lit colour of an entity face with world normal `normal`: Lambert with the sun plus
/// ambient, as the world's faces (without ambient occlusion).
pub fn face_light(normal: DVec3, sun: DVec3, ambient: f64) -> f64 {
    ambient + (1.0 - ambient) * normal.dot(sun).max(0.0)
}

/// The light of a particle: a face turned to the sky.
pub fn particle_light(sun: DVec3, ambient: f64) -> f64 {
    ambient + (1.0 - ambient) * sun.y.max(0.0)
}

/// The unit vectors of a rotation given as yaw (about y), pitch (about x) and roll (about
/// z), degrees, applied in that order.
pub fn rotation(yaw_pitch_roll_deg: [f64; 3]) -> DQuat {
    let [y, p, r] = yaw_pitch_roll_deg.map(f64::to_radians);
    DQuat::from_rotation_y(y) * DQuat::from_rotation_x(p) * DQuat::from_rotation_z(r)
}

/// A box's world normal of face `axis` (0 x, 1 y, 2 z) on side `sign` (±1).
pub fn box_normal(rotation: DQuat, axis: usize, sign: f64) -> DVec3 {
    let mut n = DVec3::ZERO;
    n[axis] = sign;
    rotation * n
}

/// For tests: an entity's faces in world space as matrices (unused by the renderer).
pub fn entity_matrix(e: &Entity) -> Mat3 {
    let axes = e.axes().map(|a| a.as_vec3());
    Mat3::from_cols(axes[0], axes[1], axes[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_turns_axes() {
        let q = rotation([90.0, 0.0, 0.0]);
        let x = q * DVec3::X;
        assert!((x - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-9);
        assert!((box_normal(q, 1, 1.0) - DVec3::Y).length() < 1e-9);
        let e = Entity {
            center: DVec3::ZERO,
            half_extents: [1.0, 2.0, 3.0],
            rotation: DQuat::IDENTITY,
            color: [0; 3],
            opacity: 1.0,
            emissive: 0.0,
        };
        assert_eq!(entity_matrix(&e).y_axis, glam::Vec3::new(0.0, 2.0, 0.0));
    }
}
