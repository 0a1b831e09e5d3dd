//! Ordered-dithering matrices (Bayer 1973) and the stipple technique's packed 32-bit
//! shading state (alpha, transparency mode, pattern: a per-draw word in the style of
//! retro hardware).

use crate::{Error, Result};

/// Side of the Bayer matrix a stipple pattern repeats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BayerSize {
    /// 2×2: 4 levels, "extremely chunky".
    B2 = 2,
    /// 4×4: 16 levels, the default: the classic console stipple.
    B4 = 4,
    /// 8×8: 64 levels.
    B8 = 8,
    /// 16×16: 256 levels.
    B16 = 16,
}

impl BayerSize {
    /// All sizes, smallest first.
    pub const ALL: [BayerSize; 4] = [BayerSize::B2, BayerSize::B4, BayerSize::B8, BayerSize::B16];

    /// The side in pixels.
    pub fn side(self) -> u32 {
        self as u32
    }

    /// The state's 2-bit pattern code: 0 = 2×2, 1 = 4×4, 2 = 8×8, 3 = 16×16.
    pub(crate) fn code(self) -> u32 {
        self.side().trailing_zeros() - 1
    }

    #[cfg(test)]
    /// The size with pattern code `code` (its low two bits).
    pub(crate) fn from_code(code: u32) -> Self {
        Self::ALL[(code & 3) as usize]
    }

    /// Parses 2, 4, 8 or 16.
    pub fn from_side(side: u32) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|b| b.side() == side)
            .ok_or_else(|| {
                Error::unknown_name("Bayer size", &side.to_string(), ["2", "4", "8", "16"])
            })
    }
}

/// The `n`×`n` Bayer matrix (`n` a power of two, at least 1), row-major: entry `y * n + x`
/// holds a level in `0..n²`. Built recursively: `M₂ₙ = [[4Mₙ, 4Mₙ + 2], [4Mₙ + 3, 4Mₙ + 1]]`.
pub fn bayer(n: usize) -> Vec<u32> {
    assert!(n.is_power_of_two(), "Bayer size {n} is not a power of two");
    if n == 1 {
        return vec![0];
    }
    let h = n / 2;
    let m = bayer(h);
    let mut out = vec![0; n * n];
    for y in 0..n {
        for x in 0..n {
            let quadrant = [[0, 2], [3, 1]][y / h][x / h];
            out[y * n + x] = 4 * m[(y % h) * h + x % h] + quadrant;
        }
    }
    out
}

/// The four matrices one after the other (2×2, 4×4, 8×8, 16×16: 340 levels), as the
/// shaders read them from a storage buffer: the GPU uses exactly the tested tables. (As
/// WGSL `const` arrays indexed at run time, lavapipe copies all of them into every
/// fragment's private memory, which made the opaque pass five times slower.)
pub(crate) fn bayer_levels() -> Vec<u32> {
    BayerSize::ALL
        .iter()
        .flat_map(|b| bayer(b.side() as usize))
        .collect()
}

/// Where the matrix of `size` starts in [`bayer_levels`].
pub(crate) fn bayer_offset(size: BayerSize) -> usize {
    BayerSize::ALL
        .iter()
        .take_while(|b| **b != size)
        .map(|b| (b.side() * b.side()) as usize)
        .sum()
}

/// The mode code for stipple in bits 8–9 of the shading state. (The other modes,
/// 0 opaque and 2 alpha test, are what the opaque and cutout passes do; the stipple
/// technique always sends this one.)
pub(crate) const STIPPLE_MODE: u32 = 1;

/// The 32-bit shading state: bits 0–7 uniform alpha (0–255), bits 8–9 transparency
/// mode (always `STIPPLE_MODE` here), bits 10–11 dither pattern; bits 12–31 are left zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct ShadingState {
    /// Whole-draw opacity, 255 = 1.0.
    pub alpha: u8,
    /// Which Bayer matrix.
    pub pattern: BayerSize,
}

impl ShadingState {
    /// Packs into the 32-bit layout.
    pub(crate) fn pack(self) -> u32 {
        u32::from(self.alpha) | STIPPLE_MODE << 8 | self.pattern.code() << 10
    }

