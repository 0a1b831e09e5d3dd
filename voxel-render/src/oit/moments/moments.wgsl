// Moment-based OIT, shared by both passes (appended to the constants made in Rust:
// ABSORBANCE_MAX). Münstermann, Krumpen, Klein & Peters 2018, with 4 power moments of
// log-warped depth; the reconstruction is the paper's Hamburger 4-moment bound.
//
// Pass 1 (additive blend):  b0 += a,  (b1, b2, b3, b4) += a · (z, z², z³, z⁴),
//                           a = −ln(1 − α), z the fragment's warped depth in [−1, 1].
// Pass 2 (additive blend):  accum += (C·α, α) · T(z),  T reconstructed from the moments.

// The technique's own uniform (`MboitParams` in mod.rs, checked equal by a test).
struct MboitParams {
    // ln of the nearest view depth of the warp range, and 1 / (ln far − ln near).
    ln_near: f32,
    inv_ln_range: f32,
    // How far the moments are pulled toward a well-conditioned vector (the paper's bias:
    // 5·10⁻⁷ for 32-bit moments, more for 16-bit ones).
    bias: f32,
    // The share of a fragment's own layer counted in front of it (the paper's 0.25).
    overestimation: f32,
};

@group(2) @binding(0) var<uniform> params: MboitParams;

// The paper's logarithmic depth warp: view depth to [−1, 1] across the frame's range of
// translucent depths (clamped outside it).
fn mboit_warp(view_depth: f32) -> f32 {
    let t = (log(max(view_depth, 1e-6)) - params.ln_near) * params.inv_ln_range;
    return clamp(t, 0.0, 1.0) * 2.0 - 1.0;
}

// Absorbance −ln(1 − α), at most ABSORBANCE_MAX (α = 1 would be infinite).
fn mboit_absorbance(alpha: f32) -> f32 {
    return -log(max(1.0 - alpha, exp(-ABSORBANCE_MAX)));
}

// Pass 1's outputs for a fragment of opacity `alpha` at `view_depth`: b0 (in every
// channel: the target has one) and the four weighted power moments.
struct MboitMoments {
    b0: vec4<f32>,
    moments: vec4<f32>,
};

fn mboit_moments(view_depth: f32, alpha: f32) -> MboitMoments {
    let a = mboit_absorbance(alpha);
    let z = mboit_warp(view_depth);
    let z2 = z * z;
    return MboitMoments(vec4<f32>(a), vec4<f32>(z, z2, z2 * z, z2 * z2) * a);
}

// The transmittance in front of warped depth `z` from the total absorbance `b0` and the
// sums `m` of the weighted moments: the paper's 4-power-moment reconstruction (Cholesky
// factorisation of the biased Hankel matrix, the two other support points from a
// quadratic, the lower bound of the absorbance in front blended with its own layer by
// the overestimation factor). `mboit_transmittance` in mod.rs is its Rust twin.
fn mboit_transmittance(b0: f32, m: vec4<f32>, z: f32) -> f32 {
    if b0 <= 0.0 {
        return 1.0;
    }
    let b = mix(m / b0, vec4<f32>(0.0, 0.375, 0.0, 0.375), params.bias);
    let l21d11 = fma(-b.x, b.y, b.z);
    let d11 = fma(-b.x, b.x, b.y);
    let inv_d11 = 1.0 / d11;
    let l21 = l21d11 * inv_d11;
    let d22 = fma(-l21d11, l21, fma(-b.y, b.y, b.w));
    // A scaled inverse image of (1, z, z²).
    var c = vec3<f32>(1.0, z, z * z);
    c.y -= b.x;
    c.z -= b.y + l21 * c.y;
    c.y *= inv_d11;
    c.z /= d22;
    c.y -= l21 * c.z;
    c.x -= dot(c.yz, b.xy);
    // Roots of c.x + c.y·t + c.z·t²: the two other points the distribution rests on.
    let p = c.y / c.z;
    let q = c.x / c.z;
    let r = sqrt(max(p * p * 0.25 - q, 0.0));
    let z1 = -p * 0.5 - r;
    let z2 = -p * 0.5 + r;
    // Weights: the fragment's own point counts `overestimation`, the others fully when in
    // front of it. Interpolating polynomial through them (Newton's divided differences),
    // integrated against the moments.
    let f0 = params.overestimation;
    let f1 = select(0.0, 1.0, z1 < z);
    let f2 = select(0.0, 1.0, z2 < z);
    let f01 = (f1 - f0) / (z1 - z);
    let f12 = (f2 - f1) / (z2 - z1);
    let f012 = (f12 - f01) / (z2 - z);
    var poly = vec3<f32>(0.0);
    poly.z = f012;
    poly.y = f01 - f012 * z1;
    poly.x = f0 - poly.y * z;
    poly.y = poly.y - poly.z * z;
    var absorbance = poly.x + dot(b.xy, poly.yz);
    if !mboit_finite(absorbance) {
        // A root on the fragment's own depth (moments too degenerate for the bias): count
        // its own share only, as for a single layer.
        absorbance = params.overestimation;
    }
    return exp(-b0 * clamp(absorbance, 0.0, 1.0));
}

// Whether x is finite, from its bits (WGSL may assume floats are finite, so comparisons
// with NaN are not reliable).
fn mboit_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}
