// Types shared by both A-buffer passes.

struct Node {
    // Colour and alpha as four halves (pack2x16float): exact enough for a reference that
    // blends in f32 and is compared after 8-bit output.
    color: vec2<u32>,
    depth: f32,
    // Index + 1 of the next node of the pixel; 0 ends the list.
    next: u32,
};

struct Counters {
    // Nodes asked for, including those that did not fit.
    nodes: atomic<u32>,
    // Pixels whose list was longer than the resolve can sort (MAX_LAYERS).
    truncated: atomic<u32>,
};

struct Params {
    width: u32,
    capacity: u32,
};
