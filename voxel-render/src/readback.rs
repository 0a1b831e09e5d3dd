//! Reading textures back to the CPU, and PNG files.

use std::path::Path;

use crate::{Error, GpuContext, Result};

/// An RGBA8 image, rows top to bottom, tightly packed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The pixel at `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Writes the image as an sRGB PNG, creating parent folders.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let io = |error| Error::Io {
            path: path.to_owned(),
            error,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let png = |error| Error::PngEncode {
            path: path.to_owned(),
            error,
        };
        // Encoded in memory and written in one call whose result is checked: a buffered
        // file writer dropped at the end would lose the error of its last flush (a full
        // disk, `/dev/full`).
        let mut bytes = Vec::new();
        let mut enc = png::Encoder::new(&mut bytes, self.width, self.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut w = enc.write_header().map_err(png)?;
        w.write_image_data(&self.rgba).map_err(png)?;
        w.finish().map_err(png)?;
        write_file(path, &bytes)
    }

    /// The largest side [`Image::load_png`] reads: wgpu's 2D texture limit on every
    /// backend's top tier (a 16 384² RGBA image is 1 GiB decoded).
    pub const MAX_PNG_SIDE: u32 = 16_384;

    /// Reads an 8-bit PNG (grey, RGB or RGBA; palettes expanded) of at most
    /// [`Image::MAX_PNG_SIDE`] a side (see `Image::load_png_within`).
    pub fn load_png(path: &Path) -> Result<Self> {
        Self::load_png_within(path, Self::MAX_PNG_SIDE)
    }

    /// Reads a PNG whose header says it is at most `max_side` pixels wide and high; a
    /// larger one is an [`Error::Image`] naming its size, found from the header before
    /// anything is allocated, so a small file claiming a huge image costs nothing. The
    /// decoder's own allocation limit is set to what such an image needs.
    pub(crate) fn load_png_within(path: &Path, max_side: u32) -> Result<Self> {
        let file = std::fs::File::open(path).map_err(|error| Error::Io {
            path: path.to_owned(),
            error,
        })?;
        let png = |error| Error::PngDecode {
            path: path.to_owned(),
            error,
        };
        // Room for the decoded frame (16-bit samples, 4 channels, before stripping)
        // plus the decoder's own buffers.
        let side = u64::from(max_side);
        let bytes = usize::try_from(side * side * 8 + (1 << 20)).unwrap_or(usize::MAX);
        let mut dec =
            png::Decoder::new_with_limits(std::io::BufReader::new(file), png::Limits { bytes });
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = dec.read_info().map_err(png)?;
        let (width, height) = (reader.info().width, reader.info().height);
        if width > max_side || height > max_side {
            return Err(Error::Image {
                path: path.to_owned(),
                error: voxel_core::Error::InvalidImage(format!(
                    "{width}x{height} pixels (from the PNG header): at most {max_side} a side"
                )),
            });
        }
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| png(png::DecodingError::LimitsExceeded))?;
        let mut buf = vec![0; size];
        let info = reader.next_frame(&mut buf).map_err(png)?;
        let data = &buf[..info.buffer_size()];
        let rgba = match info.color_type {
            png::ColorType::Rgba => data.to_vec(),
            png::ColorType::Rgb => data
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            png::ColorType::GrayscaleAlpha => data
                .chunks_exact(2)
                .flat_map(|p| [p[0], p[0], p[0], p[1]])
                .collect(),
            png::ColorType::Grayscale | png::ColorType::Indexed => {
                data.iter().flat_map(|&g| [g, g, g, 255]).collect()
            }
        };
        Ok(Self {
            width: info.width,
            height: info.height,
            rgba,
        })
    }
}

/// Writes `bytes` to `path` in one checked call; when the write fails part way (a full
/// disk), the partial file is removed rather than left looking like a result. The error
/// names the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|error| {
        // Only a regular file is removed (never a device such as `/dev/full`).
        if std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(path);
        }
        Error::Io {
            path: path.to_owned(),
            error,
        }
    })
}

