// The custom_stage example's shaders: boxes and camera-facing particles from one instance
// layout. Opaque boxes write the scene colour; translucent ones and the particles end in
// `oit_output`, which the renderer's prelude for each pass of the technique declares.

struct GameView {
    view_proj: mat4x4<f32>,
    // The camera's right and up (particles face it); the sun, w: ambient; x of light:
    // brightness (the frame's lighting, `GameFrame::sun_dir`, `ambient`, `brightness`).
    right: vec4<f32>,
    up: vec4<f32>,
    sun: vec4<f32>,
    light: vec4<f32>,
};

@group(0) @binding(0) var<uniform> game_view: GameView;

struct Instance {
    // Centre relative to the eye (`GameFrame::relative`); w: 1 for a particle.
    @location(0) center: vec4<f32>,
    // A box's half axes (world directions, scaled); a particle's half size in axis_x.x.
    @location(1) axis_x: vec4<f32>,
    @location(2) axis_y: vec4<f32>,
    @location(3) axis_z: vec4<f32>,
    // Linear colour and opacity.
    @location(4) color: vec4<f32>,
};

struct GameOut {
    @builtin(position) position: vec4<f32>,
    @location(0) color: vec4<f32>,
};

// The 6 faces of a unit cube, two triangles each: face `f` has normal axis f / 2, sign
// + for even f; corners (u, v) in [-1, 1].
fn corner(i: u32) -> vec2<f32> {
    var c = array<vec2<f32>, 6>(
        vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0),
    );
    return c[i];
}

@vertex
fn vs_game(@builtin(vertex_index) vi: u32, inst: Instance) -> GameOut {
    var out: GameOut;
    let face = vi / 6u;
    let uv = corner(vi % 6u);
    var p: vec3<f32>;
    var normal: vec3<f32>;
    if inst.center.w > 0.5 {
        // A particle: one square facing the camera, only face 0.
        if face != 0u {
            out.position = vec4<f32>(0.0, 0.0, 0.0, 0.0);
            return out;
        }
        let s = inst.axis_x.x;
        p = inst.center.xyz + (game_view.right.xyz * uv.x + game_view.up.xyz * uv.y) * s;
        normal = game_view.sun.xyz;
    } else {
        var axes = array<vec3<f32>, 3>(inst.axis_x.xyz, inst.axis_y.xyz, inst.axis_z.xyz);
        let k = face / 2u;
        let sign = select(-1.0, 1.0, face % 2u == 0u);
        let n = axes[k] * sign;
        let f = inst.center.xyz + n;
        // Faces turned away from the eye (at the origin) are dropped: a translucent box is
        // one layer, its front.
        if dot(n, -f) <= 0.0 {
            out.position = vec4<f32>(0.0, 0.0, 0.0, 0.0);
            return out;
        }
        p = f + axes[(k + 1u) % 3u] * uv.x + axes[(k + 2u) % 3u] * uv.y;
        normal = normalize(n);
    }
    out.position = game_view.view_proj * vec4<f32>(p, 1.0);
    let lambert = max(dot(normal, game_view.sun.xyz), 0.0);
    let light = game_view.light.x * (game_view.sun.w + (1.0 - game_view.sun.w) * lambert);
    out.color = vec4<f32>(inst.color.rgb * light, inst.color.a);
    return out;
}

@fragment
fn fs_opaque(in: GameOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.rgb, 1.0);
}
