//! WBOIT weight functions: where a reader finds them, and the CPU's copy (the lab and the
//! unit tests use it). What draws is the WGSL copy (`accumulate.wgsl`, `weight()`), the same
//! formulas; `tests/tests/render_wboit.rs`'s `shader_weights_match_the_rust_formulas` renders
//! every weight at three depths and fails when the two copies differ. Another weight: a
//! variant here (with its name), its branch in `weight()` of `accumulate.wgsl`
//! (the `WEIGHT_<NAME>` id constants are generated from this enum), and
//! `OitConfig.wboit.weight` picks it.
//!
//! Inputs: `z` is the standard window depth in [0, 1] (0 at the near plane: OpenGL's
//! `gl_FragCoord.z`, which the published weights use), `depth` the view-space distance (McGuire & Bavoil's |z|), `alpha`
//! the fragment's coverage; only the fitted weight uses the last two: `screen`, the
//! fragment's position on screen (0 to 1, y down), and `fit`, the frame's estimate of the
//! translucent layers in view ([`WeightFit`]).

pub(crate) use super::fit::MAX_FITTED_DEPTH;
pub(crate) use super::fit::WeightFit;
use crate::{Error, Result};

/// A weight function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum WeightFunction {
    /// `α · max(1e-2, 3e3 · (1 − 0.001·z)³)` clamped to [1e-2, 3e4], `z` the window depth
    /// clamped to [1e-5, 3e4] (McGuire & Bavoil's eq. 10 with the depth scaled by 1/1000).
    /// With window depths below 1 this is
    /// almost `3000·α`: nearly flat, a plain α-weighted average.
    Flat = 0,
    /// `clamp(α³ · 3000 · (1 − z)³, 0.01, 3000)` (the Voxelize engine's weight): α cubed,
    /// so that dense layers dominate, falling with the cube of the window depth.
    AlphaCubed = 1,
    /// McGuire & Bavoil 2013 eq. 7: `α · clamp(10 / (1e-5 + (|z|/5)² + (|z|/200)⁶), 1e-2, 3e3)`.
    McGuire7 = 2,
    /// McGuire & Bavoil 2013 eq. 8: `α · clamp(10 / (1e-5 + (|z|/10)³ + (|z|/200)⁶), 1e-2, 3e3)`.
    McGuire8 = 3,
    /// McGuire & Bavoil 2013 eq. 9: `α · clamp(0.03 / (1e-5 + (|z|/200)⁴), 1e-2, 3e3)`.
    McGuire9 = 4,
    /// McGuire & Bavoil 2013 eq. 10: `α · max(1e-2, 3e3 · (1 − z)³)`.
    McGuire10 = 5,
    /// Ours: `3000 · e^−τ`, where `τ` is the optical depth expected in front of the
    /// fragment, estimated each frame from the visible translucent meshes for the
    /// fragment's screen tile and interpolated in log depth (`super::fit`). The ideal
    /// weight of a layer is the transmittance in front of it (with it the weighted average
    /// is exact), so this weight falls where translucent layers are and stays flat where
    /// there are none: steep through a stack of dense sheets, flat between clear glass at
    /// the eye and water far away, which no fixed curve of depth can be. Eq. 7–10 fix the
    /// depths their weights fall over (a few blocks to 200, or the window depth, which a
    /// near plane of 0.1 squeezes into 1 − z < 0.01 beyond 10 blocks). The power of α and
    /// the tiles were chosen by runs over the scene suite (`results/weight_sweep.md`).
    Fitted = 6,
}

