// Weighted blended OIT, composite (appended to fullscreen.wgsl).
//
// Output (avg, 1 − revealage), blended SRC_ALPHA, ONE_MINUS_SRC_ALPHA over the opaque image:
//   result = avg · (1 − Π(1 − α)) + opaque · Π(1 − α),  avg = Σ(C·α·w) / Σ(α·w).

@group(0) @binding(0) var accumulation: texture_2d<f32>;
@group(0) @binding(1) var revealage: texture_2d<f32>;

const FP16_MAX: f32 = 65504.0;

@fragment
fn fs_composite(in: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(in.clip.xy);
    let reveal = textureLoad(revealage, p, 0).r;
    if reveal >= 1.0 {
        // No translucent fragment here: leave the opaque image exactly as it is.
        discard;
    }
    let accum = textureLoad(accumulation, p, 0);
    var avg = accum.rgb / max(accum.a, 1e-5);
    if any_not_finite(accum) || accum.a >= FP16_MAX || any_not_finite(vec4<f32>(avg, 0.0)) {
        // The sums overflowed (only possible without the fp16 headroom scale, or with
        // thousands of layers): inf on most GPUs, saturated at 65504 on some (lavapipe).
        // The average colour is lost. Keep coverage right and show the layers as black
        // rather than write inf, NaN or a made-up colour into the scene.
        avg = vec3<f32>(0.0);
    }
    return vec4<f32>(avg, 1.0 - reveal);
}