/// Copies a whole single-sample 2D texture to the CPU, row padding removed. Blocks until
/// the GPU is done. Returns `width * height * bytes_per_texel` bytes.
///
/// The texture needs `COPY_SRC` usage, one sample and one layer, and `bytes_per_texel`
/// must be its format's (4 for `Rgba8Unorm` and `Depth32Float`, 8 for `Rgba16Float`);
/// anything else is an [`Error::Unreadable`] naming what is wrong, before anything is
/// recorded. So is a depth texture on a device without
/// `DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES` (wgpu's GL backend): read those
/// with [`read_depth`].
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>> {
    let copy = copy_texture(ctx, texture, bytes_per_texel)?;
    let bytes = map_read(ctx, &copy.buffer)?;
    Ok(copy.rows(&bytes))
}

/// A texture copied into a mappable buffer, the copy submitted: the first half of
/// [`read_texture`], for a caller that maps [`TextureCopy::buffer`] itself (a web page
/// awaits the map instead of blocking) and then takes [`TextureCopy::rows`].
#[derive(Debug)]
pub struct TextureCopy {
    /// The buffer the texture was copied into (`MAP_READ`), rows padded to wgpu's
    /// alignment.
    pub buffer: wgpu::Buffer,
    row: u32,
    padded: u32,
    height: u32,
}

impl TextureCopy {
    /// The texels of the mapped buffer's bytes `mapped`, row padding removed:
    /// `width * height * bytes_per_texel` bytes.
    pub fn rows(&self, mapped: &[u8]) -> Vec<u8> {
        let (row, padded) = (self.row as usize, self.padded as usize);
        let mut out = Vec::with_capacity(row * self.height as usize);
        for r in 0..self.height as usize {
            let start = r * padded;
            out.extend_from_slice(&mapped[start..start + row]);
        }
        out
    }
}

/// Copies a whole single-sample 2D texture into a new mappable buffer and submits the copy;
/// what [`read_texture`] checks and refuses, this does.
pub fn copy_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<TextureCopy> {
    ctx.check_device()?;
    check_copyable(ctx, texture, bytes_per_texel)?;
    let (w, h) = (texture.width(), texture.height());
    let row = w * bytes_per_texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let size = u64::from(padded) * u64::from(h);
    // One buffer holds the whole texture: past the adapter's largest buffer (an RGBA16F
    // 16384² picture is 2 GiB) it is an error, not wgpu's validation panic.
    let limit = ctx.caps.limits.max_buffer_size;
    if size > limit {
        return Err(Error::TooLarge {
            what: format!("a readback of {w}x{h} pixels of {bytes_per_texel} bytes, in bytes,"),
            value: size,
            limit_name: "max_buffer_size",
            limit,
        });
    }
    // What the checks above cannot see (a texture of another device) is an error too.
    let (buffer, commands) = crate::error::scoped(&ctx.device, "reading a texture back", || {
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            texture.size(),
        );
        (buffer, encoder.finish())
    })?;
    ctx.queue.submit([commands]);
    Ok(TextureCopy {
        buffer,
        row,
        padded,
        height: h,
    })
}

/// What [`read_texture`] needs of `texture`, checked before anything is recorded.
fn check_copyable(ctx: &GpuContext, texture: &wgpu::Texture, bytes_per_texel: u32) -> Result<()> {
    let format = texture.format();
    let bad = |why: String| Err(Error::Unreadable(format!("a {format:?} texture: {why}")));
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return bad(format!("no COPY_SRC usage ({:?})", texture.usage()));
    }
    if texture.sample_count() != 1 {
        return bad(format!(
            "{} samples (only single-sample textures are copied)",
            texture.sample_count()
        ));
    }
    if texture.dimension() != wgpu::TextureDimension::D2 || texture.depth_or_array_layers() != 1 {
        return bad(format!(
            "{:?} with {} layers (only a single 2D layer is read)",
            texture.dimension(),
            texture.depth_or_array_layers()
        ));
    }
    if format.is_depth_stencil_format()
        && !ctx
            .caps
            .downlevel
            .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES)
    {
        return bad(format!(
            "{} copies no depth texture to a buffer (it lacks \
             DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES, as wgpu's GL backend does); \
             readback::read_depth reads it through a pass",
            ctx.caps.adapter_name
        ));
    }
    match format.block_copy_size(None) {
        Some(size) if format.block_dimensions() == (1, 1) && size == bytes_per_texel => Ok(()),
        Some(size) if format.block_dimensions() == (1, 1) => bad(format!(
            "{bytes_per_texel} bytes a texel asked, the format has {size}"
        )),
        _ => bad("a format copied by aspect or in blocks, which is not read here".into()),
    }
}

