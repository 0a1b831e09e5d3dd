//! Error of a picture against the exact reference: RMSE, PSNR, mean FLIP (NVIDIA's
//! perceptual difference, through the nv-flip crate), largest channel error, share of
//! pixels off by more than one level, and non-finite HDR pixels.

use serde::Serialize;
use voxel_render::Image;

/// How far a picture is from the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// Root mean square error over RGB, in [0, 1] units of the 8-bit output.
    pub rmse: f64,
    /// Peak signal-to-noise ratio, dB; 100 stands for identical pictures.
    pub psnr: f64,
    /// Mean FLIP error in [0, 1] (0: identical), at nv-flip's default pixels per degree.
    pub flip_mean: f64,
    /// Largest absolute difference of any channel, in 1/255 steps.
    pub max_abs_err: u32,
    /// Share of pixels whose largest channel difference exceeds 1/255.
    pub frac_bad_px: f64,
}

/// PSNR written for identical pictures (a finite stand-in for infinity, which JSON lacks).
pub const PSNR_IDENTICAL: f64 = 100.0;

fn rgb(img: &Image) -> Vec<u8> {
    img.rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// Compares `test` with `reference` (same size). Also returns the FLIP error map as a
/// magma-coloured heat map.
pub fn compare(reference: &Image, test: &Image) -> (Metrics, Image) {
    let plain = compare_without_flip(reference, test);
    let (w, h) = (reference.width, reference.height);
    let error_map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &rgb(reference)),
        nv_flip::FlipImageRgb8::with_data(w, h, &rgb(test)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let flip_mean = f64::from(nv_flip::FlipPool::from_image(&error_map).mean());
    let heat = error_map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let heat = Image {
        width: w,
        height: h,
        rgba: heat
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
    };
    (Metrics { flip_mean, ..plain }, heat)
}

/// [`compare`] without FLIP, the dearest part at large sizes (a few hundred milliseconds
/// of CPU at 1920×1080): `flip_mean` is NaN.
pub fn compare_without_flip(reference: &Image, test: &Image) -> Metrics {
    assert_eq!(
        (reference.width, reference.height),
        (test.width, test.height),
        "picture sizes differ"
    );
    let (w, h) = (reference.width, reference.height);
    let mut sq = 0.0f64;
    let mut max = 0u32;
    let mut bad = 0usize;
    for (p, q) in reference
        .rgba
        .chunks_exact(4)
        .zip(test.rgba.chunks_exact(4))
    {
        let mut m = 0u32;
        for c in 0..3 {
            let d = u32::from(p[c].abs_diff(q[c]));
            sq += f64::from(d * d);
            m = m.max(d);
        }
        max = max.max(m);
        bad += usize::from(m > 1);
    }
    let n = f64::from(w) * f64::from(h);
    let rmse = (sq / (3.0 * n)).sqrt() / 255.0;
    let psnr = if rmse == 0.0 {
        PSNR_IDENTICAL
    } else {
        (20.0 * (1.0 / rmse).log10()).min(PSNR_IDENTICAL)
    };
    Metrics {
        rmse,
        psnr,
        flip_mean: f64::NAN,
        max_abs_err: max,
        frac_bad_px: bad as f64 / n,
    }
}

/// Pixels of an HDR readback holding NaN or an infinity in any channel.
pub fn non_finite_pixels(hdr: &[[f32; 4]]) -> usize {
    hdr.iter()
        .filter(|p| p.iter().any(|c| !c.is_finite()))
        .count()
}

/// Mean over pixels and RGB of |a − b|, in 1/255 steps.
pub fn mean_abs_diff(a: &Image, b: &Image) -> f64 {
    let total: u64 = a
        .rgba
        .chunks_exact(4)
        .zip(b.rgba.chunks_exact(4))
        .map(|(p, q)| (0..3).map(|c| u64::from(p[c].abs_diff(q[c]))).sum::<u64>())
        .sum();
    total as f64 / (3.0 * f64::from(a.width) * f64::from(a.height))
}

/// How far beyond the reference's own change a pixel's channel must change between two
/// frames for the step to count toward a pop (of 255).
pub const POP_LEVEL: u8 = 32;
/// A step pops when more than this share of its pixels change by more than [`POP_LEVEL`]
/// beyond the reference (issue 54's target: a player sees it).
pub const POP_SHARE: f64 = 0.001;

/// One step of a camera path: how much more a technique's picture changed than the
/// reference's did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepExcess {
    /// Per pixel and channel, the change beyond the reference's (never below zero),
    /// averaged, in 1/255 steps.
    pub mean: f64,
    /// The share of pixels (0 to 1) with a channel more than [`POP_LEVEL`] beyond.
    pub over: f64,
}

impl StepExcess {
    /// Whether the step pops ([`POP_SHARE`]).
    pub fn pops(&self) -> bool {
        self.over > POP_SHARE
    }
}

/// Temporal flicker of a technique beyond the reference's own change between two frames
/// ([`StepExcess`]).
pub fn step_excess(prev: &Image, cur: &Image, ref_prev: &Image, ref_cur: &Image) -> StepExcess {
    let mut total = 0.0f64;
    let mut over = 0usize;
    for (((p, q), r), s) in prev
        .rgba
        .chunks_exact(4)
        .zip(cur.rgba.chunks_exact(4))
        .zip(ref_prev.rgba.chunks_exact(4))
        .zip(ref_cur.rgba.chunks_exact(4))
    {
        let mut most = 0.0f64;
        for c in 0..3 {
            let own = f64::from(p[c].abs_diff(q[c]));
            let truth = f64::from(r[c].abs_diff(s[c]));
            let excess = (own - truth).max(0.0);
            total += excess;
            most = most.max(excess);
        }
        over += usize::from(most > f64::from(POP_LEVEL));
    }
    let pixels = f64::from(cur.width) * f64::from(cur.height);
    StepExcess {
        mean: total / (3.0 * pixels),
        over: over as f64 / pixels,
    }
}

