//! Ready-made game content drawn through the frame's stages ([`crate::stages`]), so that a
//! game adds particles or a translucent entity without writing WGSL for each technique's
//! passes: camera-facing translucent particles (bubbles, snow, smoke, fireflies) and boxes
//! turned any way (an opaque boat or mob, a glass or slime cube, a lantern), lit like the
//! world's faces (Lambert with the renderer's sun plus ambient at the light's brightness; a
//! particle as a face turned to the sky) and glowing by their own light where they emit.
//!
//! **Colour.** A thing's `color` is sRGB bytes, as an image editor or a colour picker shows
//! them; the content turns them into linear values, lights them (multiplies by the world's
//! light on the thing) and adds its own light (`emissive`, in multiples of that linear
//! colour), all in the renderer's linear HDR scene colour, which the tonemap maps to the
//! output. So `emissive: 3.0` is three times as bright as the colour in full daylight, at
//! night as by day: a firefly's glow stays bright through water and glass, which dim it as
//! they dim anything behind them. `opacity` is the share of what lies behind it the thing
//! covers (not sRGB-encoded). A game writing its own shaders gives `oit_output` linear
//! colour (`crate::stages`).
//!
//! [`Content`] is the description; [`ContentStages`] draws it with every technique: opaque
//! boxes with the game's opaque geometry, every translucent particle and box as one object
//! the sorted techniques order with the chunks (its instances written in that order each
//! frame). Its translucent pipelines follow the technique: a frame whose contract it has no
//! pipelines for builds them first ([`ContentStages::prebuild`] builds them at loading time
//! instead, so that a switch compiles nothing). With a game's own stages beside it (its own
//! translucent shader, overlays), `crate::stages::Both` draws the two as one.
//!
//! ```no_run
//! # fn game(renderer: &mut voxel_render::Renderer, camera: &voxel_render::Camera,
//! #         encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView) -> voxel_render::Result<()> {
//! use glam::{DQuat, DVec3};
//! use voxel_render::content::{Content, ContentStages, Entity, Particle};
//! let bubble = |x| Particle {
//!     center: DVec3::new(x, 1.0, 0.0),
//!     half_size: 0.1,
//!     color: [220, 235, 255],
//!     opacity: 0.4,
//!     emissive: 0.0,
//! };
//! let firefly = Particle { color: [255, 220, 90], opacity: 0.9, emissive: 4.0, ..bubble(3.0) };
//! let glass = Entity {
//!     center: DVec3::new(0.0, 2.0, -3.0),
//!     half_extents: [1.0; 3],
//!     rotation: DQuat::from_rotation_y(0.5),
//!     color: [40, 200, 90],
//!     opacity: 0.5,
//!     emissive: 0.0,
//! };
//! let mut particles: Vec<Particle> = (0..10).map(|i| bubble(f64::from(i))).collect();
//! particles.push(firefly);
//! let content = Content { particles, entities: vec![glass] };
//! let mut game = ContentStages::new(renderer, content)?; // checks every value
//! renderer.render(encoder, view, camera, &mut game)?;   // each frame; set_content to move things
//! # Ok(()) }
//! ```
//!
//! Its instances reach the vertex shader as the world's quads do (the renderer's
//! `QuadFetch`): pulled from storage buffers, or, where the vertex stage has none (WebGL2's
//! limits), as per-instance vertex attributes. Either way they are split over as many
//! buffers as the device's binding or buffer size needs, so any count that fits in memory
//! draws. A game that needs its own shader writes its stages itself
//! (`examples/custom_stage.rs`).

mod draw;

use glam::{DQuat, DVec3};

use crate::camera::{MAX_FAR, WORLD_EXTENT};
use crate::{Error, Result};

pub use draw::ContentStages;

/// The largest [`Particle::emissive`] and [`Entity::emissive`]: sixteen times its colour
/// is white after the tonemap even at night, and keeps every technique's half-float sums
/// finite (WBOIT's largest weight, 3·10⁴ scaled by 1/64, times 17 is about 8 000 a layer of
/// the 65 504 a half float holds).
pub const MAX_EMISSIVE: f32 = 16.0;

/// The largest half size of a particle or half extent of an entity, blocks: the farthest
/// far plane (`low_level::MAX_FAR`); nothing larger could be seen whole.
pub const MAX_HALF_SIZE: f32 = MAX_FAR as f32;

/// A camera-facing square of translucent colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Centre, world blocks: finite, each coordinate within the `i32` world.
    pub center: DVec3,
    /// Half the side of the square, blocks: above 0, at most [`MAX_HALF_SIZE`].
    pub half_size: f32,
    /// Colour, sRGB bytes (the module docs say how it is lit).
    pub color: [u8; 3],
    /// Opacity, 0 to 1.
    pub opacity: f32,
    /// The light it gives off, in multiples of its linear colour, 0 (lit only: dark at
    /// night) to [`MAX_EMISSIVE`]; drawn `colour × (world light + emissive)`.
    pub emissive: f32,
}