/// Reads a whole single-sample 2D depth texture back, one `f32` a texel, rows top to
/// bottom. Blocks until the GPU is done. A `Depth32Float` texture with `COPY_SRC` usage
/// is copied where the device copies depth textures; otherwise (wgpu's GL backend, which
/// has no depth-to-buffer copy, or another depth format) a pass samples it into an
/// `R32Uint` texture, bit for bit, and that is read: the texture then needs
/// `TEXTURE_BINDING` usage. A texture that allows neither, is not a depth format, is
/// multisampled or is not a single 2D layer is an [`Error::Unreadable`].
pub fn read_depth(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<f32>> {
    ctx.check_device()?;
    let format = texture.format();
    if !format.has_depth_aspect() {
        return Err(Error::Unreadable(format!(
            "a {format:?} texture is not a depth texture (read_texture reads colour)"
        )));
    }
    let copies = ctx
        .caps
        .downlevel
        .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
    let bytes = if format == wgpu::TextureFormat::Depth32Float
        && copies
        && texture.usage().contains(wgpu::TextureUsages::COPY_SRC)
    {
        read_texture(ctx, texture, 4)?
    } else {
        read_depth_through_pass(ctx, texture)?
    };
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// The depth of each texel as the bits of an `f32`, written by a full-screen pass into an
/// `R32Uint` texture (colour-renderable everywhere, WebGL2 included) and read back.
///
/// The depth is sampled with a nearest sampler at the texel's centre through a
/// non-filterable float binding, as the renderer's passes read depth (`gpu::DEPTH_READ`
/// says why: GLSL has no load from depth textures).
fn read_depth_through_pass(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>> {
    let format = texture.format();
    if !texture
        .usage()
        .contains(wgpu::TextureUsages::TEXTURE_BINDING)
        || texture.sample_count() != 1
        || texture.dimension() != wgpu::TextureDimension::D2
        || texture.depth_or_array_layers() != 1
    {
        return Err(Error::Unreadable(format!(
            "a {format:?} texture: a depth texture is read with COPY_SRC usage where the device \
             copies depth ({}), else through a pass, which needs TEXTURE_BINDING usage, one \
             sample and one 2D layer (this one: {:?}, {} samples, {:?} with {} layers)",
            ctx.caps.adapter_name,
            texture.usage(),
            texture.sample_count(),
            texture.dimension(),
            texture.depth_or_array_layers()
        )));
    }
    let device = &ctx.device;
    let bits = crate::error::scoped(device, "reading a depth texture through a pass", || {
        let bits = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth_readback_bits"),
            size: texture.size(),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Uint,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("depth_readback"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                    count: None,
                },
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("depth_readback"),
            source: wgpu::ShaderSource::Wgsl(DEPTH_READBACK_WGSL.into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("depth_readback"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("depth_readback"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::TextureFormat::R32Uint.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let source = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("depth_readback_source"),
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("depth_readback"),
            ..Default::default()
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth_readback"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&source),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        let target = bits.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("depth_readback"),
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth_readback"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..3, 0..1);
        }
        (bits, encoder.finish())
    })?;
    let (bits, commands) = bits;
    ctx.queue.submit([commands]);
    read_texture(ctx, &bits, 4)
}

/// [`read_depth_through_pass`]'s shader: a full-screen triangle writing each texel's
/// depth, sampled at its centre, as bits.
const DEPTH_READBACK_WGSL: &str = "
@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var nearest: sampler;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) u32 {
    let uv = (floor(p.xy) + 0.5) / vec2<f32>(textureDimensions(depth));
    return bitcast<u32>(textureSampleLevel(depth, nearest, uv, 0.0).x);
}
";

/// Copies a whole single-sample 2D texture of 8-bit RGBA or BGRA (sRGB or not) to the CPU
/// as an [`Image`] (BGRA swizzled to RGBA, bytes as stored). Blocks until the GPU is done.
/// Another format is an error naming it. The texture needs `COPY_SRC` usage.
pub fn read_image(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Image> {
    use wgpu::TextureFormat as F;
    let bgra = match texture.format() {
        F::Rgba8Unorm | F::Rgba8UnormSrgb => false,
        F::Bgra8Unorm | F::Bgra8UnormSrgb => true,
        other => {
            return Err(Error::Output(format!(
                "format {other:?}: only 8-bit RGBA and BGRA textures are read as images"
            )));
        }
    };
    let mut rgba = read_texture(ctx, texture, 4)?;
    if bgra {
        for p in rgba.chunks_exact_mut(4) {
            p.swap(0, 2);
        }
    }
    Ok(Image {
        width: texture.width(),
        height: texture.height(),
        rgba,
    })
}

/// Maps a `MAP_READ` buffer, waits, and copies its contents out. In a browser, whose page
/// cannot wait for the GPU, an error unless the mapping is done at once.
pub(crate) fn map_read(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    ctx.check_device()?;
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
    #[cfg(not(target_arch = "wasm32"))]
    let mapped = rx.recv().ok();
    // Blocking on a channel panics on wasm32's one thread.
    #[cfg(target_arch = "wasm32")]
    let mapped = rx.try_recv().ok();
    mapped.ok_or_else(|| {
        Error::ReadbackData(
            "the mapping callback never ran (a browser maps buffers on its event loop: \
             map them with wgpu's map_async there)"
                .into(),
        )
    })??;
    let data = buffer.slice(..).get_mapped_range()?.to_vec();
    buffer.unmap();
    Ok(data)
}

/// Converts IEEE half-precision bits to f32 (for reading `Rgba16Float` targets).
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = (h >> 10) & 0x1f;
    let frac = f32::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        0x1f if frac == 0.0 => sign * f32::INFINITY,
        0x1f => f32::NAN,
        e => sign * (1.0 + frac / 1024.0) * 2f32.powi(i32::from(e) - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert!(f16_to_f32(0x7c00).is_infinite());
        assert!(f16_to_f32(0x7e00).is_nan());
    }

    #[test]
    fn png_round_trip() {
        let img = Image {
            width: 3,
            height: 2,
            rgba: (0..24).map(|i| (i * 10) as u8).collect(),
        };
        let path =
            std::env::temp_dir().join(format!("voxel_render_png_{}.png", std::process::id()));
        img.save_png(&path).unwrap();
        assert_eq!(Image::load_png(&path).unwrap(), img);
        let _ = std::fs::remove_file(path);
    }

    /// A full disk is an error naming the file, not a silent success.
    #[test]
    fn a_failed_png_write_is_an_error_naming_the_file() {
        let img = Image {
            width: 64,
            height: 64,
            rgba: vec![7; 64 * 64 * 4],
        };
        let full = Path::new("/dev/full");
        if full.exists() {
            let e = img.save_png(full).unwrap_err();
            assert!(matches!(e, Error::Io { .. }), "{e:?}");
            assert!(e.to_string().contains("/dev/full"), "{e}");
        }
        // A folder where the file should be.
        let dir = std::env::temp_dir().join(format!("voxel_render_png_dir_{}", std::process::id()));
        std::fs::create_dir_all(dir.join("x.png")).unwrap();
        let e = img.save_png(&dir.join("x.png")).unwrap_err();
        assert!(e.to_string().contains("x.png"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }
}

const IDLE: u8 = 0;
const MAPPING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

/// A query set whose results are copied to the CPU without stalling: resolved and copied
/// at the end of a frame's commands, mapped when those are submitted (nothing to call),
/// read a frame or more later (or at once with [`QueryReadback::wait`]). While one copy is
/// in flight, further copies are skipped rather than waited for; a copy whose encoder is
/// dropped unsubmitted frees the buffer again.
#[derive(Debug)]
pub(crate) struct QueryReadback {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    state: std::sync::Arc<std::sync::atomic::AtomicU8>,
    pending: u32,
}

/// Held by a copy's deferred mapping: dropped without the mapping having run (its encoder
/// was dropped unsubmitted), it frees the readback buffer for the next copy.
struct Mapping(std::sync::Arc<std::sync::atomic::AtomicU8>);

impl Drop for Mapping {
    fn drop(&mut self) {
        use std::sync::atomic::Ordering;
        let _ = self
            .0
            .compare_exchange(MAPPING, IDLE, Ordering::AcqRel, Ordering::Acquire);
    }
}

impl QueryReadback {
    /// `count` queries of `ty`.
    pub(crate) fn new(ctx: &GpuContext, label: &str, ty: wgpu::QueryType, count: u32) -> Self {
        let size = u64::from(count) * 8;
        let buffer = |suffix: &str, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label}_{suffix}")),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty,
                count,
            }),
            resolve: buffer(
                "resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            state: std::sync::Arc::new(std::sync::atomic::AtomicU8::new(IDLE)),
            pending: 0,
        }
    }

    /// The query set passes write to.
    pub(crate) fn set(&self) -> &wgpu::QuerySet {
        &self.set
    }

    /// Records the copy of queries `range` (to be read as results `0..len`) and its
    /// mapping when `encoder` is submitted, unless a copy is already in flight. Returns
    /// whether it was recorded.
    pub(crate) fn copy(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        range: std::ops::Range<u32>,
    ) -> bool {
        use std::sync::atomic::Ordering;
        let n = range.end.saturating_sub(range.start);
        if n == 0 || self.state.load(Ordering::Acquire) != IDLE {
            return false;
        }
        encoder.resolve_query_set(&self.set, range, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, u64::from(n) * 8);
        self.pending = n;
        self.state.store(MAPPING, Ordering::Release);
        let mapping = Mapping(self.state.clone());
        encoder.map_buffer_on_submit(&self.readback, wgpu::MapMode::Read, .., move |r| {
            mapping
                .0
                .store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
        });
        true
    }

    /// The results once mapped (`Ok(None)` until then; needs `device.poll` now and then),
    /// and frees the buffer for the next copy. A failed mapping is an error.
    pub(crate) fn take(&mut self) -> Result<Option<Vec<u64>>> {
        use std::sync::atomic::Ordering;
        match self.state.load(Ordering::Acquire) {
            MAPPED => {
                let values = self.readback.slice(..).get_mapped_range().map(|v| {
                    bytemuck::cast_slice::<u8, u64>(&v[..self.pending as usize * 8]).to_vec()
                });
                self.readback.unmap();
                self.state.store(IDLE, Ordering::Release);
                Ok(Some(values?))
            }
            FAILED => {
                self.state.store(IDLE, Ordering::Release);
                Err(Error::ReadbackData(
                    "mapping the query results failed".into(),
                ))
            }
            _ => Ok(None),
        }
    }

    /// Waits for the copy in flight, then [`QueryReadback::take`]. An error when no copy
    /// is in flight or it does not arrive.
    pub(crate) fn wait(&mut self, ctx: &GpuContext) -> Result<Vec<u64>> {
        if self.state.load(std::sync::atomic::Ordering::Acquire) == MAPPING {
            ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
        }
        self.take()?
            .ok_or_else(|| Error::ReadbackData("no query results were in flight".into()))
    }
}
