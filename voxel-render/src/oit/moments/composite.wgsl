// Moment-based OIT, composite (appended to fullscreen.wgsl).
//
// Output (avg, 1 − e^(−b0)), blended SRC_ALPHA, ONE_MINUS_SRC_ALPHA over the opaque image:
//   result = avg · (1 − e^(−b0)) + opaque · e^(−b0),  avg = Σ(C·α·T) / Σ(α·T).
// The total transmittance e^(−b0) is exact (up to the absorbance cap); only the weights
// of the average are approximate.

@group(0) @binding(0) var accumulation: texture_2d<f32>;
@group(0) @binding(1) var b0_target: texture_2d<f32>;

@fragment
fn fs_composite(in: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(in.clip.xy);
    let b0 = textureLoad(b0_target, p, 0).r;
    if !(b0 > 0.0) {
        // No translucent fragment here: leave the opaque image exactly as it is.
        discard;
    }
    let accum = textureLoad(accumulation, p, 0);
    var avg = accum.rgb / max(accum.a, 1e-10);
    if any_not_finite(accum) || any_not_finite(vec4<f32>(avg, b0)) {
        // Overflowed sums (thousands of layers in 16 bits): the colour is lost; keep
        // coverage and show black rather than write inf or NaN into the scene.
        avg = vec3<f32>(0.0);
    }
    return vec4<f32>(avg, 1.0 - exp(-b0));
}
