// The clip of a part of a game's object (sorted techniques; the technique's group 2 in a
// game's prelude): an object cut where it reaches through a plane of quads is drawn once
// per part, each run of parts with its clip (`interleave`, `Split::clip`).

struct OitClip {
    // Each plane in clip space, oriented toward the eye's side: a fragment at normalised
    // device position p lies dot(plane, p) times its view depth blocks from the plane
    // (positive on the eye's side).
    planes: array<vec4<f32>, 6>,
    // How many planes there are; bit i of `far`: plane i keeps what lies beyond it (else the
    // eye's side and the plane itself).
    count: u32,
    far: u32,
};

@group(2) @binding(0) var<uniform> oit_clip: OitClip;

// Whether the fragment at `position` lies outside the part being drawn. A fragment within
// OIT_CLIP_EPSILON of its view depth of a plane counts as in the plane (what the depth
// reconstruction can tell apart), so that a face lying in it stays on the eye's side.
fn oit_clipped(position: vec4<f32>) -> bool {
    let p = vec4<f32>(
        position.x / frame.viewport.x * 2.0 - 1.0,
        1.0 - position.y / frame.viewport.y * 2.0,
        position.z,
        1.0,
    );
    for (var i = 0u; i < oit_clip.count; i += 1u) {
        let eye_side = dot(oit_clip.planes[i], p) >= -OIT_CLIP_EPSILON;
        let far = ((oit_clip.far >> i) & 1u) != 0u;
        if far == eye_side {
            return true;
        }
    }
    return false;
}
