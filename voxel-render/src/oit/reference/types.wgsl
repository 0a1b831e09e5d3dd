// Types shared by both A-buffer passes (after the constants made in Rust: MAX_LAYERS).

struct Node {
    // Colour and alpha as four halves (pack2x16float): exact enough for a reference that
    // blends in f32 and is compared after 8-bit output.
    color: vec2<u32>,
    depth: f32,
    // Index + 1 of the next node of the pixel; 0 ends the list.
    next: u32,
    // The depth's screen-space gradient (dpdx, dpdy): orders fragments of equal depth.
    slope: vec2<f32>,
    // Its part in the medium the ray is in (`fragment_info` in volume.wgsl).
    info: u32,
    _pad: u32,
};

// Read back after every tile (`Counters` in mod.rs, checked equal by a test).
struct Counters {
    // Nodes asked for, including those that did not fit in the pool.
    nodes: atomic<u32>,
    // Pixels with more than MAX_LAYERS fragments: only the nearest MAX_LAYERS are blended.
    capped: atomic<u32>,
    // Of those, pixels where more than half a level of light (1/510) still came through
    // the kept layers, so that the dropped ones could change the 8-bit colour.
    capped_visible: atomic<u32>,
    _pad: u32,
};

// The tile being drawn (`Params` in mod.rs, checked equal by a test): head pointers are
// per tile, so that they fit in one storage binding at any render size.
struct Params {
    origin: vec2<u32>,
    tile_width: u32,
    capacity: u32,
};

fn head_index(p: vec2<u32>) -> u32 {
    let local = p - params.origin;
    return local.y * params.tile_width + local.x;
}
