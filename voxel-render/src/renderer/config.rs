//! The settings of a renderer ([`RendererConfig`], [`Lighting`], the output formats) and
//! their checks.

#[cfg(doc)]
use super::Renderer;
use crate::chunks::DrawMode;
use crate::fetch::QuadFetch;
use crate::oit::OitConfig;
use crate::{Error, GpuContext, Result};

/// Settings of a [`Renderer`]. Every field has a reasoned default.
#[derive(Clone, Debug, PartialEq)]
pub struct RendererConfig {
    /// Output width in pixels. Zero is raised to 1 (a renderer always has targets); more
    /// than the adapter's `max_texture_dimension_2d` is an error.
    pub width: u32,
    /// Output height in pixels, like `width`.
    pub height: u32,
    /// Format of the textures `render` draws into first (its tonemap pipeline is built
    /// with the renderer). Default `Rgba8UnormSrgb`, what offscreen readback and PNG files
    /// want. Any of [`OUTPUT_FORMATS`] works without changing this: an output of another
    /// format gets its tonemap pipeline at its first frame (once per format, about a
    /// millisecond), and this field follows the format drawn last.
    pub output_format: wgpu::TextureFormat,
    /// The format of the views `render` is given, where they differ from their texture's:
    /// the sRGB or linear twin of the texture's format (a surface configured with
    /// `view_formats`). Default `None`: every view has its texture's format, which is
    /// what wgpu gives unless asked otherwise. A view format the texture cannot have is
    /// ignored.
    pub output_view_format: Option<wgpu::TextureFormat>,
    /// 4× MSAA for the opaque and cutout passes. Default off: the translucent pass is
    /// single-sampled anyway and lavapipe pays 4× for it.
    pub msaa: bool,
    /// Transparency settings (technique and each technique's own settings).
    pub oit: OitConfig,
    /// Direction towards the sun (normalised on use; a zero vector means straight up).
    /// Default: high in the south-east, so that every face direction gets a different
    /// brightness. NaN or infinite components are an error at [`Renderer::new`].
    pub sun_dir: [f32; 3],
    /// Ambient share of the lighting, 0 to 1 (outside, NaN or infinite: an error at
    /// [`Renderer::new`]). Default 0.45: faces away from the sun stay readable.
    pub ambient: f32,
    /// How bright the sun's (or the moon's) and the ambient light are, from 0 to
    /// [`Lighting::MAX_BRIGHTNESS`] (else an error at [`Renderer::new`]): every lit colour
    /// is scaled by it, the sky is not. Default 1, daylight; [`Lighting::daytime`] lowers
    /// it at night.
    pub brightness: f32,
    /// Sky colour (linear), each channel from 0 to [`Lighting::MAX_BRIGHTNESS`] (else an
    /// error at [`Renderer::new`]). Default a light blue.
    pub sky: [f32; 3],
    /// How chunk meshes are drawn. Default: indirect (`multi_draw_indirect` per page and
    /// pass), which costs the CPU next to nothing per chunk; adapters without indirect
    /// first-instance draws, and [`QuadFetch::Instanced`], draw one mesh per draw (logged).
    pub draw: DrawMode,
    /// Frames over which a newly uploaded chunk fades in (screen-door dissolve of its
    /// opaque and cutout faces, alpha ramp of its translucent ones). Default 0: off, so
    /// that a picture depends only on the scene; the interactive demo turns it on.
    pub fade_in_frames: u32,
    /// How strongly the mesher's per-vertex ambient occlusion darkens, 0 to 1. Default 1:
    /// one-block steps of terrain read as steps. 0 draws every face with its Lambert light
    /// alone (the pictures before ambient occlusion).
    pub ao_strength: f32,
    /// Every block drawn in one flat colour (its base colour and opacity; cutout blocks
    /// solid), no texture pattern. Default off. For comparisons with references that
    /// cannot filter textures as a GPU does (the lab's CPU ray march).
    pub flat_textures: bool,
    /// How the chunk pipelines fetch quads. Default `None`: the first of
    /// [`QuadFetch::ALL`] the device can (storage buffers where the vertex stage has them,
    /// else instance attributes). A way the device cannot is an [`Error::Unsupported`].
    pub quad_fetch: Option<QuadFetch>,
}

