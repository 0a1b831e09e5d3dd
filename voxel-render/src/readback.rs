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
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| Error::Io(format!("{}: {e}", dir.display())))?;
        }
        let file = std::fs::File::create(path)
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut w = enc
            .write_header()
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
        w.write_image_data(&self.rgba)
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))
    }

    /// Reads an RGBA or RGB 8-bit PNG.
    pub fn load_png(path: &Path) -> Result<Self> {
        let err = |e: &dyn std::fmt::Display| Error::Io(format!("{}: {e}", path.display()));
        let file = std::fs::File::open(path).map_err(|e| err(&e))?;
        let mut dec = png::Decoder::new(std::io::BufReader::new(file));
        dec.set_transformations(png::Transformations::EXPAND);
        let mut reader = dec.read_info().map_err(|e| err(&e))?;
        let mut buf = vec![
            0;
            reader
                .output_buffer_size()
                .ok_or_else(|| err(&"image too large"))?
        ];
        let info = reader.next_frame(&mut buf).map_err(|e| err(&e))?;
        let rgba = match info.color_type {
            png::ColorType::Rgba => buf[..info.buffer_size()].to_vec(),
            png::ColorType::Rgb => buf[..info.buffer_size()]
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            other => return Err(err(&format!("unsupported PNG colour type {other:?}"))),
        };
        Ok(Self {
            width: info.width,
            height: info.height,
            rgba,
        })
    }
}

/// Copies a whole single-sample 2D texture to the CPU, row padding removed. Blocks until
/// the GPU is done. Returns `width * height * bytes_per_texel` bytes.
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>> {
    let (w, h) = (texture.width(), texture.height());
    let row = w * bytes_per_texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded) * u64::from(h),
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
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_read(ctx, &buffer)?;
    let mut out = Vec::with_capacity((row * h) as usize);
    for r in 0..h as usize {
        let start = r * padded as usize;
        out.extend_from_slice(&bytes[start..start + row as usize]);
    }
    Ok(out)
}

/// Maps a `MAP_READ` buffer, waits, and copies its contents out.
pub fn map_read(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("waiting for the GPU: {e}")))?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("readback: {e}")))?
        .map_err(|e| Error::Gpu(format!("readback: {e}")))?;
    let data = buffer
        .slice(..)
        .get_mapped_range()
        .map_err(|e| Error::Gpu(format!("readback: {e}")))?
        .to_vec();
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
}
