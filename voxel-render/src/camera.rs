//! The camera: where the eye is (in f64 world units, so that the world can be large), where
//! it looks, and the perspective. Rendering is camera-relative: the GPU never sees absolute
//! world coordinates, only chunk origins minus the eye's integer part.

use glam::{DMat4, DVec3, Mat4, Vec3};
use voxel_core::BlockId;

use crate::{Error, Result};

/// Smallest near plane distance: below it the reverse-Z projection's f32 matrix loses the
/// depth of nearby surfaces (at 1e-50 the whole floor vanished).
pub const MIN_NEAR: f64 = 1e-3;
/// Largest far plane distance: 2^20 blocks, far beyond any view distance (64 chunks are
/// 2 048 blocks) and still exact to 1/8 block in f32.
pub const MAX_FAR: f64 = 1_048_576.0;
/// Smallest vertical field of view in degrees (narrower projects everything off-screen).
pub const MIN_FOV_DEG: f64 = 0.01;
/// Largest vertical field of view in degrees.
pub const MAX_FOV_DEG: f64 = 179.0;
/// The eye must lie inside the `i32` world (each coordinate within ±2^31 blocks).
pub const WORLD_EXTENT: f64 = 2_147_483_648.0;

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position in world block units.
    pub eye: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Distance of the near plane (> 0).
    pub near: f64,
    /// Distance of the far plane (> near).
    pub far: f64,
    /// The translucent block type the eye is immersed in (water when diving), `None` in
    /// air; the game finds it from its world ([`voxel_core::World::medium_at`]). From
    /// inside a medium, its surfaces are seen from behind and fog of its colour fills the
    /// way to them.
    pub medium: Option<BlockId>,
}

impl Camera {
    /// A camera at `eye` looking at `target`.
    pub fn look_at(eye: DVec3, target: DVec3, fov_y_deg: f64, near: f64, far: f64) -> Result<Self> {
        let c = Self {
            eye,
            forward: (target - eye),
            fov_y_deg,
            near,
            far,
            medium: None,
        };
        c.validate()?;
        Ok(c.normalized())
    }

    /// The same camera immersed in `medium` (see [`Camera::medium`]).
    pub fn in_medium(self, medium: Option<BlockId>) -> Self {
        Self { medium, ..self }
    }

    /// A camera at `eye` looking along yaw (radians, 0 = -z, growing towards +x) and pitch
    /// (radians, positive up), as a fly camera steers.
    pub fn from_yaw_pitch(
        eye: DVec3,
        yaw: f64,
        pitch: f64,
        fov_y_deg: f64,
        near: f64,
        far: f64,
    ) -> Result<Self> {
        let pitch = pitch.clamp(-1.55, 1.55);
        let forward = DVec3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            -yaw.cos() * pitch.cos(),
        );
        let c = Self {
            eye,
            forward,
            fov_y_deg,
            near,
            far,
            medium: None,
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks that every number is usable: finite eye and direction, a non-zero direction,
    /// the eye inside the `i32` world ([`WORLD_EXTENT`]), [`MIN_NEAR`] ≤ near < far ≤
    /// [`MAX_FAR`], and a field of view from [`MIN_FOV_DEG`] to [`MAX_FOV_DEG`] degrees.
    pub fn validate(&self) -> Result<()> {
        let bad = |why: String| Err(Error::InvalidCamera(format!("{why}: {self:?}")));
        if !self.eye.is_finite() {
            return bad("the eye must be finite".into());
        }
        if let Err(why) = voxel_core::unit_direction(self.forward.to_array()) {
            let hint = if self.forward.is_finite() {
                " (eye equals target?)"
            } else {
                ""
            };
            return bad(format!("the view direction: {why}{hint}"));
        }
        if self.eye.abs().max_element() >= WORLD_EXTENT {
            return bad(format!(
                "the eye lies outside the i32 world (each coordinate within ±{WORLD_EXTENT})"
            ));
        }
        if !(self.near >= MIN_NEAR && self.far > self.near && self.far <= MAX_FAR) {
            return bad(format!(
                "need {MIN_NEAR} <= near < far <= {MAX_FAR}, got near {} and far {}",
                self.near, self.far
            ));
        }
        if !(MIN_FOV_DEG..=MAX_FOV_DEG).contains(&self.fov_y_deg) {
            return bad(format!(
                "vertical field of view {} must be from {MIN_FOV_DEG} to {MAX_FOV_DEG} degrees",
                self.fov_y_deg
            ));
        }
        Ok(())
    }

    /// The view direction at length 1, whatever finite length `forward` has (zero for a
    /// zero or non-finite one, which [`Camera::validate`] refuses).
    pub fn unit_forward(&self) -> DVec3 {
        voxel_core::unit_direction(self.forward.to_array()).map_or(DVec3::ZERO, DVec3::from)
    }

    /// The same camera with [`Camera::forward`] at length 1 ([`Camera::unit_forward`]).
    pub(crate) fn normalized(self) -> Self {
        Self {
            forward: self.unit_forward(),
            ..self
        }
    }

    /// Yaw and pitch of the view direction (inverse of [`Camera::from_yaw_pitch`]).
    pub fn yaw_pitch(&self) -> (f64, f64) {
        let f = self.unit_forward();
        (f.x.atan2(-f.z), f.y.clamp(-1.0, 1.0).asin())
    }

    /// The eye split into an integer part (`floor`) and a fraction in [0, 1).
    pub(crate) fn eye_split(&self) -> ([i64; 3], Vec3) {
        let fl = self.eye.floor();
        let frac = (self.eye - fl).as_vec3();
        ([fl.x as i64, fl.y as i64, fl.z as i64], frac)
    }

    /// View rotation (eye at the origin) times a reverse-Z perspective projection
    /// (depth 1 at the near plane, 0 at the far plane) for `aspect` = width / height.
    pub fn view_proj(&self, aspect: f64) -> Mat4 {
        let f = self.unit_forward();
        let view = DMat4::look_to_rh(DVec3::ZERO, f, up_hint(f));
        // Reverse-Z: a standard projection with near and far swapped.
        let proj = DMat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, self.far, self.near);
        (proj * view).as_mat4()
    }
}