impl Default for RendererConfig {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            output_format: wgpu::TextureFormat::Rgba8UnormSrgb,
            output_view_format: None,
            msaa: false,
            oit: OitConfig::default(),
            sun_dir: [0.35, 0.85, 0.4],
            ambient: 0.45,
            brightness: 1.0,
            sky: [0.45, 0.65, 0.9],
            draw: DrawMode::Indirect,
            fade_in_frames: 0,
            ao_strength: 1.0,
            flat_textures: false,
            // The device decides: both draw the same picture.
            quad_fetch: None,
        }
    }
}

/// The formats [`Renderer::render`] draws into: what surfaces offer (BGRA and RGBA, sRGB or
/// not; 10-bit; half float, written linear) and what offscreen targets use. An sRGB format
/// is encoded by the GPU, the 8- and 10-bit linear ones by the tonemap shader, so every
/// one shows the same picture.
pub const OUTPUT_FORMATS: [wgpu::TextureFormat; 6] = [
    wgpu::TextureFormat::Rgba8UnormSrgb,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Bgra8UnormSrgb,
    wgpu::TextureFormat::Bgra8Unorm,
    wgpu::TextureFormat::Rgb10a2Unorm,
    wgpu::TextureFormat::Rgba16Float,
];

/// The format to draw an output texture of `format` with: `view` when it is given and is
/// the texture's sRGB / linear twin ([`RendererConfig::output_view_format`]), else the
/// texture's own.
pub(super) fn output_format(
    view: Option<wgpu::TextureFormat>,
    format: wgpu::TextureFormat,
) -> wgpu::TextureFormat {
    match view {
        Some(v) if v.remove_srgb_suffix() == format.remove_srgb_suffix() => v,
        _ => format,
    }
}

/// Lighting a renderer draws with ([`Renderer::set_lighting`]); its fields are those of
/// [`RendererConfig`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Direction towards the sun (normalised on use).
    pub sun_dir: [f32; 3],
    /// Ambient share of the lighting, 0 to 1.
    pub ambient: f32,
    /// How bright the light is (1 by day, 0.12 at night in [`Lighting::daytime`]), from 0 to
    /// [`Lighting::MAX_BRIGHTNESS`].
    pub brightness: f32,
    /// Sky colour (linear), what the background is cleared to, each channel from 0 to
    /// [`Lighting::MAX_BRIGHTNESS`].
    pub sky: [f32; 3],
}

impl Lighting {
    /// The hour the sun rises in [`Lighting::daytime`].
    pub(crate) const SUNRISE: f32 = 6.0;
    /// The hour the sun sets in [`Lighting::daytime`].
    pub(crate) const SUNSET: f32 = 18.0;
    /// The brightness of moonlight (night in [`Lighting::daytime`]), a share of daylight.
    pub(crate) const MOONLIGHT: f32 = 0.12;
    /// The largest brightness, and sky channel, a renderer takes: a larger one (up to
    /// `f32::MAX`) is an `Error::InvalidSetting`. The scene colour is half floats
    /// ([`crate::SCENE_FORMAT`], largest finite value 65 504), where a GPU makes a larger
    /// value infinite (lavapipe saturates it) and the tonemap shows infinity as magenta;
    /// with lit colours at most 64, the techniques' sums of them stay finite too (WBOIT
    /// sums 22 layers of its largest weight before 65 504, with its default headroom).
    /// Nothing is lost: the tonemap rolls every channel above 0.8 towards 1, so a face lit
    /// 64 times daylight is already white.
    pub const MAX_BRIGHTNESS: f32 = 64.0;

    /// The lighting of [`RendererConfig::default`].
    pub fn default_day() -> Self {
        let c = RendererConfig::default();
        Self {
            sun_dir: c.sun_dir,
            ambient: c.ambient,
            brightness: c.brightness,
            sky: c.sky,
        }
    }

