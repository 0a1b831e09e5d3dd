//! The demo's own game content, drawn through the renderer's frame stages like a game's
//! (`voxel_render::content`): bubbles rising through the water to its surface, a glass cube
//! turning as it bobs through the surface, and an opaque boat rocking on it. They are
//! placed where the first camera's view meets the water level and animated each frame.

use glam::{DQuat, DVec3};
use voxel_core::TerrainConfig;
use voxel_render::content::{Content, ContentStages, Entity, Particle};
use voxel_render::{Camera, GpuContext, Renderer, Technique};

/// Which content is shown (the panel's toggles).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Toggles {
    /// Bubbles rising through the water.
    pub bubbles: bool,
    /// The turning glass cube crossing the surface.
    pub cube: bool,
    /// The boat.
    pub boat: bool,
}

impl Toggles {
    /// All on or all off.
    pub fn all(on: bool) -> Self {
        Self {
            bubbles: on,
            cube: on,
            boat: on,
        }
    }

    fn any(self) -> bool {
        self.bubbles || self.cube || self.boat
    }
}

/// How many bubbles rise at once.
pub const BUBBLES: usize = 3000;

/// The content's place, its bubbles, and its stages for the renderer and the reference.
pub struct Game {
    /// A point on the water level in the first view.
    anchor: DVec3,
    /// Each bubble: position across the column (x, z offsets), rise speed, phase, size.
    bubbles: Vec<[f64; 5]>,
    stages: Option<ContentStages>,
    reference: Option<ContentStages>,
}

impl Game {
    /// Content on the water in front of `camera`: the nearest place at least 10 blocks
    /// away, 35° or 25° left or right of straight ahead first (beside what the view looks at), where `water(x, z)` holds for 6 blocks on
    /// (`None`: no water is known, e.g. a scene: 16 blocks ahead, 4 below the eye).
    pub fn new(camera: &Camera, water: Option<&dyn Fn(i64, i64) -> bool>) -> Self {
        let sea = f64::from(TerrainConfig::default().sea_level);
        let yaw = camera.forward.x.atan2(camera.forward.z);
        let at = |d: f64, deg: f64| {
            let a = yaw + deg.to_radians();
            camera.eye + DVec3::new(a.sin(), 0.0, a.cos()) * d
        };
        let wet = |p: DVec3| water.is_some_and(|w| w(p.x.floor() as i64, p.z.floor() as i64));
        let anchor = (10..60)
            .flat_map(|d| [-35.0, 35.0, -25.0, 25.0, 0.0].map(|a| (f64::from(d), a)))
            .find(|&(d, a)| (0..6).all(|k| wet(at(d + f64::from(k), a))))
            .map_or_else(
                || at(16.0, 0.0) - DVec3::Y * 4.0,
                |(d, a)| {
                    let p = at(d + 3.0, a);
                    DVec3::new(p.x, sea, p.z)
                },
            );
        log::info!("game content at {anchor:.1} (eye {:.1})", camera.eye);
        // A fixed xorshift stream: the same bubbles in every run.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let bubbles = (0..BUBBLES)
            .map(|_| {
                [
                    (next() - 0.5) * 8.0,
                    (next() - 0.5) * 8.0,
                    0.6 + next() * 1.4,
                    next(),
                    0.08 + next() * 0.14,
                ]
            })
            .collect();
        Self {
            anchor,
            bubbles,
            stages: None,
            reference: None,
        }
    }

    /// What is shown at `time` seconds.
    pub fn content(&self, toggles: Toggles, time: f64) -> Content {
        let a = self.anchor;
        let mut content = Content::default();
        if toggles.bubbles {
            // From 9 blocks down to the surface, where they burst and start again.
            const DEPTH: f64 = 9.0;
            content.particles = self
                .bubbles
                .iter()
                .map(|&[x, z, speed, phase, size]| {
                    let rise = (phase * DEPTH + time * speed).rem_euclid(DEPTH);
                    let wobble = 0.15 * (time * 3.0 * speed + phase * 40.0).sin();
                    Particle {
                        center: a + DVec3::new(x + wobble, rise - DEPTH, z),
                        half_size: size as f32,
                        color: [225, 240, 255],
                        opacity: 0.45,
                        emissive: 0.0,
                    }
                })
                .collect();
        }
        if toggles.cube {
            content.entities.push(Entity {
                center: a + DVec3::new(3.0, 0.3 * (time * 0.8).sin(), -1.5),
                half_extents: [1.4; 3],
                rotation: DQuat::from_euler(glam::EulerRot::YXZ, time * 0.6, 0.5, 0.3),
                color: [90, 225, 140],
                opacity: 0.45,
                emissive: 0.0,
            });
        }
        if toggles.boat {
            content.entities.push(Entity {
                center: a + DVec3::new(-3.5, 0.2 + 0.06 * (time * 1.3).sin(), 2.5),
                half_extents: [2.8, 0.45, 1.2],
                rotation: DQuat::from_euler(
                    glam::EulerRot::YXZ,
                    0.4,
                    0.0,
                    0.05 * (time * 1.1).sin(),
                ),
                color: [125, 82, 45],
                opacity: 1.0,
                emissive: 0.0,
            });
        }
        content
    }

    /// Sets this frame's content for the renderer (and the reference when it draws):
    /// `None` when nothing is shown (the renderer then draws no stage).
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        renderer: &mut Renderer,
        reference: Option<&mut Renderer>,
        toggles: Toggles,
        time: f64,
    ) -> voxel_render::Result<()> {
        if !toggles.any() {
            return Ok(());
        }
        let content = self.content(toggles, time);
        prepare(&mut self.stages, ctx, renderer, &content, true)?;
        match reference {
            Some(r) => prepare(&mut self.reference, ctx, r, &content, false)?,
            None => self.reference = None,
        }
        Ok(())
    }

    /// The stages to draw with the renderer and the reference this frame.
    pub fn stages(
        &mut self,
        toggles: Toggles,
    ) -> (Option<&mut ContentStages>, Option<&mut ContentStages>) {
        if !toggles.any() {
            return (None, None);
        }
        (self.stages.as_mut(), self.reference.as_mut())
    }
}

/// Makes or refreshes `stages` for `renderer` with `content` (its pipelines follow the
/// renderer's technique by themselves); made new, with `ahead` its pipelines for every
/// real-time technique the device runs are built at once, as the renderer built the
/// techniques (switching then compiles nothing).
fn prepare(
    stages: &mut Option<ContentStages>,
    ctx: &GpuContext,
    renderer: &mut Renderer,
    content: &Content,
    ahead: bool,
) -> voxel_render::Result<()> {
    match stages {
        Some(s) => s.set_content(ctx, content.clone())?,
        None => {
            let s = stages.insert(ContentStages::new(renderer, content.clone())?);
            if ahead {
                for t in Technique::supported(&ctx.caps) {
                    if !t.stalls() {
                        s.prebuild(renderer, t)?;
                    }
                }
            }
        }
    }
    Ok(())
}
