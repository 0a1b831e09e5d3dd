// The media between the eye and a fragment, for the real-time techniques (after
// volume.wgsl; needs `frame`, `volume_depth`, `volume_entry`, `entry_look`,
// `depth_sampler` and `boundary_depth`). `medium.rs` has the model.
//
// Along a pixel's ray the real-time techniques know three stretches of medium: the eye's
// own medium up to its boundary (the first surface of its type, or the opaque surface),
// the nearest volume entered beyond it (`volume_entry`, with its look in `entry_look`) up
// to where volumes end (`volume_depth`: the first back face of a volume, or the opaque
// surface), and the nearest volume entered beyond that end (`volume_entry2`,
// `entry2_look`) up to the farthest back face of a volume or else the opaque surface
// (`volume_end`). Every translucent fragment is seen through the part of that path in front of
// it, `fogged`, and the opaque picture through all of it, by the media pass before the
// technique draws (`media.wgsl`). With layers (straight colour c_i, opacity a_i) at path
// transmittances T_i and the light E_i the path adds in front of each (premultiplied),
//   a_1 (T_1 c_1 + E_1) + (1 − a_1) [a_2 (T_2 c_2 + E_2) + (1 − a_2) (… + T_o o + E_o)]
// is, term for term, the path split at every layer: segment, layer, segment, … , opaque.
// So a fragment needs only its own path, whatever lies in front of or behind it: exact for
// any number of a game's things inside the water that holds the eye or inside a lake
// seen from above, in every technique that blends in order; the weighted ones blend the
// same fragments by weight. Nothing is divided and no colour leaves what its inputs span.

fn depth_at(t: texture_2d<f32>, xy: vec2<f32>) -> f32 {
    return textureSampleLevel(t, depth_sampler, depth_uv(xy, textureDimensions(t)), 0.0).x;
}

// The path from the eye to window depth `z` at pixel `xy` through the media above
// (premultiplied: rgb the light it adds, a one minus its transmittance). Zero when the
// frame is not one of the real-time techniques' with media (MEDIA_EYE, MEDIA_VOLUMES).
fn path_to(xy: vec2<f32>, z: f32) -> vec4<f32> {
    var p = vec4<f32>(0.0);
    if frame.volumes != MEDIA_EYE && frame.volumes != MEDIA_VOLUMES {
        return p;
    }
    if frame.medium != NO_MEDIUM && frame.medium_look.a > 0.0 {
        // Up to the boundary, or to the fragment in front of it (reverse-Z: the larger).
        p = medium_segment(frame.medium_look, ray_length(xy, EYE_Z, max(z, boundary_depth(xy))));
    }
    if frame.volumes == MEDIA_VOLUMES {
        let entry = depth_at(volume_entry, xy);
        if z < entry {
            let look = look_at(entry_look, xy);
            let end = max(z, depth_at(volume_depth, xy));
            p += (1.0 - p.a) * medium_segment(look, ray_length(xy, entry, end));
        }
        let entry2 = depth_at(volume_entry2, xy);
        if z < entry2 {
            let look = look_at(entry2_look, xy);
            let end = max(z, volume_end(xy, entry2));
            p += (1.0 - p.a) * medium_segment(look, ray_length(xy, entry2, end));
        }
    }
    return p;
}

// Two depths closer than this share of their value lie in one plane (two quads of one
// plane interpolate its depth with different rounding).
const PATH_TIE: f32 = 1.0 / 65536.0;

// A medium's look at pixel `xy` of a look target.
fn look_at(t: texture_2d<f32>, xy: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(t, depth_sampler, depth_uv(xy, textureDimensions(t)), 0.0);
}

// Where a volume entered at depth `z` ends at pixel `xy`, as far as the real-time
// techniques know: the farthest back face of a volume, where it lies beyond `z`, or else
// the opaque surface.
fn volume_end(xy: vec2<f32>, z: f32) -> f32 {
    let far = depth_at(volume_far, xy);
    return select(depth_at(opaque_copy, xy), far, far < z);
}

// A translucent fragment's straight colour `c` at pixel `xy` and window depth `z`, seen
// through the path in front of it (its opacity unchanged).
fn fogged(xy: vec2<f32>, z: f32, c: vec4<f32>) -> vec4<f32> {
    if c.a <= 0.0 {
        return c;
    }
    let p = path_to(xy, z);
    return vec4<f32>(p.rgb + (1.0 - p.a) * c.rgb, c.a);
}