/// [`StepExcess::mean`] of [`step_excess`].
pub fn excess_change(prev: &Image, cur: &Image, ref_prev: &Image, ref_cur: &Image) -> f64 {
    step_excess(prev, cur, ref_prev, ref_cur).mean
}

/// `img` scaled down (box filter) to `width` pixels wide, or as it is if not wider.
pub fn thumbnail(img: &Image, width: Option<u32>) -> Image {
    let Some(w) = width.filter(|w| *w > 0 && *w < img.width) else {
        return img.clone();
    };
    let f = img.width.div_ceil(w);
    let (nw, nh) = (img.width / f, img.height / f);
    if nw == 0 || nh == 0 {
        // Too small to shrink by a whole factor (a picture wider than it is tall, shrunk
        // to a handful of pixels): kept as it is.
        return img.clone();
    }
    let mut rgba = Vec::with_capacity((nw * nh * 4) as usize);
    for y in 0..nh {
        for x in 0..nw {
            let mut acc = [0u32; 4];
            for dy in 0..f {
                for dx in 0..f {
                    let p = img.pixel(x * f + dx, y * f + dy);
                    for c in 0..4 {
                        acc[c] += u32::from(p[c]);
                    }
                }
            }
            rgba.extend(acc.map(|v| (v / (f * f)) as u8));
        }
    }
    Image {
        width: nw,
        height: nh,
        rgba,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> Image {
        Image {
            width: w,
            height: h,
            rgba: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .flat_map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    #[test]
    fn identical_pictures_have_no_error() {
        let a = img(16, 8, |x, y| [x as u8 * 10, y as u8 * 20, 7, 255]);
        let (m, heat) = compare(&a, &a);
        assert_eq!(m.rmse, 0.0);
        assert_eq!(m.psnr, PSNR_IDENTICAL);
        assert_eq!(m.max_abs_err, 0);
        assert_eq!(m.frac_bad_px, 0.0);
        assert!(m.flip_mean < 1e-6);
        assert_eq!((heat.width, heat.height), (16, 8));
    }

    #[test]
    fn worked_example() {
        // Half the pixels differ by 30 in red only: mean square = 0.5 * 900 / 3 = 150,
        // rmse = sqrt(150) / 255 = 0.04803, psnr = 20 log10(1 / 0.04803) = 26.37 dB.
        let a = img(8, 8, |_, _| [100, 100, 100, 255]);
        let b = img(8, 8, |x, _| {
            if x < 4 {
                [130, 100, 100, 255]
            } else {
                [100, 100, 100, 255]
            }
        });
        let (m, _) = compare(&a, &b);
        assert!((m.rmse - 0.048_03).abs() < 1e-4, "{m:?}");
        assert!((m.psnr - 26.37).abs() < 0.01, "{m:?}");
        assert_eq!(m.max_abs_err, 30);
        assert_eq!(m.frac_bad_px, 0.5);
        assert!(m.flip_mean > 0.01);
    }

    #[test]
    fn non_finite_and_flicker() {
        assert_eq!(
            non_finite_pixels(&[
                [0.0; 4],
                [f32::NAN, 0.0, 0.0, 1.0],
                [0.0, f32::INFINITY, 0.0, 0.0]
            ]),
            2
        );
        let a = img(2, 1, |_, _| [10, 10, 10, 255]);
        let b = img(2, 1, |x, _| {
            if x == 0 {
                [20, 10, 10, 255]
            } else {
                [10, 10, 10, 255]
            }
        });
        assert!((mean_abs_diff(&a, &b) - 10.0 / 6.0).abs() < 1e-12);
        // The technique changes where the reference did not: all of it is excess.
        assert!((excess_change(&a, &b, &a, &a) - 10.0 / 6.0).abs() < 1e-12);
        // The same change as the reference: none of it is.
        assert_eq!(excess_change(&a, &b, &a, &b), 0.0);
    }

    #[test]
    fn a_step_pops_when_a_thousandth_of_its_pixels_jump_beyond_the_reference() {
        // 2000 pixels, of which `n` jump by 40 in red where the reference stays.
        let still = img(2000, 1, |_, _| [10, 10, 10, 255]);
        let jump = |n: u32| {
            img(2000, 1, move |x, _| {
                if x < n {
                    [50, 10, 10, 255]
                } else {
                    [10, 10, 10, 255]
                }
            })
        };
        let two = step_excess(&still, &jump(2), &still, &still);
        assert_eq!(two.over, 0.001);
        assert!(!two.pops(), "0.1 % is not more than 0.1 %");
        assert!(step_excess(&still, &jump(3), &still, &still).pops());
        // The reference jumps too: no excess, no pop.
        let both = step_excess(&still, &jump(3), &still, &jump(3));
        assert_eq!((both.mean, both.over), (0.0, 0.0));
        // Below the level: excess, but no pop.
        let small = img(2000, 1, |_, _| [40, 10, 10, 255]);
        let s = step_excess(&still, &small, &still, &still);
        assert!(s.mean > 9.0 && s.over == 0.0, "{s:?}");
    }
}