    /// The lighting at `hour` of a 24-hour day (any finite hour, taken modulo 24; NaN or
    /// infinite: noon). Day, 6 h to 18 h: the sun rises
    /// in the east (+x), stands highest in the south (+z) at noon and sets in the west;
    /// the ambient share falls from 0.45 at noon to 0.2 at the horizon, and the sky turns
    /// from light blue to a dusk orange. Night, from an hour after sunset to an hour before
    /// sunrise: the moon crosses the sky on the sun's path, its light
    /// 0.12 bright, more of it ambient (0.5), under a dark blue sky.
    /// Twilight, the hour between: day and night blended, so that a clock running
    /// through the day changes the light smoothly. A model for a time-of-day control, not
    /// an atmosphere.
    pub fn daytime(hour: f32) -> Self {
        let hour = if hour.is_finite() {
            hour.rem_euclid(24.0)
        } else {
            12.0
        };
        let (rise, set) = (Self::SUNRISE, Self::SUNSET);
        if (rise..=set).contains(&hour) {
            return Self::sun(hour);
        }
        // Hours since sunset, 0 to 12: twilight in the first and the last hour.
        let since = (hour - set).rem_euclid(24.0);
        let night_len = 24.0 - (set - rise);
        if since < 1.0 {
            Self::blend(Self::sun(set), Self::moon(1.0 / night_len), since)
        } else if since > night_len - 1.0 {
            let t = since - (night_len - 1.0);
            Self::blend(
                Self::moon((night_len - 1.0) / night_len),
                Self::sun(rise),
                t,
            )
        } else {
            Self::moon(since / night_len)
        }
    }

    /// A body on the daily path at `a` (0 rising in the east, pi setting in the west): a
    /// path leaning toward the south (z = 0.47 y: at 10:30 this is the default lighting's
    /// sun within a few degrees), a few degrees above the horizon at either end so that
    /// the sides facing it keep some light.
    fn path(a: f32) -> glam::Vec3 {
        let elevation = 0.08 + 0.92 * a.sin();
        glam::Vec3::new(a.cos(), elevation, 0.47 * elevation).normalize_or(glam::Vec3::Y)
    }

    /// Daylight at `hour`, from sunrise to sunset.
    fn sun(hour: f32) -> Self {
        let a = (hour - Self::SUNRISE) / (Self::SUNSET - Self::SUNRISE) * std::f32::consts::PI;
        let day = glam::Vec3::from([0.45, 0.65, 0.9]);
        let dusk = glam::Vec3::from([0.85, 0.45, 0.25]);
        let t = a.sin().clamp(0.0, 1.0).sqrt();
        Self {
            sun_dir: Self::path(a).to_array(),
            ambient: 0.2 + 0.25 * t,
            brightness: 1.0,
            sky: dusk.lerp(day, t).to_array(),
        }
    }

    /// Moonlight with the moon `share` (0 to 1) of the way across the sky.
    fn moon(share: f32) -> Self {
        Self {
            sun_dir: Self::path(share * std::f32::consts::PI).to_array(),
            ambient: 0.5,
            brightness: Self::MOONLIGHT,
            sky: [0.012, 0.018, 0.045],
        }
    }

    /// `a` turning into `b` as `t` goes from 0 to 1 (smoothly at both ends). The light
    /// turns all ambient halfway, where the direction changes from `a`'s to `b`'s, so that
    /// no face's light jumps.
    fn blend(a: Self, b: Self, t: f32) -> Self {
        let s = t * t * (3.0 - 2.0 * t);
        let mix = |x: f32, y: f32| x + (y - x) * s;
        let (body, half) = if s < 0.5 {
            (a, s * 2.0)
        } else {
            (b, 2.0 - s * 2.0)
        };
        Self {
            sun_dir: body.sun_dir,
            ambient: body.ambient + (1.0 - body.ambient) * half,
            brightness: mix(a.brightness, b.brightness),
            sky: std::array::from_fn(|i| mix(a.sky[i], b.sky[i])),
        }
    }

    /// Checks the values: a finite non-zero sun direction, an ambient share from 0 to 1, a
    /// brightness and sky channels from 0 to [`Lighting::MAX_BRIGHTNESS`].
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::InvalidSetting(what));
        if let Err(why) = voxel_core::unit_direction(self.sun_dir.map(f64::from)) {
            return bad(format!("sun direction {:?}: {why}", self.sun_dir));
        }
        if !(0.0..=1.0).contains(&self.ambient) {
            return bad(format!("ambient {}: it must be from 0 to 1", self.ambient));
        }
        check_light(self.brightness, self.sky)
    }
}

