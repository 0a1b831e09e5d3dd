// Fragments inside a volume in the sorted techniques (after volume.wgsl; needs `frame`,
// `volume_depth`, `volume_entry`, `entry_look`, `depth_sampler` and `boundary_depth`).
//
// A volume's entry face composes the whole path behind it down to where the volume ends
// (`translucent_color`), so a translucent fragment inside the volume, drawn before it in
// back-to-front order, would be absorbed as if it lay at that end. Drawn with colour
// (c − (1 − T) m) / T instead, T = exp(−σ d) over the d blocks from it to that end and m
// the medium's lit colour (the colour may leave 0..1: the targets are float), the blend
// comes out as the path split at the fragment, for any number of fragments inside: with
// S the entry face and V(a→b) the medium between, S ⊕ V(0→e) ⊕ [c'] ⊕ V… equals
// S ⊕ V(0→z) ⊕ c ⊕ V(z→e). The eye's own medium, which the fog puts in front of
// everything up to its boundary, is treated the same way.

fn depth_at(t: texture_2d<f32>, xy: vec2<f32>) -> f32 {
    return textureSampleLevel(t, depth_sampler, depth_uv(xy, textureDimensions(t)), 0.0).x;
}

// `c` (straight) of a fragment at pixel `xy` and window depth `z`, as the sorted
// techniques compose it (unchanged unless `frame.volumes` is 2 and it lies inside a volume).
fn inside_volume(xy: vec2<f32>, z: f32, c: vec4<f32>) -> vec4<f32> {
    if frame.volumes != 2u || c.a <= 0.0 {
        return c;
    }
    var m = vec4<f32>(0.0);
    var end = 0.0;
    if frame.medium != NO_MEDIUM && z > boundary_depth(xy) {
        // In the eye's medium, in front of its boundary, which the fog ends at.
        m = frame.medium_look;
        end = boundary_depth(xy);
    } else {
        let exit = depth_at(volume_depth, xy);
        if z < depth_at(volume_entry, xy) && z > exit {
            let uv = depth_uv(xy, textureDimensions(entry_look));
            m = textureSampleLevel(entry_look, depth_sampler, uv, 0.0);
            end = exit;
        }
    }
    if m.a <= 0.0 {
        return c;
    }
    let segment = medium_segment(m, ray_length(xy, z, end));
    let t = 1.0 - segment.a;
    return vec4<f32>((c.rgb - segment.rgb) / max(t, 1e-4), c.a);
}
