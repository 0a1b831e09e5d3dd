//! The camera: where the eye is (in f64 world units, so that the world can be large), where
//! it looks, and the perspective. Rendering is camera-relative: the GPU never sees absolute
//! world coordinates, only chunk origins minus the eye's integer part.

use glam::{DMat4, DVec3, Mat4, Vec3};

use crate::{Error, Result};

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
}

impl Camera {
    /// A camera at `eye` looking at `target`.
    pub fn look_at(eye: DVec3, target: DVec3, fov_y_deg: f64, near: f64, far: f64) -> Result<Self> {
        let c = Self {
            eye,
            forward: (target - eye).normalize_or_zero(),
            fov_y_deg,
            near,
            far,
        };
        c.validate()?;
        Ok(c)
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
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks that every number is usable: finite eye and direction, a non-zero direction,
    /// `0 < near < far`, field of view in (0, 180) degrees.
    pub fn validate(&self) -> Result<()> {
        let bad = |why: &str| Err(Error::InvalidCamera(format!("{why}: {self:?}")));
        if !self.eye.is_finite() || !self.forward.is_finite() {
            return bad("eye and direction must be finite");
        }
        if self.forward.length_squared() < 1e-12 {
            return bad("the view direction is zero (eye equals target?)");
        }
        if !(self.near.is_finite()
            && self.far.is_finite()
            && self.near > 0.0
            && self.far > self.near)
        {
            return bad("need 0 < near < far, both finite");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return bad("vertical field of view must be in (0, 180) degrees");
        }
        Ok(())
    }

    /// Yaw and pitch of the view direction (inverse of [`Camera::from_yaw_pitch`]).
    pub fn yaw_pitch(&self) -> (f64, f64) {
        let f = self.forward.normalize_or_zero();
        (f.x.atan2(-f.z), f.y.clamp(-1.0, 1.0).asin())
    }

    /// The eye split into an integer part (`floor`) and a fraction in [0, 1).
    pub fn eye_split(&self) -> ([i64; 3], Vec3) {
        let fl = self.eye.floor();
        let frac = (self.eye - fl).as_vec3();
        ([fl.x as i64, fl.y as i64, fl.z as i64], frac)
    }

    /// View rotation (eye at the origin) times a reverse-Z perspective projection
    /// (depth 1 at the near plane, 0 at the far plane) for `aspect` = width / height.
    pub fn view_proj(&self, aspect: f64) -> Mat4 {
        let f = self.forward.normalize();
        // Looking straight up or down: pick another up vector so the basis stays defined.
        let up = if f.y.abs() > 0.999 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let view = DMat4::look_to_rh(DVec3::ZERO, f, up);
        // Reverse-Z: a standard projection with near and far swapped.
        let proj = DMat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, self.far, self.near);
        (proj * view).as_mat4()
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
