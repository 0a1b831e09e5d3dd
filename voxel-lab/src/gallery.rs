//! One scene under every technique: each picture with its FLIP error map against the exact
//! reference (the A-buffer), side by side in one labelled sheet (`demo gallery`).

use crate::{Error, Result};

use std::path::Path;

use plotters::prelude::*;
use voxel_render::{GpuContext, Image, Technique};

use crate::eval::{default_weight, oit_config};
use crate::headless::{Offscreen, render_image, renderer_for};
use crate::metrics::{self, Metrics};
use crate::scene::Scene;

/// One technique's picture and its error against the reference.
#[derive(Debug)]
pub struct Entry {
    /// The technique.
    pub technique: Technique,
    /// Its picture.
    pub image: Image,
    /// The FLIP error map against the reference (magma: black is no error).
    pub error_map: Image,
    /// Its error.
    pub metrics: Metrics,
}

/// Renders `scene`'s first camera at `size` with the reference and every technique
/// (default settings; two frames each, so that adaptive peeling settles), and compares
/// each with the reference.
pub fn render(ctx: &GpuContext, scene: &Scene, size: (u32, u32)) -> Result<Vec<Entry>> {
    let config = voxel_render::RendererConfig {
        width: size.0,
        height: size.1,
        ..voxel_render::RendererConfig::default()
    };
    let mut renderer = renderer_for(ctx, scene, config)?;
    let target = Offscreen::new(ctx, size.0, size.1);
    let camera = &scene.cameras[0];
    let mut draw = |t: Technique| -> Result<Image> {
        renderer.set_oit_config(oit_config(t, default_weight()))?;
        render_image(ctx, &mut renderer, &target, camera)?;
        render_image(ctx, &mut renderer, &target, camera)
    };
    let reference = draw(Technique::Reference)?;
    Technique::ALL
        .iter()
        .map(|&t| {
            let image = draw(t)?;
            let (metrics, error_map) = metrics::compare(&reference, &image);
            Ok(Entry {
                technique: t,
                image,
                error_map,
                metrics,
            })
        })
        .collect()
}

/// Writes `<technique>.png` and `<technique>_flip.png` per entry into `out`, and
/// `gallery.png`: a sheet of `columns` tiles, each the picture over its error map under a
/// line naming the technique, its mean FLIP and its largest channel error.
pub fn write(out: &Path, entries: &[Entry], columns: usize) -> Result<()> {
    std::fs::create_dir_all(out).map_err(Error::io(out))?;
    for e in entries {
        let name = e.technique.name();
        e.image.save_png(&out.join(format!("{name}.png")))?;
        e.error_map
            .save_png(&out.join(format!("{name}_flip.png")))?;
    }
    let Some(first) = entries.first() else {
        return Ok(());
    };
    let (w, h) = (first.image.width, first.image.height);
    let label = 26u32;
    let (tile_w, tile_h) = (w + 8, label + 2 * h + 12);
    let columns = columns.clamp(1, entries.len());
    let rows = entries.len().div_ceil(columns);
    let (sheet_w, sheet_h) = (tile_w * columns as u32, tile_h * rows as u32);
    let mut rgb = vec![24u8; (sheet_w * sheet_h * 3) as usize];
    let mut blit = |img: &Image, x0: u32, y0: u32| {
        for y in 0..img.height.min(h) {
            for x in 0..img.width.min(w) {
                let p = img.pixel(x, y);
                let i = (((y0 + y) * sheet_w + x0 + x) * 3) as usize;
                rgb[i..i + 3].copy_from_slice(&p[..3]);
            }
        }
    };
    for (k, e) in entries.iter().enumerate() {
        let (x0, y0) = (
            (k % columns) as u32 * tile_w + 4,
            (k / columns) as u32 * tile_h + label,
        );
        blit(&e.image, x0, y0);
        blit(&e.error_map, x0, y0 + h + 4);
    }
    crate::charts::fonts();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (sheet_w, sheet_h)).into_drawing_area();
        let style = ("sans-serif", 17).into_font().color(&WHITE);
        for (k, e) in entries.iter().enumerate() {
            let (x0, y0) = (
                (k % columns) as u32 * tile_w + 6,
                (k / columns) as u32 * tile_h + 4,
            );
            let text = format!(
                "{}   FLIP {:.4}   max {}/255",
                e.technique.name(),
                e.metrics.flip_mean,
                e.metrics.max_abs_err
            );
            root.draw(&Text::new(text, (x0 as i32, y0 as i32), style.clone()))
                .map_err(|e| Error::Chart {
                    what: "gallery",
                    detail: format!("{e:?}"),
                })?;
        }
        root.present().map_err(|e| Error::Chart {
            what: "gallery",
            detail: format!("{e:?}"),
        })?;
    }
    let rgba = rgb
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    Image {
        width: sheet_w,
        height: sheet_h,
        rgba,
    }
    .save_png(&out.join("gallery.png"))
    .map_err(Error::Render)
}
