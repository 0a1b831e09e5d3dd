// The per-frame uniforms every pass reads (`FrameUniforms` in bindings.rs, checked equal by
// a test), shared by the chunk pipelines (group 0) and games' translucent pipelines
// (the renderer's group there).

struct Frame {
    view_proj: mat4x4<f32>,
    eye_int: vec3<i32>,
    near: f32,
    eye_frac: vec3<f32>,
    far: f32,
    sun_dir: vec3<f32>,
    ambient: f32,
    sky: vec3<f32>,
    // How much darker chunks of odd levels of detail are drawn (0: not at all).
    level_bands: f32,
    viewport: vec2<f32>,
    // Block id of the translucent type the eye is inside, or NO_MEDIUM.
    medium: u32,
    // Ambient-occlusion strength, 0 (off) to 1.
    ao_strength: f32,
    // tan of half the horizontal and vertical field of view.
    tan_half: vec2<f32>,
    // Which media the fragments are seen through (MEDIA_*, `bindings.rs`): none; the eye's
    // medium (real-time techniques, `path.wgsl`); besides, the nearest volume in view
    // (`volume_depth`, `volume_entry`, `entry_look`, `opaque_copy` hold it); or every
    // medium, walked by the exact references along their sorted fragments.
    volumes: u32,
    // How bright sun (or moon) and ambient light are: 1 by day, less at night.
    brightness: f32,
    // The look of the medium the eye is in (linear colour, absorption), or zero.
    medium_look: vec4<f32>,
    // Sun shadows (`sun.rs`, `sun_transmittance` in common.wgsl): the eye's integer part
    // minus the shadow volume's first block; 1 while on; the volume's size in blocks; where
    // the sun filters start in `block_media`; per tile of 8 × 8 columns (x + 32 z) the
    // highest cell holding anything but air (-1: none).
    sun_offset: vec3<i32>,
    sun_on: u32,
    sun_size: vec3<u32>,
    sun_table: u32,
    // Where the volume's first block lies in `sun_cells` (a torus: a block at its world
    // position modulo the size).
    sun_wrap: vec3<u32>,
    sun_pad: u32,
    sun_tops: array<vec4<i32>, 256>,
};

// The light a medium's colour is lit by, the same for the fog around the eye and for a
// path through a volume: that of a face turned to the sky, at the light's brightness.
fn frame_sky_light(f: Frame) -> f32 {
    return f.brightness * (f.ambient + (1.0 - f.ambient) * max(f.sun_dir.y, 0.0));
}
