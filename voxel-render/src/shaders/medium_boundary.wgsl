// The first surface of the eye's medium (appended to common.wgsl): both sides of every
// translucent face of the medium's type, nearest kept in the depth attachment, which
// starts as a copy of the opaque depth. Other fragments are dropped.
//
// In this pass group 0's `medium_boundary` binding holds the opaque depth itself. A face of
// the medium toward a cutout block lies in the plane of that block's face: where the cutout
// texel is solid the two surfaces tie, and the rasteriser's rounding would pick one or the
// other pixel by pixel. A tie goes to the opaque surface, as an opaque block hides the
// medium's face altogether: the passage ends there (its fog still counts). Where the texel
// is a hole the cutout fragment is gone, the opaque depth lies behind, and the face is the
// way out of the medium.
const TIE: f32 = 1.0 / 16384.0;

@fragment
fn fs_boundary(in: VsOut) {
    let opaque = boundary_depth(in.clip.xy);
    if in.block != frame.medium || in.clip.z <= opaque * (1.0 + TIE) {
        discard;
    }
}