impl WeightFunction {
    /// Every weight function.
    pub const ALL: [WeightFunction; 7] = [
        WeightFunction::Flat,
        WeightFunction::AlphaCubed,
        WeightFunction::McGuire7,
        WeightFunction::McGuire8,
        WeightFunction::McGuire9,
        WeightFunction::McGuire10,
        WeightFunction::Fitted,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            WeightFunction::Flat => "flat",
            WeightFunction::AlphaCubed => "alpha-cubed",
            WeightFunction::McGuire7 => "eq7",
            WeightFunction::McGuire8 => "eq8",
            WeightFunction::McGuire9 => "eq9",
            WeightFunction::McGuire10 => "eq10",
            WeightFunction::Fitted => "fitted",
        }
    }

    /// The id the shader switches on (`WEIGHT_<NAME>` constants, generated from this).
    pub(crate) fn id(self) -> u32 {
        self as u32
    }

    /// WGSL constants `WEIGHT_FLAT`, `WEIGHT_ALPHA_CUBED`, ... holding each weight's id.
    pub(crate) fn wgsl_ids() -> crate::gpu::WgslConsts {
        Self::ALL
            .into_iter()
            .fold(crate::gpu::WgslConsts::default(), |c, w| {
                let name = format!("WEIGHT_{}", w.name().to_uppercase().replace('-', "_"));
                c.u32(&name, w.id())
            })
    }

    /// The weight of a fragment (see the module docs for the inputs).
    pub fn weight(self, z: f32, depth: f32, alpha: f32, screen: [f32; 2], fit: &WeightFit) -> f32 {
        let cube = |x: f32| x * x * x;
        let d = depth.abs();
        match self {
            WeightFunction::Flat => {
                let d = z.clamp(1e-5, 3e4);
                (alpha * (3e3 * cube(1.0 - d * 0.001)).max(1e-2)).clamp(1e-2, 3e4)
            }
            WeightFunction::AlphaCubed => {
                (cube(alpha) * 3000.0 * cube(1.0 - z)).clamp(0.01, 3000.0)
            }
            WeightFunction::McGuire7 => {
                alpha * (10.0 / (1e-5 + (d / 5.0).powi(2) + (d / 200.0).powi(6))).clamp(1e-2, 3e3)
            }
            WeightFunction::McGuire8 => {
                alpha * (10.0 / (1e-5 + (d / 10.0).powi(3) + (d / 200.0).powi(6))).clamp(1e-2, 3e3)
            }
            WeightFunction::McGuire9 => {
                alpha * (0.03 / (1e-5 + (d / 200.0).powi(4))).clamp(1e-2, 3e3)
            }
            WeightFunction::McGuire10 => alpha * (3e3 * cube(1.0 - z)).max(1e-2),
            WeightFunction::Fitted => 3e3 * (-fit.optical_depth_at(screen, d)).exp(),
        }
    }
}

/// Parses a command-line name (what `name` gives); the error lists the known names.
impl std::str::FromStr for WeightFunction {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        crate::error::parse_name("weight", name, &Self::ALL, Self::name)
    }
}

#[cfg(test)]
mod tests {
    use super::super::fit::{PROFILE_LEN, TILES};
    use super::*;
    use WeightFunction::*;

    /// A screen position and a fit for the weights that ignore them.
    const S: [f32; 2] = [0.5, 0.5];
    const R: &WeightFit = &WeightFit {
        range: [0.1, 100.0],
        optical_depth: Vec::new(),
        covered: [glam::Vec2::ZERO; 2],
    };

