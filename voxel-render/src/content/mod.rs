//! Ready-made game content drawn through the frame's stages ([`crate::stages`]), so that a
//! game adds particles or a translucent entity without writing WGSL for each technique's
//! passes: camera-facing translucent particles (bubbles, snow, smoke) and boxes turned any
//! way (an opaque boat or mob, a glass or slime cube), lit like the world's faces (Lambert
//! with the renderer's sun plus ambient; a particle as a face turned to the sky).
//!
//! [`Content`] is the description; [`ContentStages`] draws it with every technique: opaque
//! boxes with the game's opaque geometry, every translucent particle and box as one object
//! the sorted techniques order with the chunks (its instances written in that order each
//! frame). Its translucent pipelines follow the technique: a frame whose contract it has no
//! pipelines for builds them first ([`ContentStages::prebuild`] builds them at loading time
//! instead, so that a switch compiles nothing).
//!
//! ```no_run
//! # fn game(renderer: &mut voxel_render::Renderer, camera: &voxel_render::Camera,
//! #         encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView) -> voxel_render::Result<()> {
//! use glam::{DQuat, DVec3};
//! use voxel_render::content::{Content, ContentStages, Entity, Particle};
//! let bubble = |x| Particle { center: DVec3::new(x, 1.0, 0.0), half_size: 0.1, color: [220, 235, 255], opacity: 0.4 };
//! let glass = Entity {
//!     center: DVec3::new(0.0, 2.0, -3.0),
//!     half_extents: [1.0; 3],
//!     rotation: DQuat::from_rotation_y(0.5),
//!     color: [40, 200, 90],
//!     opacity: 0.5,
//! };
//! let content = Content { particles: (0..10).map(|i| bubble(f64::from(i))).collect(), entities: vec![glass] };
//! let mut game = ContentStages::new(renderer, content);
//! renderer.render(encoder, view, camera, &mut game)?;   // each frame; set_content to move things
//! # Ok(()) }
//! ```
//!
//! Its shaders pull instances from a storage buffer in the vertex stage
//! (`wgpu::DownlevelFlags::VERTEX_STORAGE`, not on WebGL2); a game that needs its own
//! shader writes its stages itself (`examples/custom_stage.rs`).

mod draw;

use glam::{DQuat, DVec3};

pub use draw::ContentStages;

/// A camera-facing square of translucent colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Centre, world blocks.
    pub center: DVec3,
    /// Half the side of the square, blocks.
    pub half_size: f32,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Opacity, 0 to 1.
    pub opacity: f32,
}

/// A box turned any way: opaque (opacity 1) or translucent (its faces toward the eye drawn
/// as one layer; from inside, its far faces).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entity {
    /// Centre, world blocks.
    pub center: DVec3,
    /// Half extents along its own axes, blocks.
    pub half_extents: [f32; 3],
    /// Its orientation.
    pub rotation: DQuat,
    /// sRGB colour.
    pub color: [u8; 3],
    /// Opacity: 1 is opaque.
    pub opacity: f32,
}

impl Entity {
    /// Whether it is drawn with the opaque geometry.
    pub fn is_opaque(&self) -> bool {
        self.opacity >= 1.0
    }

    /// Whether point `p` lies inside it (strictly).
    pub(crate) fn contains(&self, p: DVec3) -> bool {
        let o = p - self.center;
        self.axes().iter().all(|a| {
            let len2 = a.length_squared();
            len2 > 0.0 && o.dot(*a).abs() < len2
        })
    }

    /// Half the sides of the axis-aligned box around it, world blocks.
    pub(crate) fn world_half_extents(&self) -> DVec3 {
        self.axes().iter().map(|a| a.abs()).sum()
    }

    /// Its axes scaled by the half extents (columns), world directions.
    pub fn axes(&self) -> [DVec3; 3] {
        let h = self.half_extents.map(f64::from);
        [
            self.rotation * DVec3::X * h[0],
            self.rotation * DVec3::Y * h[1],
            self.rotation * DVec3::Z * h[2],
        ]
    }
}

/// Particles and entities.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Content {
    /// Translucent particles.
    pub particles: Vec<Particle>,
    /// Entities, opaque or translucent.
    pub entities: Vec<Entity>,
}

impl Content {
    /// Whether there is nothing.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty() && self.entities.is_empty()
    }

    /// `count` particles spread over the box `min..max` by a deterministic sequence from
    /// `seed`.
    pub fn scatter(
        min: DVec3,
        max: DVec3,
        count: usize,
        seed: u64,
        half_size: f32,
        color: [u8; 3],
        opacity: f32,
    ) -> Vec<Particle> {
        let mut s = seed ^ 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..count)
            .map(|_| Particle {
                center: min + (max - min) * DVec3::new(next(), next(), next()),
                half_size,
                color,
                opacity,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scatter_is_deterministic_and_inside() {
        let a = Content::scatter(DVec3::ZERO, DVec3::splat(4.0), 50, 7, 0.1, [1, 2, 3], 0.5);
        let b = Content::scatter(DVec3::ZERO, DVec3::splat(4.0), 50, 7, 0.1, [1, 2, 3], 0.5);
        assert_eq!(a, b);
        assert!(
            a.iter()
                .all(|p| p.center.cmpge(DVec3::ZERO).all()
                    && p.center.cmple(DVec3::splat(4.0)).all())
        );
        assert_ne!(a[0].center, a[1].center);
    }
}
