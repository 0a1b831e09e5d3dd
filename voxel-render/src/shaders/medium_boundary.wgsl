// The first surface of the eye's medium (appended to common.wgsl): both sides of every
// translucent face of the medium's type, nearest kept in the depth attachment, which
// starts as a copy of the opaque depth. Other fragments are dropped.

@fragment
fn fs_boundary(in: VsOut) {
    if in.block != frame.medium {
        discard;
    }
}
