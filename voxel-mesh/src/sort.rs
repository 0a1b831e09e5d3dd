//! Back-to-front ordering for blended transparency (the painter's order of sorted alpha blending, for chunks and quads).
//!
//! Keys are squared distances from the eye, compared through their IEEE bit patterns (which
//! order non-negative floats correctly), so a NaN eye cannot make the sort panic: NaN keys
//! simply sort as farthest.

use std::cmp::Reverse;

use crate::PackedQuad;

fn key(p: [f32; 3], eye: [f32; 3]) -> Reverse<u32> {
    let d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    // d2 >= 0 or NaN; -0.0 cannot occur from a sum of squares.
    Reverse(d2.to_bits())
}

/// Sorts `items` farthest first by the distance from `eye` to `position(item)`. Items at
/// equal distance keep their relative order.
pub fn back_to_front<T>(items: &mut [T], eye: [f32; 3], position: impl Fn(&T) -> [f32; 3]) {
    items.sort_by_cached_key(|item| key(position(item), eye));
}

/// Sorts a chunk's translucent quads farthest first. `eye_local` is the eye in the chunk's
/// local block coordinates (eye minus chunk origin), so precision does not depend on how far
/// the chunk is from the world origin.
pub fn quads_back_to_front(quads: &mut [PackedQuad], eye_local: [f32; 3]) {
    back_to_front(quads, eye_local, |q| q.center());
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::{BlockId, Face};

    #[test]
    fn positions_come_out_far_to_near() {
        let mut v = [[1.0, 0.0, 0.0], [10.0, 0.0, 0.0], [5.0, 0.0, 0.0]];
        back_to_front(&mut v, [0.0; 3], |p| *p);
        assert_eq!(v, [[10.0, 0.0, 0.0], [5.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    }

    #[test]
    fn equal_distances_do_not_crash_and_keep_order() {
        let mut v = [
            (0, [1.0, 0.0, 0.0]),
            (1, [0.0, 1.0, 0.0]),
            (2, [0.0, 0.0, -1.0]),
        ];
        back_to_front(&mut v, [0.0; 3], |p| p.1);
        assert_eq!(v.map(|p| p.0), [0, 1, 2]);
    }

    #[test]
    fn nan_and_infinite_eyes_do_not_crash() {
        let mut v = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [0.0; 3]];
        back_to_front(&mut v, [f32::NAN, 0.0, 0.0], |p| *p);
        back_to_front(&mut v, [f32::INFINITY, 0.0, 0.0], |p| *p);
    }

    #[test]
    fn quads_sort_by_their_centres() {
        let near = PackedQuad::new([0, 0, 0], 1, 1, Face::PosZ, BlockId(7));
        let mid = PackedQuad::new([0, 0, 10], 1, 1, Face::PosZ, BlockId(7));
        let far = PackedQuad::new([0, 0, 20], 4, 4, Face::NegZ, BlockId(8));
        let mut q = [mid, near, far];
        quads_back_to_front(&mut q, [0.5, 0.5, -3.0]);
        assert_eq!(q, [far, mid, near]);
    }
}
