//! WBOIT weight functions, mirrored in WGSL (`accumulate.wgsl`, `weight()`): the same
//! formulas, so that unit tests of these pin the shader's maths too (a GPU test checks the
//! shader against this file).
//!
//! Inputs: `z` is the standard window depth in [0, 1] (0 at the near plane: the seeds'
//! `gl_FragCoord.z`), `depth` the view-space distance (McGuire & Bavoil's |z|), `alpha`
//! the fragment's coverage, `range` the nearest and farthest view distance of the
//! translucent chunks in view (from their bounds; only the fitted weight uses it).

use crate::{Error, Result};

/// A weight function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum WeightFunction {
    /// Seed 000: `α · max(1e-2, 3e3 · (1 − 0.001·d)³)` clamped to [1e-2, 3e4], `d` the
    /// window depth clamped to [1e-5, 3e4]. With a window depth below 1 this is almost
    /// `3000·α`: close to a plain average.
    Seed000 = 0,
    /// Seed 002 (Voxelize): `clamp(α³ · 3000 · (1 − z)³, 0.01, 3000)`.
    Seed002 = 1,
    /// McGuire & Bavoil 2013 eq. 7: `α · clamp(10 / (1e-5 + (|z|/5)² + (|z|/200)⁶), 1e-2, 3e3)`.
    McGuire7 = 2,
    /// McGuire & Bavoil 2013 eq. 8: `α · clamp(10 / (1e-5 + (|z|/10)³ + (|z|/200)⁶), 1e-2, 3e3)`.
    McGuire8 = 3,
    /// McGuire & Bavoil 2013 eq. 9: `α · clamp(0.03 / (1e-5 + (|z|/200)⁴), 1e-2, 3e3)`.
    McGuire9 = 4,
    /// McGuire & Bavoil 2013 eq. 10: `α · max(1e-2, 3e3 · (1 − z)³)`.
    McGuire10 = 5,
    /// Ours, fitted to the translucent depth range in view `[n, f]` (from the boxes around
    /// the visible translucent meshes): `α² · 3e3 · exp(−K·t)` with `t = ln(d/n) / ln(f/n)`
    /// clamped to [0, 1] and `K = 9`. Eq. 7–10 fix the depths their weights fall over (a
    /// few blocks to 200, or the window depth, which a near plane of 0.1 squeezes into
    /// 1 − z < 0.01 beyond 10 blocks, where eq. 10 is flat); this one falls over the depths
    /// that hold translucent layers, in relative (log) depth so that near layers are as
    /// distinct as far ones. The α² favours dense layers, which hide what lies behind
    /// them whatever the order (seed 002's α³ idea, milder). K and the power of α were
    /// chosen by a sweep over the scene suite (`results/weight_sweep.md`).
    Fitted = 6,
}

/// The fitted weight's fall over the translucent depth range: `e^−9` (1/8100) from its
/// nearest to its farthest end.
pub const FITTED_K: f32 = 9.0;

