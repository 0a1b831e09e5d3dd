// The clip of a part of a game's object (sorted techniques; the technique's group 2 in a
// game's prelude): an object cut where it reaches through a plane of quads is drawn once
// per part, each run of parts with its clip (`interleave`, `Split::clip`).

struct OitClip {
    // Each plane in clip space, oriented toward the eye's side: a fragment at normalised
    // device position p lies dot(plane, p) times its view depth blocks from the plane
    // (positive on the eye's side); dot(plane, p) = 0 solved for p.z is where the pixel's
    // ray meets it.
    planes: array<vec4<f32>, 6>,
    // How many planes there are; bit i of `far`: plane i keeps what lies beyond it (else the
    // eye's side and the plane itself).
    count: u32,
    far: u32,
};

@group(2) @binding(0) var<uniform> oit_clip: OitClip;

// Whether the fragment at `position` lies outside the part being drawn. A fragment is on
// a plane's eye side where it lies nearer than the plane along its pixel's ray, compared as
// the exact methods compare an object's fragment with a face's (its depth times
// 1 + OIT_OBJECT_DEPTH_BIAS: at equal depth the object is in front), so that a part a cut
// puts on the eye's side is what they put in front of the plane's quads.
fn oit_clipped(position: vec4<f32>) -> bool {
    let xy = vec2<f32>(
        position.x / frame.viewport.x * 2.0 - 1.0,
        1.0 - position.y / frame.viewport.y * 2.0,
    );
    let z = position.z * (1.0 + OIT_OBJECT_DEPTH_BIAS);
    for (var i = 0u; i < oit_clip.count; i += 1u) {
        let plane = oit_clip.planes[i];
        var eye_side = dot(plane, vec4<f32>(xy, position.z, 1.0)) >= 0.0;
        if plane.z != 0.0 {
            // Where the pixel's ray meets the plane (window depth), whichever way it faces.
            let at = -(plane.x * xy.x + plane.y * xy.y + plane.w) / plane.z;
            eye_side = z >= at;
        }
        let far = ((oit_clip.far >> i) & 1u) != 0u;
        if far == eye_side {
            return true;
        }
    }
    return false;
}