/// A box turned any way: opaque (opacity 1) or translucent (its faces toward the eye drawn
/// as one layer; from inside, its far faces).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entity {
    /// Centre, world blocks: finite, each coordinate within the `i32` world.
    pub center: DVec3,
    /// Half extents along its own axes, blocks: each above 0, at most [`MAX_HALF_SIZE`].
    pub half_extents: [f32; 3],
    /// Its orientation: a unit quaternion (length within 10⁻³ of 1).
    pub rotation: DQuat,
    /// Colour, sRGB bytes (the module docs say how it is lit).
    pub color: [u8; 3],
    /// Opacity, 0 to 1: 1 is opaque.
    pub opacity: f32,
    /// The light it gives off, in multiples of its linear colour, 0 to [`MAX_EMISSIVE`]
    /// (see [`Particle::emissive`]).
    pub emissive: f32,
}

impl Particle {
    /// Whether every value is in its range (`Content::validate` names the one that is not).
    fn in_range(&self) -> bool {
        center_in_range(self.center)
            && size_in_range(self.half_size)
            && (0.0..=1.0).contains(&self.opacity)
            && (0.0..=MAX_EMISSIVE).contains(&self.emissive)
    }
}

impl Entity {
    /// Whether every value is in its range (`Content::validate` names the one that is not).
    fn in_range(&self) -> bool {
        let q = self.rotation;
        center_in_range(self.center)
            && self.half_extents.iter().all(|&h| size_in_range(h))
            && q.is_finite()
            && (q.length() - 1.0).abs() <= 1e-3
            && (0.0..=1.0).contains(&self.opacity)
            && (0.0..=MAX_EMISSIVE).contains(&self.emissive)
    }

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

    /// Checks every value against the ranges its field documents: the first one outside
    /// (a NaN or infinite number, an opacity outside 0 to 1, a size of 0, a rotation that
    /// is not a unit quaternion, a centre outside the world) is
    /// [`Error::InvalidContent`] naming the particle or entity, its index and the field.
    /// [`ContentStages::new`] and [`ContentStages::set_content`] check with it.
    pub fn validate(&self) -> Result<()> {
        // Every value in range, as plain comparisons over the whole content (what a game's
        // every `set_content` pays); the error is found and named only when one is not.
        if self.particles.iter().all(Particle::in_range)
            && self.entities.iter().all(Entity::in_range)
        {
            return Ok(());
        }
        for (i, p) in self.particles.iter().enumerate() {
            let bad = |field, message| invalid("particle", i, field, message);
            check_center(p.center).map_err(|m| bad("center", m))?;
            check_size(p.half_size).map_err(|m| bad("half_size", m))?;
            check_opacity(p.opacity).map_err(|m| bad("opacity", m))?;
            check_emissive(p.emissive).map_err(|m| bad("emissive", m))?;
        }
        for (i, e) in self.entities.iter().enumerate() {
            let bad = |field, message| invalid("entity", i, field, message);
            check_center(e.center).map_err(|m| bad("center", m))?;
            for h in e.half_extents {
                check_size(h).map_err(|m| bad("half_extents", m))?;
            }
            let q = e.rotation;
            if !q.is_finite() || (q.length() - 1.0).abs() > 1e-3 {
                return Err(bad(
                    "rotation",
                    format!("{q:?} is not a unit quaternion (length {})", q.length()),
                ));
            }
            check_opacity(e.opacity).map_err(|m| bad("opacity", m))?;
            check_emissive(e.emissive).map_err(|m| bad("emissive", m))?;
        }
        Ok(())
    }

    /// `count` particles spread over the box `min..max` by a deterministic sequence from
    /// `seed`, unlit (`emissive` 0).
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
                emissive: 0.0,
            })
            .collect()
    }
}

fn invalid(kind: &'static str, index: usize, field: &'static str, message: String) -> Error {
    Error::InvalidContent {
        kind,
        index,
        field,
        message,
    }
}

fn center_in_range(c: DVec3) -> bool {
    c.is_finite() && c.abs().max_element() < WORLD_EXTENT
}

fn size_in_range(s: f32) -> bool {
    s > 0.0 && s <= MAX_HALF_SIZE
}

fn check_center(c: DVec3) -> std::result::Result<(), String> {
    if !center_in_range(c) {
        return Err(format!(
            "{c} is not a point of the world (finite, each coordinate within ±{WORLD_EXTENT})"
        ));
    }
    Ok(())
}

