//! The page's fly camera: W/S forward and back, A/D sideways, Space and Shift up and down
//! (along the world's up), the mouse dragged to turn.

use glam::DVec3;
use voxel_core::BlockId;
use voxel_render::Camera;

/// Blocks a second the camera flies (the width of a chunk in under 3 s).
pub const SPEED: f64 = 12.0;
/// Degrees the camera turns per pixel dragged (a 1000-pixel drag: 250°).
pub const DEGREES_PER_PIXEL: f64 = 0.25;
/// The steepest the camera looks up or down, degrees: short of straight, where the view
/// direction and the up vector would meet.
pub const MAX_PITCH: f64 = 89.0;

/// Where the camera is and where it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// The eye, in blocks.
    pub eye: DVec3,
    /// Turn about the world's up, degrees (0: towards +x, 90: towards +z).
    pub yaw: f64,
    /// Up (positive) or down, degrees, within ±[`MAX_PITCH`].
    pub pitch: f64,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f64,
}

/// The keys held, each -1, 0 or 1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Movement {
    /// W (1) or S (-1).
    pub forward: f64,
    /// D (1) or A (-1).
    pub right: f64,
    /// Space (1) or Shift (-1).
    pub up: f64,
}

impl Movement {
    /// The movement of the keys held, by their `KeyboardEvent.code`.
    pub fn from_keys<'a>(held: impl IntoIterator<Item = &'a str>) -> Self {
        let mut m = Movement::default();
        for code in held {
            match code {
                "KeyW" | "ArrowUp" => m.forward += 1.0,
                "KeyS" | "ArrowDown" => m.forward -= 1.0,
                "KeyD" | "ArrowRight" => m.right += 1.0,
                "KeyA" | "ArrowLeft" => m.right -= 1.0,
                "Space" | "KeyE" => m.up += 1.0,
                "ShiftLeft" | "ShiftRight" | "KeyQ" => m.up -= 1.0,
                _ => {}
            }
        }
        Movement {
            forward: m.forward.clamp(-1.0, 1.0),
            right: m.right.clamp(-1.0, 1.0),
            up: m.up.clamp(-1.0, 1.0),
        }
    }
}

impl FlyCamera {
    /// A camera at `camera`'s eye looking its way, with its field of view.
    pub fn from_camera(camera: &Camera) -> Self {
        let f = camera.forward.normalize_or(DVec3::X);
        Self {
            eye: camera.eye,
            yaw: f.z.atan2(f.x).to_degrees(),
            pitch: f
                .y
                .clamp(-1.0, 1.0)
                .asin()
                .to_degrees()
                .clamp(-MAX_PITCH, MAX_PITCH),
            fov_y_deg: camera.fov_y_deg,
        }
    }

    /// The unit view direction.
    pub fn forward(&self) -> DVec3 {
        let (yaw, pitch) = (self.yaw.to_radians(), self.pitch.to_radians());
        DVec3::new(
            yaw.cos() * pitch.cos(),
            pitch.sin(),
            yaw.sin() * pitch.cos(),
        )
    }

    /// Turns by a drag of `dx`, `dy` pixels (right and down positive: right turns right,
    /// down looks down).
    pub fn turn(&mut self, dx: f64, dy: f64) {
        if !(dx.is_finite() && dy.is_finite()) {
            return;
        }
        self.yaw = (self.yaw + dx * DEGREES_PER_PIXEL).rem_euclid(360.0);
        self.pitch = (self.pitch - dy * DEGREES_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Flies `seconds` with `movement` (forward along the view's horizontal direction, so
    /// that looking down does not sink the camera).
    pub fn fly(&mut self, movement: Movement, seconds: f64) {
        if !seconds.is_finite() || seconds <= 0.0 {
            return;
        }
        let yaw = self.yaw.to_radians();
        let ahead = DVec3::new(yaw.cos(), 0.0, yaw.sin());
        let right = DVec3::new(-yaw.sin(), 0.0, yaw.cos());
        let step = ahead * movement.forward + right * movement.right + DVec3::Y * movement.up;
        if step != DVec3::ZERO {
            self.eye += step.normalize() * SPEED * seconds;
        }
    }

    /// The renderer's camera, in `medium` (the volume block around the eye, if any).
    pub fn camera(&self, medium: Option<BlockId>) -> voxel_render::Result<Camera> {
        Ok(Camera::look_at(
            self.eye,
            self.eye + self.forward(),
            self.fov_y_deg,
            0.1,
            600.0,
        )?
        .in_medium(medium))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> FlyCamera {
        let c = Camera::look_at(
            DVec3::new(0.0, 40.0, 0.0),
            DVec3::new(10.0, 40.0, 0.0),
            70.0,
            0.1,
            600.0,
        )
        .expect("a camera");
        FlyCamera::from_camera(&c)
    }

    #[test]
    fn keeps_the_view_it_starts_from() {
        let c = Camera::look_at(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(4.0, 0.0, -1.0),
            60.0,
            0.1,
            600.0,
        )
        .expect("a camera");
        let fly = FlyCamera::from_camera(&c);
        assert!((fly.forward() - c.forward.normalize()).length() < 1e-9);
        assert_eq!(fly.eye, c.eye);
        assert_eq!(fly.fov_y_deg, 60.0);
    }

    #[test]
    fn flies_along_the_ground_whatever_the_pitch() {
        let mut fly = camera();
        fly.turn(0.0, 200.0); // 50° down
        assert!((fly.pitch + 50.0).abs() < 1e-9);
        fly.fly(Movement::from_keys(["KeyW"]), 0.5);
        assert!((fly.eye - DVec3::new(6.0, 40.0, 0.0)).length() < 1e-9);
        fly.fly(Movement::from_keys(["KeyD", "Space"]), 1.0);
        let moved = fly.eye - DVec3::new(6.0, 40.0, 0.0);
        assert!((moved.length() - SPEED).abs() < 1e-9, "diagonals no faster");
        assert!(moved.z > 0.0 && moved.y > 0.0, "{moved}");
        // W and S together cancel; a bad time step moves nothing.
        let before = fly.eye;
        fly.fly(Movement::from_keys(["KeyW", "KeyS"]), 1.0);
        fly.fly(Movement::from_keys(["KeyW"]), f64::NAN);
        assert_eq!(fly.eye, before);
    }

    #[test]
    fn pitch_stops_short_of_straight_up_and_down() {
        let mut fly = camera();
        fly.turn(0.0, -10_000.0);
        assert_eq!(fly.pitch, MAX_PITCH);
        fly.turn(0.0, 1e9);
        assert_eq!(fly.pitch, -MAX_PITCH);
        fly.turn(f64::INFINITY, 0.0);
        assert_eq!(fly.pitch, -MAX_PITCH);
        assert!(fly.camera(None).is_ok());
    }
}