    fn close(a: f32, b: f32) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} != {b}");
    }

    // Each expected value is worked out by hand in the comment beside it.

    #[test]
    fn flat() {
        // d = 0.5: (1 - 0.0005)³ = 0.998500749875; × 3000 = 2995.50225; × α 0.5 = 1497.75112
        close(Flat.weight(0.5, 10.0, 0.5, S, R), 1_497.751_1);
        // α = 1e-6: 3000 × 1e-6 = 0.003, clamped up to 0.01
        close(Flat.weight(0.5, 10.0, 1e-6, S, R), 0.01);
    }

    #[test]
    fn alpha_cubed() {
        // 0.5³ × 3000 × 0.5³ = 0.125 × 3000 × 0.125 = 46.875
        close(AlphaCubed.weight(0.5, 1.0, 0.5, S, R), 46.875);
        // α 1 at the near plane: 3000, the upper clamp
        close(AlphaCubed.weight(0.0, 1.0, 1.0, S, R), 3000.0);
        // 0.1³ × 3000 × 0.1³ = 0.003, clamped up to 0.01
        close(AlphaCubed.weight(0.9, 1.0, 0.1, S, R), 0.01);
    }

    #[test]
    fn mcguire7() {
        // |z| 10: (10/5)² = 4, (10/200)⁶ = 1.5625e-8; 10 / 4.0000100156 = 2.49999374; × 0.5
        close(McGuire7.weight(0.5, 10.0, 0.5, S, R), 1.249_996_9);
        // |z| 0.1: 10 / (1e-5 + 4e-4) = 24390, clamped to 3000; × 0.5 = 1500
        close(McGuire7.weight(0.5, 0.1, 0.5, S, R), 1500.0);
    }

    #[test]
    fn mcguire8() {
        // |z| 10: (10/10)³ = 1; 10 / 1.0000100156 = 9.99989985; × 0.5 = 4.99995
        close(McGuire8.weight(0.5, 10.0, 0.5, S, R), 4.999_95);
        // |z| 2000: (200)³ = 8e6 and (10)⁶ = 1e6: 10 / 9e6 ≈ 1.1e-6, clamped to 0.01; × 1
        close(McGuire8.weight(0.5, 2000.0, 1.0, S, R), 0.01);
    }

    #[test]
    fn mcguire9() {
        // |z| 100: (0.5)⁴ = 0.0625; 0.03 / 0.06251 = 0.479923; × 0.5 = 0.239962
        close(McGuire9.weight(0.5, 100.0, 0.5, S, R), 0.239_962);
        // |z| 1000: 5⁴ = 625: 4.8e-5, clamped to 0.01; × 0.5 = 0.005
        close(McGuire9.weight(0.5, 1000.0, 0.5, S, R), 0.005);
    }

    #[test]
    fn mcguire10() {
        // z 0.5: 3000 × 0.125 = 375; × 0.5 = 187.5
        close(McGuire10.weight(0.5, 1.0, 0.5, S, R), 187.5);
        // z 1 (far plane): max(0.01, 0) = 0.01; × 0.5 = 0.005
        close(McGuire10.weight(1.0, 1.0, 0.5, S, R), 0.005);
    }

    /// A fit over [10, 1000] whose tile `(tx, ty)` has optical depth
    /// `(tx + 1) · 0.1 · k` at its k-th depth `10 · 100^(k/31)`.
    fn ramp_fit() -> WeightFit {
        let mut optical_depth = Vec::new();
        for _ty in 0..TILES {
            for tx in 0..TILES {
                optical_depth.extend((0..PROFILE_LEN).map(|k| (tx + 1) as f32 * 0.1 * k as f32));
            }
        }
        WeightFit {
            range: [10.0, 1000.0],
            optical_depth,
            covered: [glam::Vec2::ZERO; 2],
        }
    }

    #[test]
    fn fitted() {
        let fit = ramp_fit();
        // The centre of tile (1, 0) (x 1.5/8, y 0.5/8), d 100: halfway, x = 15.5:
        // τ = 0.2 × 15.5 = 3.1; 3000 × e^−3.1 = 3000 × 0.0450492 = 135.148
        close(
            Fitted.weight(0.5, 100.0, 0.5, [0.1875, 0.0625], &fit),
            135.147_6,
        );
        // The same depth near the corner of tile (0, 7), clamped to its centre:
        // τ = 0.1 × 15.5 = 1.55; 3000 × 0.212248 = 636.744
        close(
            Fitted.weight(0.5, 100.0, 0.5, [0.01, 0.99], &fit),
            636.744_3,
        );
        // Halfway between the centres of tiles 1 and 2 (x 2/8): τ = 0.25 × 15.5 = 3.875;
        // 3000 × e^−3.875 = 62.2630
        close(Fitted.weight(0.5, 100.0, 0.5, [0.25, 0.3], &fit), 62.263_0);
        // α does not enter (the accumulation multiplies by it once).
        close(
            Fitted.weight(0.5, 100.0, 1.0, [0.01, 0.99], &fit),
            636.744_3,
        );
        // The near end: τ 0, 3000; nearer stays there.
        close(
            Fitted.weight(0.5, 10.0, 1.0, [0.1875, 0.0625], &fit),
            3000.0,
        );
        close(Fitted.weight(0.5, 1.0, 1.0, [0.1875, 0.0625], &fit), 3000.0);
        // The far end of tile (1, 0): τ 6.2: 3000 × e^−6.2 = 6.08829; beyond stays there.
        close(
            Fitted.weight(0.5, 1000.0, 1.0, [0.1875, 0.0625], &fit),
            6.088_29,
        );
        close(
            Fitted.weight(0.5, 5000.0, 1.0, [0.1875, 0.0625], &fit),
            6.088_29,
        );
        // Off-screen positions take the edge tiles: x 1.0 is tile 7, τ 0.8 × 31 = 24.8,
        // cut at MAX_FITTED_DEPTH: 3000 × e^−12 = 0.018433.
        close(Fitted.weight(0.5, 1000.0, 1.0, [1.0, 0.5], &fit), 0.018_433);
        // No table (no translucent mesh in view): flat.
        close(Fitted.weight(0.5, 100.0, 0.5, S, R), 3000.0);
        // A degenerate range (one depth) stays finite.
        let flat = WeightFit {
            range: [10.0, 10.0],
            ..fit
        };
        assert!(Fitted.weight(0.5, 10.0, 1.0, S, &flat).is_finite());
    }

    #[test]
    fn names_round_trip() {
        for w in WeightFunction::ALL {
            assert_eq!(w.name().parse::<WeightFunction>().unwrap(), w);
        }
        assert!(
            "eq11"
                .parse::<WeightFunction>()
                .unwrap_err()
                .to_string()
                .contains("eq10")
        );
    }
}