/// The up vector a view looking along the unit `forward` is built with: world up, or +z
/// looking straight up or down, so that the basis stays defined.
fn up_hint(forward: DVec3) -> DVec3 {
    if forward.y.abs() > 0.999 {
        DVec3::Z
    } else {
        DVec3::Y
    }
}

impl Camera {
    /// The unit right and up vectors of the view [`Camera::view_proj`] builds (what faces
    /// the camera, a game's particles, is drawn in).
    pub(crate) fn right_up(&self) -> (DVec3, DVec3) {
        let f = self.unit_forward();
        let right = f.cross(up_hint(f)).normalize();
        (right, right.cross(f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::look_at(
            DVec3::new(0.5, 0.5, 10.0),
            DVec3::new(0.5, 0.5, 0.0),
            60.0,
            0.1,
            100.0,
        )
        .unwrap()
    }

    #[test]
    fn reverse_z_maps_near_to_one_and_far_to_zero() {
        let c = cam();
        let vp = c.view_proj(1.0);
        let ndc = |d: f32| {
            let p = vp * glam::Vec4::new(0.0, 0.0, -d, 1.0);
            p.z / p.w
        };
        assert!((ndc(0.1) - 1.0).abs() < 1e-5);
        assert!(ndc(100.0).abs() < 1e-5);
        assert!(ndc(1.0) > ndc(2.0), "nearer is larger");
    }

    #[test]
    fn bad_numbers_are_errors() {
        let e = DVec3::ZERO;
        assert!(Camera::look_at(DVec3::new(f64::NAN, 0.0, 0.0), e, 60.0, 0.1, 10.0).is_err());
        assert!(Camera::look_at(e, e, 60.0, 0.1, 10.0).is_err());
        assert!(Camera::look_at(e, DVec3::X, 60.0, 0.0, 10.0).is_err());
        assert!(Camera::look_at(e, DVec3::X, 60.0, 1.0, 1.0).is_err());
        assert!(Camera::look_at(e, DVec3::X, 180.0, 0.1, 10.0).is_err());
        assert!(Camera::look_at(e, DVec3::X, 60.0, 0.1, f64::INFINITY).is_err());
        assert!(Camera::from_yaw_pitch(e, f64::NAN, 0.0, 60.0, 0.1, 10.0).is_err());
        assert!(
            Camera::look_at(e, DVec3::X, 60.0, 1e-50, 10.0).is_err(),
            "near"
        );
        assert!(
            Camera::look_at(e, DVec3::X, 1e-40, 0.1, 10.0).is_err(),
            "fov"
        );
        assert!(Camera::look_at(e, DVec3::X, 60.0, 0.1, 1e9).is_err(), "far");
        let outside = DVec3::new(3e9, 0.0, 0.0);
        assert!(
            Camera::look_at(outside, DVec3::ZERO, 60.0, 0.1, 10.0).is_err(),
            "eye"
        );
        assert!(Camera::look_at(e, DVec3::X, MIN_FOV_DEG, MIN_NEAR, MAX_FAR).is_ok());
    }

    #[test]
    fn yaw_pitch_round_trip_and_vertical_views() {
        let c = Camera::from_yaw_pitch(DVec3::ZERO, 0.7, -0.3, 70.0, 0.1, 10.0).unwrap();
        let (y, p) = c.yaw_pitch();
        assert!((y - 0.7).abs() < 1e-9 && (p + 0.3).abs() < 1e-9);
        let down = Camera::look_at(DVec3::Y, DVec3::ZERO, 60.0, 0.1, 10.0).unwrap();
        assert!(down.view_proj(1.0).is_finite());
    }

    #[test]
    fn eye_split_is_exact_far_from_the_origin() {
        let c = Camera::look_at(
            DVec3::new(2.0e9 + 0.25, -3.5, 7.0),
            DVec3::ZERO,
            60.0,
            0.1,
            10.0,
        )
        .unwrap();
        let (i, f) = c.eye_split();
        assert_eq!(i, [2_000_000_000, -4, 7]);
        assert_eq!(f, Vec3::new(0.25, 0.5, 0.0));
    }
}