/// The output format must be one the tonemap writes: a colour format sampled as float
/// (the shader writes `vec4<f32>`) that every adapter can render to.
pub(super) fn check_output_format(ctx: &GpuContext, format: wgpu::TextureFormat) -> Result<()> {
    let float = matches!(
        format.sample_type(None, Some(ctx.caps.features)),
        Some(wgpu::TextureSampleType::Float { .. })
    );
    let renderable = format
        .guaranteed_format_features(ctx.caps.features)
        .allowed_usages
        .contains(wgpu::TextureUsages::RENDER_ATTACHMENT);
    if !format.has_color_aspect() || format.has_depth_aspect() || !float || !renderable {
        return Err(Error::InvalidSetting(format!(
            "output_format {format:?}: the tonemap writes float colour, so it must be a \
             renderable float colour format (e.g. Rgba8UnormSrgb, Bgra8UnormSrgb, Rgba16Float)"
        )));
    }
    Ok(())
}

/// The sun direction at length 1, normalised in f64 so that any finite non-zero
/// direction (`[1e38; 3]`, `[f32::MAX, 0, 0]`) is the same direction at length 1; a zero
/// one (accepted by `Renderer::new`, refused by `set_lighting`) is straight up.
pub(super) fn sun_unit(sun: [f32; 3]) -> glam::Vec3 {
    voxel_core::unit_direction(sun.map(f64::from))
        .map_or(glam::Vec3::Y, |d| glam::DVec3::from(d).as_vec3())
}

/// Lighting values must be numbers the shaders can use: NaN or infinity would reach
/// every pixel.
pub(super) fn check_lighting(config: &RendererConfig) -> Result<()> {
    let bad = |m: String| Err(Error::InvalidSetting(m));
    // A zero sun direction is the documented fallback here: straight up.
    if !config.sun_dir.iter().all(|v| v.is_finite()) {
        return bad(format!(
            "sun_dir {:?}: every component must be finite",
            config.sun_dir
        ));
    }
    if !(0.0..=1.0).contains(&config.ambient) {
        return bad(format!(
            "ambient {}: it must be a share from 0 to 1",
            config.ambient
        ));
    }
    check_light(config.brightness, config.sky)
}

/// A brightness and sky channels from 0 to [`Lighting::MAX_BRIGHTNESS`] (NaN is neither).
fn check_light(brightness: f32, sky: [f32; 3]) -> Result<()> {
    let range = 0.0..=Lighting::MAX_BRIGHTNESS;
    if !range.contains(&brightness) {
        return Err(Error::InvalidSetting(format!(
            "brightness {brightness}: it must be from 0 to {} (Lighting::MAX_BRIGHTNESS)",
            Lighting::MAX_BRIGHTNESS
        )));
    }
    if !sky.iter().all(|c| range.contains(c)) {
        return Err(Error::InvalidSetting(format!(
            "sky colour {sky:?}: every channel must be from 0 to {} (Lighting::MAX_BRIGHTNESS)",
            Lighting::MAX_BRIGHTNESS
        )));
    }
    Ok(())
}

/// An ambient-occlusion strength must be a number from 0 to 1.
pub(super) fn check_ao_strength(strength: f32) -> Result<()> {
    if (0.0..=1.0).contains(&strength) {
        Ok(())
    } else {
        Err(Error::InvalidSetting(format!(
            "ambient-occlusion strength {strength}: it must be from 0 to 1"
        )))
    }
}

/// A render size must fit the adapter's 2D textures.
pub(super) fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
    let limit = ctx.caps.limits.max_texture_dimension_2d;
    for (what, value) in [("render width", width), ("render height", height)] {
        if value > limit {
            return Err(Error::TooLarge {
                what: what.into(),
                value: u64::from(value),
                limit_name: "max_texture_dimension_2d",
                limit: u64::from(limit),
            });
        }
    }
    Ok(())
}
