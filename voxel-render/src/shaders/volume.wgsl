// Volumes (`medium.rs` has the model): what the techniques and the exact references share.
// Needs in scope: `frame` (Frame) and FLAG_INTERFACE.

// A fragment's part in the medium a ray is in, as the exact references keep it: bits 0..16
// the block (OBJECT_BLOCK for a game's object), INFO_FRONT for a front face,
// INFO_INTERFACE for a face toward another translucent type.
const INFO_FRONT: u32 = 0x10000u;
const INFO_INTERFACE: u32 = 0x20000u;
const OBJECT_BLOCK: u32 = 0xffffu;

fn fragment_info(block: u32, front: bool, flags: u32) -> u32 {
    return (block & 0xffffu) | select(0u, INFO_FRONT, front)
        | select(0u, INFO_INTERFACE, (flags & FLAG_INTERFACE) != 0u);
}

// A window depth that stands for the eye itself (view depth 0): a path from the eye starts
// there. Every drawn depth is at most 1 (the near plane).
const EYE_Z: f32 = 2.0;

// View depth of reverse-Z window depth `z` (the far plane where nothing was drawn; 0 at
// EYE_Z).
fn view_depth_of(z: f32) -> f32 {
    if z >= EYE_Z {
        return 0.0;
    }
    return frame.near * frame.far / (z * (frame.far - frame.near) + frame.near);
}

// The length along pixel `xy`'s ray between window depths `near_z` and `far_z`.
fn ray_length(xy: vec2<f32>, near_z: f32, far_z: f32) -> f32 {
    let ndc = vec2<f32>(xy.x / frame.viewport.x * 2.0 - 1.0, 1.0 - xy.y / frame.viewport.y * 2.0);
    let scale = length(vec3<f32>(ndc * frame.tan_half, 1.0));
    return max(view_depth_of(far_z) - view_depth_of(near_z), 0.0) * scale;
}

// `d` blocks of a medium of look `m`, premultiplied: what lies behind keeps exp(−σ d) of
// its light and the medium's colour, lit like a face turned to the sky, takes the rest.
fn medium_segment(m: vec4<f32>, d: f32) -> vec4<f32> {
    if m.a <= 0.0 || d <= 0.0 {
        return vec4<f32>(0.0);
    }
    let light = frame_sky_light(frame);
    let t = exp(-m.a * d);
    return vec4<f32>(m.rgb * light * (1.0 - t), 1.0 - t);
}

// The medium a ray is in after a fragment of `info` and look `look`, from `current` (a
// look; absorption 0: none). The entry face of a volume (a front face) enters it; its
// faces toward air or cutout blocks seen from behind leave it; a face toward another
// translucent type leaves it at that type's entry face, which lies in the same plane (so
// a thin surface's entry face there leaves the medium). Objects change nothing.
fn medium_after(current: vec4<f32>, look: vec4<f32>, info: u32) -> vec4<f32> {
    let front = (info & INFO_FRONT) != 0u;
    let at_interface = (info & INFO_INTERFACE) != 0u;
    if (info & 0xffffu) == OBJECT_BLOCK || frame.volumes != MEDIA_WALK {
        return current;
    }
    if look.a > 0.0 && front {
        return look;
    }
    if leaves_volume(look, info) || (front && at_interface) {
        return vec4<f32>(0.0);
    }
    return current;
}

// Whether a fragment is a way out of a volume: a back face of a volume not toward another
// translucent type, or of the eye's own medium, which fogs the eye even where its type is
// a thin surface seen from outside (`BlockDef::eye_absorption`).
fn leaves_volume(look: vec4<f32>, info: u32) -> bool {
    let front = (info & INFO_FRONT) != 0u;
    let at_interface = (info & INFO_INTERFACE) != 0u;
    let eyes = frame.medium != NO_MEDIUM && (info & 0xffffu) == frame.medium;
    return !front && !at_interface && (look.a > 0.0 || eyes);
}

// The medium a walk from the eye starts in (the exact references): the eye's, or none.
fn eye_medium() -> vec4<f32> {
    if frame.volumes == MEDIA_WALK && frame.medium != NO_MEDIUM {
        return frame.medium_look;
    }
    return vec4<f32>(0.0);
}

// Whether a fragment changes the medium (the exact references keep it even where it has
// no colour).
fn changes_medium(look: vec4<f32>, info: u32) -> bool {
    let front = (info & INFO_FRONT) != 0u;
    let at_interface = (info & INFO_INTERFACE) != 0u;
    return frame.volumes == MEDIA_WALK && (info & 0xffffu) != OBJECT_BLOCK
        && ((look.a > 0.0 && front) || leaves_volume(look, info) || (front && at_interface));
}

// `segment` (premultiplied) in front of `surface` (straight), premultiplied.
fn in_front_of(segment: vec4<f32>, surface: vec4<f32>) -> vec4<f32> {
    return segment + (1.0 - segment.a) * vec4<f32>(surface.rgb * surface.a, surface.a);
}