fn check_size(s: f32) -> std::result::Result<(), String> {
    if !size_in_range(s) {
        return Err(format!(
            "{s} is not a size above 0 and at most {MAX_HALF_SIZE} blocks"
        ));
    }
    Ok(())
}

fn check_opacity(a: f32) -> std::result::Result<(), String> {
    if !(0.0..=1.0).contains(&a) {
        return Err(format!("{a} is not a number from 0 to 1"));
    }
    Ok(())
}

fn check_emissive(e: f32) -> std::result::Result<(), String> {
    if !(0.0..=MAX_EMISSIVE).contains(&e) {
        return Err(format!("{e} is not a number from 0 to {MAX_EMISSIVE}"));
    }
    Ok(())
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
        assert!(
            Content {
                particles: a,
                entities: Vec::new()
            }
            .validate()
            .is_ok()
        );
    }

    fn particle() -> Particle {
        Particle {
            center: DVec3::new(1.0, 2.0, 3.0),
            half_size: 0.5,
            color: [10, 20, 30],
            opacity: 0.5,
            emissive: 0.0,
        }
    }

    fn entity() -> Entity {
        Entity {
            center: DVec3::ZERO,
            half_extents: [1.0; 3],
            rotation: DQuat::from_rotation_y(0.3),
            color: [10, 20, 30],
            opacity: 1.0,
            emissive: 2.0,
        }
    }

    /// Each bad value is refused naming the thing, its index and the field.
    #[test]
    fn bad_values_are_refused_naming_index_and_field() {
        let p = particle();
        let e = entity();
        let particles = [
            (
                Particle {
                    opacity: f32::NAN,
                    ..p
                },
                "opacity",
            ),
            (Particle { opacity: 1.5, ..p }, "opacity"),
            (Particle { opacity: -0.1, ..p }, "opacity"),
            (
                Particle {
                    half_size: 0.0,
                    ..p
                },
                "half_size",
            ),
            (
                Particle {
                    half_size: f32::INFINITY,
                    ..p
                },
                "half_size",
            ),
            (
                Particle {
                    half_size: f32::NAN,
                    ..p
                },
                "half_size",
            ),
            (
                Particle {
                    center: DVec3::new(f64::NAN, 0.0, 0.0),
                    ..p
                },
                "center",
            ),
            (
                Particle {
                    center: DVec3::splat(f64::INFINITY),
                    ..p
                },
                "center",
            ),
            (
                Particle {
                    center: DVec3::splat(3e9),
                    ..p
                },
                "center",
            ),
            (
                Particle {
                    emissive: f32::NAN,
                    ..p
                },
                "emissive",
            ),
            (
                Particle {
                    emissive: -1.0,
                    ..p
                },
                "emissive",
            ),
            (
                Particle {
                    emissive: MAX_EMISSIVE * 2.0,
                    ..p
                },
                "emissive",
            ),
        ];
        for (bad, field) in particles {
            let content = Content {
                particles: vec![p, p, bad],
                entities: vec![e],
            };
            let err = content.validate().unwrap_err();
            assert!(
                matches!(err, Error::InvalidContent { kind: "particle", index: 2, field: f, .. } if f == field),
                "{err}"
            );
            let m = err.to_string();
            assert!(m.contains("particle 2") && m.contains(field), "{m}");
        }
        let entities = [
            (
                Entity {
                    opacity: f32::NAN,
                    ..e
                },
                "opacity",
            ),
            (
                Entity {
                    half_extents: [1.0, 0.0, 1.0],
                    ..e
                },
                "half_extents",
            ),
            (
                Entity {
                    half_extents: [1.0, 1.0, f32::NAN],
                    ..e
                },
                "half_extents",
            ),
            (
                Entity {
                    rotation: DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0),
                    ..e
                },
                "rotation",
            ),
            (
                Entity {
                    rotation: DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0),
                    ..e
                },
                "rotation",
            ),
            (
                Entity {
                    center: DVec3::new(0.0, f64::NEG_INFINITY, 0.0),
                    ..e
                },
                "center",
            ),
            (
                Entity {
                    emissive: f32::INFINITY,
                    ..e
                },
                "emissive",
            ),
        ];
        for (bad, field) in entities {
            let content = Content {
                particles: vec![p],
                entities: vec![bad],
            };
            let err = content.validate().unwrap_err();
            assert!(
                matches!(err, Error::InvalidContent { kind: "entity", index: 0, field: f, .. } if f == field),
                "{err}"
            );
        }
        // The ends of each range are accepted.
        let edge = Content {
            particles: vec![Particle {
                opacity: 0.0,
                emissive: MAX_EMISSIVE,
                half_size: MAX_HALF_SIZE,
                ..p
            }],
            entities: vec![Entity {
                opacity: 1.0,
                emissive: 0.0,
                ..e
            }],
        };
        assert!(edge.validate().is_ok());
    }
}