impl WeightFunction {
    /// Every weight function.
    pub const ALL: [WeightFunction; 7] = [
        WeightFunction::Seed000,
        WeightFunction::Seed002,
        WeightFunction::McGuire7,
        WeightFunction::McGuire8,
        WeightFunction::McGuire9,
        WeightFunction::McGuire10,
        WeightFunction::Fitted,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            WeightFunction::Seed000 => "seed000",
            WeightFunction::Seed002 => "seed002",
            WeightFunction::McGuire7 => "eq7",
            WeightFunction::McGuire8 => "eq8",
            WeightFunction::McGuire9 => "eq9",
            WeightFunction::McGuire10 => "eq10",
            WeightFunction::Fitted => "fitted",
        }
    }

    /// Parses a command-line name; the error lists the known names.
    pub fn from_name(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|w| w.name() == name)
            .ok_or_else(|| {
                Error::UnknownName(format!(
                    "weight {name:?}; known: {}",
                    Self::ALL.map(WeightFunction::name).join(", ")
                ))
            })
    }

    /// The weight of a fragment (see the module docs for the inputs).
    pub fn weight(self, z: f32, depth: f32, alpha: f32, range: [f32; 2]) -> f32 {
        let cube = |x: f32| x * x * x;
        let d = depth.abs();
        match self {
            WeightFunction::Seed000 => {
                let d = z.clamp(1e-5, 3e4);
                (alpha * (3e3 * cube(1.0 - d * 0.001)).max(1e-2)).clamp(1e-2, 3e4)
            }
            WeightFunction::Seed002 => (cube(alpha) * 3000.0 * cube(1.0 - z)).clamp(0.01, 3000.0),
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
            WeightFunction::Fitted => {
                let n = range[0].max(1e-4);
                let f = range[1].max(n * 1.001);
                let t = ((d / n).ln() / (f / n).ln()).clamp(0.0, 1.0);
                alpha * alpha * 3e3 * (-FITTED_K * t).exp()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use WeightFunction::*;

    /// A range for the weights that ignore it.
    const R: [f32; 2] = [0.1, 100.0];

    fn close(a: f32, b: f32) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} != {b}");
    }

    // Each expected value is worked out by hand in the comment beside it.

    #[test]
    fn seed000() {
        // d = 0.5: (1 - 0.0005)³ = 0.998500749875; × 3000 = 2995.50225; × α 0.5 = 1497.75112
        close(Seed000.weight(0.5, 10.0, 0.5, R), 1_497.751_1);
        // α = 1e-6: 3000 × 1e-6 = 0.003, clamped up to 0.01
        close(Seed000.weight(0.5, 10.0, 1e-6, R), 0.01);
    }

    #[test]
    fn seed002() {
        // 0.5³ × 3000 × 0.5³ = 0.125 × 3000 × 0.125 = 46.875
        close(Seed002.weight(0.5, 1.0, 0.5, R), 46.875);
        // α 1 at the near plane: 3000, the upper clamp
        close(Seed002.weight(0.0, 1.0, 1.0, R), 3000.0);
        // 0.1³ × 3000 × 0.1³ = 0.003, clamped up to 0.01
        close(Seed002.weight(0.9, 1.0, 0.1, R), 0.01);
    }

    #[test]
    fn mcguire7() {
        // |z| 10: (10/5)² = 4, (10/200)⁶ = 1.5625e-8; 10 / 4.0000100156 = 2.49999374; × 0.5
        close(McGuire7.weight(0.5, 10.0, 0.5, R), 1.249_996_9);
        // |z| 0.1: 10 / (1e-5 + 4e-4) = 24390, clamped to 3000; × 0.5 = 1500
        close(McGuire7.weight(0.5, 0.1, 0.5, R), 1500.0);
    }

    #[test]
    fn mcguire8() {
        // |z| 10: (10/10)³ = 1; 10 / 1.0000100156 = 9.99989985; × 0.5 = 4.99995
        close(McGuire8.weight(0.5, 10.0, 0.5, R), 4.999_95);
        // |z| 2000: (200)³ = 8e6 and (10)⁶ = 1e6: 10 / 9e6 ≈ 1.1e-6, clamped to 0.01; × 1
        close(McGuire8.weight(0.5, 2000.0, 1.0, R), 0.01);
    }

    #[test]
    fn mcguire9() {
        // |z| 100: (0.5)⁴ = 0.0625; 0.03 / 0.06251 = 0.479923; × 0.5 = 0.239962
        close(McGuire9.weight(0.5, 100.0, 0.5, R), 0.239_962);
        // |z| 1000: 5⁴ = 625: 4.8e-5, clamped to 0.01; × 0.5 = 0.005
        close(McGuire9.weight(0.5, 1000.0, 0.5, R), 0.005);
    }

    #[test]
    fn mcguire10() {
        // z 0.5: 3000 × 0.125 = 375; × 0.5 = 187.5
        close(McGuire10.weight(0.5, 1.0, 0.5, R), 187.5);
        // z 1 (far plane): max(0.01, 0) = 0.01; × 0.5 = 0.005
        close(McGuire10.weight(1.0, 1.0, 0.5, R), 0.005);
    }

    #[test]
    fn fitted() {
        // Range [10, 1000], d 100: t = ln 10 / ln 100 = 0.5; e^(−4.5) = 0.011109;
        // α² 0.25 × 3000 × 0.011109 = 8.3318
        close(Fitted.weight(0.5, 100.0, 0.5, [10.0, 1000.0]), 8.331_8);
        // Near end of the range: 3000·α²; far end: 3000·α²·e^−9 = 0.37023·α²; beyond the
        // ends the weight stays at their values.
        close(Fitted.weight(0.5, 10.0, 1.0, [10.0, 1000.0]), 3000.0);
        close(Fitted.weight(0.5, 1.0, 1.0, [10.0, 1000.0]), 3000.0);
        close(Fitted.weight(0.5, 1000.0, 1.0, [10.0, 1000.0]), 0.370_23);
        close(Fitted.weight(0.5, 5000.0, 1.0, [10.0, 1000.0]), 0.370_23);
        // A degenerate range (one depth) stays finite.
        assert!(Fitted.weight(0.5, 10.0, 1.0, [10.0, 10.0]).is_finite());
    }

    #[test]
    fn names_round_trip() {
        for w in WeightFunction::ALL {
            assert_eq!(WeightFunction::from_name(w.name()).unwrap(), w);
        }
        assert!(
            WeightFunction::from_name("eq11")
                .unwrap_err()
                .to_string()
                .contains("eq10")
        );
    }
}
