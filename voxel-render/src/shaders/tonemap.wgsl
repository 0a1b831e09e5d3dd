// HDR scene colour to the output format (appended to fullscreen.wgsl).
//
// Values up to SHOULDER pass unchanged (the lighting keeps surfaces there), brighter ones
// roll off smoothly towards 1 with slope 1 at the joint, so highlights never clip hard.
// Non-finite values (which no technique should produce) come out as magenta, so that they
// can be seen and tested for.

@group(0) @binding(0) var scene: texture_2d<f32>;

override SRGB_ENCODE: bool = false;

const SHOULDER: f32 = 0.8;

fn tonemap_channel(x: f32) -> f32 {
    if x <= SHOULDER {
        return max(x, 0.0);
    }
    let room = 1.0 - SHOULDER;
    return SHOULDER + room * (1.0 - exp(-(x - SHOULDER) / room));
}

fn srgb_encode(c: f32) -> f32 {
    if c <= 0.0031308 {
        return c * 12.92;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_tonemap(in: FullscreenOut) -> @location(0) vec4<f32> {
    let c = textureLoad(scene, vec2<i32>(in.clip.xy), 0);
    if any_not_finite(c) {
        return vec4<f32>(1.0, 0.0, 1.0, 1.0);
    }
    var rgb = vec3<f32>(tonemap_channel(c.r), tonemap_channel(c.g), tonemap_channel(c.b));
    if SRGB_ENCODE {
        rgb = vec3<f32>(srgb_encode(rgb.r), srgb_encode(rgb.g), srgb_encode(rgb.b));
    }
    return vec4<f32>(rgb, 1.0);
}
