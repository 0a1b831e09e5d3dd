//! The lab's documented caps on what a run may ask for (a typo must not run for
//! ever or take the machine's memory). Each is checked before anything is rendered or
//! written: by the command line's parsers, by scene parsing, and by
//! `EvalOptions::validate`, which `evaluate` runs first.

use crate::{Error, Result};

/// Widest and tallest picture, in pixels: twice a 4K display's width.
pub const MAX_SIDE: u32 = 8192;
/// Most pixels in a picture: an 8K UHD display (7680 × 4320), 33.2 M. The exact
/// reference's fragment pool and the lab's per-pixel metrics grow with it; at 16384² the
/// HDR readback alone (2 GiB) passes lavapipe's largest buffer.
pub const MAX_PIXELS: u64 = 7680 * 4320;
/// Most timed frames per picture (`--frames` of `eval` and `render`): a median of 1000
/// frames is as steady as it gets; more only takes longer.
pub const MAX_FRAMES: u32 = 1000;
/// Most untimed frames before timing (`eval --warmup`): pipelines and adaptive peeling
/// settle within a few.
pub const MAX_WARMUP: u32 = 100;
/// Most frames of a flicker camera path (`eval --flicker-frames`): the reference's
/// pictures of the path are kept for comparison, 0.5 MB each at the sweeps' 480 × 270.
pub const MAX_FLICKER_FRAMES: u32 = 240;
/// Most points per stability sweep (`eval --sweep-points`): the longest sweep list.
pub const MAX_SWEEP_POINTS: u32 = 9;
/// Fewest points per stability sweep: its two ends.
pub const MIN_SWEEP_POINTS: u32 = 2;
/// Narrowest heat map saved (`eval --heatmap-width`): a picture is shrunk by a whole
/// factor to at most this width, so narrower would leave rows of no pixel at all.
pub const MIN_HEATMAP_WIDTH: u32 = 16;
/// Largest scene file read, in bytes (the suite's largest is under 8 KiB): a path to
/// `/dev/zero` or a huge file is an error after this many bytes, not a read until memory
/// runs out.
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 20;

/// Checks a picture size against [`MAX_SIDE`] and [`MAX_PIXELS`]; the error names `what`
/// (a flag or a field) and the limits.
pub fn check_size(what: &str, (w, h): (u32, u32)) -> Result<()> {
    let sides = (1..=MAX_SIDE).contains(&w) && (1..=MAX_SIDE).contains(&h);
    if !sides || u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(Error::Size {
            what: what.to_owned(),
            size: (w, h),
            max_side: MAX_SIDE,
            max_pixels: MAX_PIXELS,
        });
    }
    Ok(())
}

/// Checks that `value` of `what` lies in `min..=max`.
pub fn check_range(what: &str, value: u64, min: u64, max: u64) -> Result<()> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            what: what.to_owned(),
            value,
            min,
            max,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_within_the_caps_pass_and_others_name_the_limit() {
        for ok in [(1, 1), (640, 360), (7680, 4320), (8192, 4050), (4320, 7680)] {
            check_size("--size", ok).unwrap();
        }
        for (bad, word) in [
            ((16384, 16384), "8192"),
            ((0, 10), "from 1"),
            ((8192, 8192), "33177600"),
            ((8193, 1), "8192"),
        ] {
            let e = check_size("--size", bad).unwrap_err().to_string();
            assert!(e.contains("--size") && e.contains(word), "{bad:?}: {e}");
        }
        assert!(check_range("--frames", 0, 1, 1000).is_err());
        assert!(check_range("--frames", 1000, 1, 1000).is_ok());
        assert!(
            check_range("--warmup", u64::from(u32::MAX), 0, 100)
                .unwrap_err()
                .to_string()
                .contains("4294967295")
        );
    }
}
