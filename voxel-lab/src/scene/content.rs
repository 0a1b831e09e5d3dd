//! A scene file's particles and entities, checked, as a game's content.

use crate::Result;

use glam::DVec3;
use voxel_render::low_level::WORLD_EXTENT;

use super::fields::at_line;
use super::format::SceneFile;
use crate::content::rotation;
use voxel_render::content::{Content, Entity, MAX_EMISSIVE, Particle};

/// Most particles a scene file may ask for, in all: a frame draws each one (6 vertices),
/// and the ray march bins them per picture.
pub const MAX_PARTICLES: usize = 1_000_000;

/// The particles and entities of a scene file, checked.
pub(super) fn content_of(text: &str, file: &SceneFile) -> Result<Content> {
    let mut content = Content::default();
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite() && x.abs() < WORLD_EXTENT);
    for p in &file.particles {
        let (span, d) = (p.span(), p.get_ref());
        let bad = |why: &str| Err(at_line(text, span.start, format!("particles: {why}")));
        if !finite(&d.min) || !finite(&d.max) || (0..3).any(|i| d.min[i] > d.max[i]) {
            return bad("min and max must be finite, inside the world, min not above max");
        }
        if content.particles.len() + d.count > MAX_PARTICLES {
            return bad(&format!("more than {MAX_PARTICLES} particles in all"));
        }
        if !(d.size.is_finite() && d.size > 0.0 && d.size <= 64.0) {
            return bad("size (half a side, blocks) must be above 0 and at most 64");
        }
        if !(d.opacity.is_finite() && d.opacity > 0.0 && d.opacity <= 1.0) {
            return bad("opacity must be above 0 and at most 1");
        }
        if !(0.0..=MAX_EMISSIVE).contains(&d.emissive) {
            return bad(&format!(
                "emissive must be a number from 0 to {MAX_EMISSIVE}"
            ));
        }
        let emissive = d.emissive;
        content.particles.extend(
            Content::scatter(
                DVec3::from(d.min),
                DVec3::from(d.max),
                d.count,
                d.seed,
                d.size,
                d.color,
                d.opacity,
            )
            .into_iter()
            .map(|p| Particle { emissive, ..p }),
        );
    }
    for e in &file.entities {
        let (span, d) = (e.span(), e.get_ref());
        let bad = |why: &str| Err(at_line(text, span.start, format!("entities: {why}")));
        if !finite(&d.center) || !d.rotation.iter().all(|r| r.is_finite()) {
            return bad("center and rotation must be finite, the centre inside the world");
        }
        if !d
            .size
            .iter()
            .all(|s| s.is_finite() && *s > 0.0 && *s <= 256.0)
        {
            return bad("size must be above 0 and at most 256 blocks on each axis");
        }
        if !(d.opacity.is_finite() && d.opacity > 0.0 && d.opacity <= 1.0) {
            return bad("opacity must be above 0 and at most 1 (1: opaque)");
        }
        if !(0.0..=MAX_EMISSIVE).contains(&d.emissive) {
            return bad(&format!(
                "emissive must be a number from 0 to {MAX_EMISSIVE}"
            ));
        }
        content.entities.push(Entity {
            center: DVec3::from(d.center),
            half_extents: d.size.map(|s| s / 2.0),
            rotation: rotation(d.rotation),
            color: d.color,
            opacity: d.opacity,
            emissive: d.emissive,
        });
    }
    Ok(content)
}
