//! Lighting a surface (Lambert plus ambient, shaded by its ambient occlusion), the
//! per-picture light (sun, sky, the fog of a medium), and the tonemap.

use glam::DVec3;
use voxel_core::RenderClass;
use voxel_render::Camera;

use super::blocks::{flipped, interpolate};
use super::{RayMarcher, Shading, Surface};
use crate::content::{face_light, particle_light};

/// The tonemap of `shaders/tonemap.wgsl` (values up to the shoulder unchanged, then a
/// smooth roll-off towards 1), then sRGB encoding and 8-bit rounding.
pub(super) fn output(x: f64) -> u8 {
    let shoulder = f64::from(voxel_render::low_level::TONEMAP_SHOULDER);
    let t = if x <= shoulder {
        x.max(0.0)
    } else {
        let room = 1.0 - shoulder;
        shoulder + room * (1.0 - (-(x - shoulder) / room).exp())
    };
    let s = if t <= 0.003_130_8 {
        t * 12.92
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s.clamp(0.0, 1.0) * 255.0).round() as u8
}

impl RayMarcher {
    /// The lit colour of `surface` at point `p` with albedo `a`, under `light`.
    pub(super) fn lit(
        &self,
        surface: Surface,
        p: DVec3,
        a: [f64; 4],
        light: &Light,
        shading: &Shading,
    ) -> [f64; 3] {
        let face = surface.face;
        let n = face.normal();
        let sky = light.on(DVec3::from(n.map(f64::from)));
        let translucent = self.class(surface.id) == RenderClass::Translucent;
        let axis = face.axis();
        let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
        let s = (p[ua] - surface.block[ua] as f64).clamp(0.0, 1.0);
        let t = (p[va] - surface.block[va] as f64).clamp(0.0, 1.0);
        let shade = if translucent {
            1.0
        } else {
            self.ao(surface.block, face, s, t, f64::from(shading.ao_strength))
        };
        // The light field's sky and block light at the point (full sky light and no block
        // light unlit), then `light()` of `common.wgsl`.
        let levels: [f64; 6] = match &self.light {
            None => [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            Some(field) => {
                let c = self.corner_lights(field, surface.block, face, surface.id);
                let flip = flipped(self.ao_values(surface.block, face));
                std::array::from_fn(|ch| {
                    let corners = c.map(|l| f64::from(l[ch]) / 255.0);
                    interpolate(corners, flip, s, t)
                })
            }
        };
        // Sun shadows: the sky light lights the ambient share, the sun's own light what
        // reaches the point along its ray.
        let n = DVec3::from(n.map(f64::from));
        let n_dot_l = n.dot(light.sun).max(0.0);
        if let (Some(_), Some(sun), true) = (&self.light, &self.sun, n_dot_l > 0.0) {
            let from = p + n * f64::from(voxel_render::low_level::SUN_NUDGE);
            let t = sun.march(
                self.bounds,
                |c| self.get(c),
                from.to_array(),
                light.sun.to_array(),
            );
            return std::array::from_fn(|ch| {
                let sky = light.brightness
                    * (light.ambient * levels[ch]
                        + (1.0 - light.ambient) * n_dot_l * f64::from(t[ch]));
                a[ch] * sky.max(levels[ch + 3]) * shade
            });
        }
        std::array::from_fn(|ch| a[ch] * (levels[ch] * sky).max(levels[ch + 3]) * shade)
    }
}

/// Per-picture lighting: the sun, the sky, the medium's fog.
pub(super) struct Light {
    pub(super) sun: DVec3,
    pub(super) ambient: f64,
    /// Scales every lit colour (the sky is not lit).
    pub(super) brightness: f64,
    pub(super) sky: [f64; 3],
    pub(super) fog: Option<Fog>,
    /// What a medium's colour is lit by: a face turned to the sky.
    pub(super) medium_light: f64,
    /// The camera's forward, right and up (unit): particles face the camera.
    pub(super) basis: [DVec3; 3],
}

pub(super) struct Fog {
    pub(super) color: [f64; 3],
    pub(super) density: f64,
}

impl Light {
    /// The light on a surface of unit normal `normal`: Lambert with the sun plus ambient,
    /// at the light's brightness (`light` in the renderer's `common.wgsl`).
    pub(super) fn on(&self, normal: DVec3) -> f64 {
        self.brightness * face_light(normal, self.sun, self.ambient)
    }

    /// The light of a face turned to the sky: a particle's (a medium's colour is lit so
    /// too, `medium_light`).
    pub(super) fn sky(&self) -> f64 {
        self.brightness * particle_light(self.sun, self.ambient)
    }

    pub(super) fn new(m: &RayMarcher, camera: &Camera, shading: &Shading) -> Self {
        let s = shading.sun_dir.map(f64::from);
        let sun = DVec3::from(s).try_normalize().unwrap_or(DVec3::Y);
        let ambient = f64::from(shading.ambient);
        let brightness = f64::from(shading.brightness);
        let medium_light = brightness * particle_light(sun, ambient);
        let fog = camera
            .medium
            .and_then(|id| m.media.get(id.index()).copied().flatten())
            .map(|look| Fog {
                color: look.color.map(|c| c * medium_light),
                density: look.fog,
            });
        Self {
            sun,
            ambient,
            brightness,
            sky: shading.sky.map(f64::from),
            fog,
            medium_light,
            basis: super::view_basis(camera),
        }
    }
}
