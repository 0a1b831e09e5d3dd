//! What light needs of each block type: whether it lets light in, its filters (derived from
//! the colour, opacity and absorption the renderer draws it with) and what it emits.

use crate::{BlockRegistry, RenderClass};

/// Fixed point of the filters the propagation multiplies by: 1.0 is `1 << 16`.
pub(super) const ONE: u32 = 1 << 16;

/// The light properties of one block type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Props {
    /// Light enters it (air, cutout and translucent blocks); an opaque block holds only
    /// its own emission.
    pub open: bool,
    /// The sky's beam passes straight down through it (air and translucent blocks): a
    /// cutout block (leaves) casts shade, light only spreads into it.
    pub beam: bool,
    /// The type whose surfaces light crosses: its own id for a translucent or opaque block,
    /// its medium's for a cutout block standing in one, air's (0) for air and other cutout
    /// blocks. Light moving between two cells of the same type crosses no surface.
    pub kind: u16,
    /// Filter per channel for light entering it from a cell of another `kind`: its
    /// surface, then one block of its volume.
    pub enter: [f32; 3],
    /// Filter per channel for light moving into it from a cell of its own `kind`.
    pub within: [f32; 3],
    /// `enter` in fixed point ([`ONE`]).
    pub enter_fx: [u32; 3],
    /// `within` in fixed point ([`ONE`]).
    pub within_fx: [u32; 3],
    /// Block light levels of its own cell.
    pub emit: [u8; 3],
}

/// The sRGB decode the renderer applies to a block's colour.
pub(super) fn linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The filters of a translucent block of linear colour `c`, opacity `a`, absorption `s`:
/// its surface lets through `(1 − a) + a·c` (what the view through it shows of a white
/// thing behind it, the block lit alike), one block of its volume `e^−s + (1 − e^−s)·c`
/// (the same for a path of one block through it).
pub(super) fn filters(c: [f32; 3], a: f32, s: f32) -> ([f32; 3], [f32; 3]) {
    let keep = (-s).exp();
    let surface = c.map(|c| ((1.0 - a) + a * c).clamp(0.0, 1.0));
    let within = c.map(|c| (keep + (1.0 - keep) * c).clamp(0.0, 1.0));
    let enter = [0, 1, 2].map(|i| surface[i] * within[i]);
    (enter, within)
}

fn fixed(f: [f32; 3]) -> [u32; 3] {
    f.map(|f| ((f * ONE as f32).round() as u32).min(ONE))
}

/// The table of every block type of `registry`, by id.
pub(super) fn table(registry: &BlockRegistry) -> Vec<Props> {
    let one = [1.0; 3];
    let open = |kind: u16, enter: [f32; 3], within: [f32; 3], beam: bool, emit| Props {
        open: true,
        beam,
        kind,
        enter,
        within,
        enter_fx: fixed(enter),
        within_fx: fixed(within),
        emit,
    };
    let translucent = |id: u16, def: &crate::BlockDef| {
        let (enter, within) = filters(def.color.map(linear), def.opacity, def.absorption);
        (id, enter, within)
    };
    registry
        .iter()
        .map(|(id, def)| match def.class {
            RenderClass::Air => open(0, one, one, true, def.emission),
            RenderClass::Translucent => {
                let (k, e, w) = translucent(id.0, def);
                open(k, e, w, true, def.emission)
            }
            RenderClass::Cutout => match def.medium.and_then(|m| registry.get(m).ok()) {
                Some(m) if m.class == RenderClass::Translucent => {
                    let (k, e, w) = translucent(def.medium.map_or(0, |m| m.0), m);
                    open(k, e, w, false, def.emission)
                }
                _ => open(0, one, one, false, def.emission),
            },
            RenderClass::Opaque => Props {
                open: false,
                beam: false,
                kind: id.0,
                enter: [0.0; 3],
                within: [0.0; 3],
                enter_fx: [0; 3],
                within_fx: [0; 3],
                emit: def.emission,
            },
        })
        .collect()
}