    #[cfg(test)]
    /// Unpacks the 32-bit layout (the mode and bits 12–31 are ignored).
    pub(crate) fn unpack(packed: u32) -> Self {
        Self {
            alpha: (packed & 0xff) as u8,
            pattern: BayerSize::from_code(packed >> 10),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // The Bayer matrices as commonly printed (numerators over n²).
    const PRINTED_2: [u32; 4] = [0, 2, 3, 1];
    const PRINTED_4: [u32; 16] = [0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5];
    const PRINTED_8: [u32; 64] = [
        0, 32, 8, 40, 2, 34, 10, 42, 48, 16, 56, 24, 50, 18, 58, 26, 12, 44, 4, 36, 14, 46, 6, 38,
        60, 28, 52, 20, 62, 30, 54, 22, 3, 35, 11, 43, 1, 33, 9, 41, 51, 19, 59, 27, 49, 17, 57,
        25, 15, 47, 7, 39, 13, 45, 5, 37, 63, 31, 55, 23, 61, 29, 53, 21,
    ];
    const PRINTED_16: [u32; 256] = [
        0, 128, 32, 160, 8, 136, 40, 168, 2, 130, 34, 162, 10, 138, 42, 170, //
        192, 64, 224, 96, 200, 72, 232, 104, 194, 66, 226, 98, 202, 74, 234, 106, //
        48, 176, 16, 144, 56, 184, 24, 152, 50, 178, 18, 146, 58, 186, 26, 154, //
        240, 112, 208, 80, 248, 120, 216, 88, 242, 114, 210, 82, 250, 122, 218, 90, //
        12, 140, 44, 172, 4, 132, 36, 164, 14, 142, 46, 174, 6, 134, 38, 166, //
        204, 76, 236, 108, 196, 68, 228, 100, 206, 78, 238, 110, 198, 70, 230, 102, //
        60, 188, 28, 156, 52, 180, 20, 148, 62, 190, 30, 158, 54, 182, 22, 150, //
        252, 124, 220, 92, 244, 116, 212, 84, 254, 126, 222, 94, 246, 118, 214, 86, //
        3, 131, 35, 163, 11, 139, 43, 171, 1, 129, 33, 161, 9, 137, 41, 169, //
        195, 67, 227, 99, 203, 75, 235, 107, 193, 65, 225, 97, 201, 73, 233, 105, //
        51, 179, 19, 147, 59, 187, 27, 155, 49, 177, 17, 145, 57, 185, 25, 153, //
        243, 115, 211, 83, 251, 123, 219, 91, 241, 113, 209, 81, 249, 121, 217, 89, //
        15, 143, 47, 175, 7, 135, 39, 167, 13, 141, 45, 173, 5, 133, 37, 165, //
        207, 79, 239, 111, 199, 71, 231, 103, 205, 77, 237, 109, 197, 69, 229, 101, //
        63, 191, 31, 159, 55, 183, 23, 151, 61, 189, 29, 157, 53, 181, 21, 149, //
        255, 127, 223, 95, 247, 119, 215, 87, 253, 125, 221, 93, 245, 117, 213, 85, //
    ];

    #[test]
    fn recursive_matrices_equal_the_printed_tables() {
        assert_eq!(bayer(2), PRINTED_2);
        assert_eq!(bayer(4), PRINTED_4);
        assert_eq!(bayer(8), PRINTED_8);
        assert_eq!(bayer(16), PRINTED_16);
    }

    #[test]
    fn every_level_appears_once() {
        for n in [2, 4, 8, 16] {
            let mut v = bayer(n);
            v.sort_unstable();
            assert_eq!(v, (0..(n * n) as u32).collect::<Vec<_>>());
        }
    }

    #[test]
    fn the_gpu_buffer_holds_the_four_tables() {
        let levels = bayer_levels();
        assert_eq!(levels.len(), 4 + 16 + 64 + 256);
        for b in BayerSize::ALL {
            let n = (b.side() * b.side()) as usize;
            let o = bayer_offset(b);
            assert_eq!(levels[o..o + n], bayer(b.side() as usize)[..]);
        }
        assert_eq!(BayerSize::ALL.map(bayer_offset), [0, 4, 20, 84]);
    }

    #[test]
    fn shading_state_bit_layout() {
        let s = ShadingState {
            alpha: 0xab,
            pattern: BayerSize::B8,
        };
        assert_eq!(s.pack(), 0xab | 1 << 8 | 2 << 10);
        assert_eq!(ShadingState::unpack(s.pack()), s);
        // Bits 12-31 carry other parameters and do not disturb ours.
        assert_eq!(ShadingState::unpack(s.pack() | 0xffff_f000), s);
    }

    #[test]
    fn shading_state_round_trips_every_combination() {
        for alpha in [0u8, 1, 127, 255] {
            for pattern in BayerSize::ALL {
                let s = ShadingState { alpha, pattern };
                assert_eq!(ShadingState::unpack(s.pack()), s);
                assert_eq!(s.pack() >> 12, 0);
                assert_eq!((s.pack() >> 8) & 3, STIPPLE_MODE);
            }
        }
    }

    #[test]
    fn pattern_codes_follow_the_layout() {
        assert_eq!(BayerSize::ALL.map(BayerSize::code), [0, 1, 2, 3]);
        assert_eq!(BayerSize::from_side(8).unwrap(), BayerSize::B8);
        assert!(BayerSize::from_side(3).is_err());
    }
}
