//! The MagicaVoxel models of `scenes/vox/`, built in code and written with `dot_vox`'s
//! writer (so the repository's `.vox` files are ours, under the project's licence). The test
//! `tests/tests/vox.rs` checks that the committed files are what these builders write, and
//! rewrites them with `VOX_UPDATE=1`.
//!
//! Colour indices here are the file's (1 to 255); `dot_vox` stores a voxel's index minus
//! one and the palette from index 1, and names a material by the file's index.

use std::collections::BTreeMap;

use dot_vox::{
    Color, Dict, DotVoxData, Frame, Material, Model, SceneNode, ShapeModel, Size, Voxel,
};

/// A model under construction: later writes replace earlier ones.
#[derive(Debug, Default)]
pub struct Builder {
    size: [u32; 3],
    voxels: BTreeMap<[u8; 3], u8>,
}

impl Builder {
    /// An empty model of `size` (MagicaVoxel's axes: x right, y back, z up).
    pub fn new(size: [u32; 3]) -> Self {
        Self {
            size,
            voxels: BTreeMap::new(),
        }
    }

    /// Sets one voxel to colour `index` (ignored outside the model).
    pub fn set(&mut self, x: i32, y: i32, z: i32, index: u8) {
        let inside = |v: i32, s: u32| v >= 0 && (v as u32) < s;
        if inside(x, self.size[0]) && inside(y, self.size[1]) && inside(z, self.size[2]) {
            self.voxels.insert([x as u8, y as u8, z as u8], index);
        }
    }

    /// Empties one voxel.
    pub fn clear(&mut self, x: i32, y: i32, z: i32) {
        if let (Ok(x), Ok(y), Ok(z)) = (u8::try_from(x), u8::try_from(y), u8::try_from(z)) {
            self.voxels.remove(&[x, y, z]);
        }
    }

    /// Fills the box `a..=b` with colour `index`.
    pub fn fill(&mut self, a: [i32; 3], b: [i32; 3], index: u8) {
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    self.set(x, y, z, index);
                }
            }
        }
    }

    /// Empties the box `a..=b`.
    pub fn carve(&mut self, a: [i32; 3], b: [i32; 3]) {
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    self.clear(x, y, z);
                }
            }
        }
    }

    /// The colour index at a voxel, if set.
    pub fn get(&self, x: i32, y: i32, z: i32) -> Option<u8> {
        let (x, y, z) = (
            u8::try_from(x).ok()?,
            u8::try_from(y).ok()?,
            u8::try_from(z).ok()?,
        );
        self.voxels.get(&[x, y, z]).copied()
    }

    /// The `dot_vox` model.
    pub fn model(&self) -> Model {
        Model {
            size: Size {
                x: self.size[0],
                y: self.size[1],
                z: self.size[2],
            },
            voxels: self
                .voxels
                .iter()
                .map(|(p, i)| Voxel {
                    x: p[0],
                    y: p[1],
                    z: p[2],
                    i: i - 1,
                })
                .collect(),
        }
    }
}

fn dict(entries: &[(&str, String)]) -> Dict {
    entries
        .iter()
        .map(|(k, v)| ((*k).to_owned(), v.clone()))
        .collect()
}

/// A transform node: child, translation and rotation byte (MagicaVoxel's `_r`).
pub fn transform(child: u32, t: [i32; 3], rotation: Option<u8>) -> SceneNode {
    let mut frame = vec![("_t", format!("{} {} {}", t[0], t[1], t[2]))];
    if let Some(r) = rotation {
        frame.push(("_r", r.to_string()));
    }
    SceneNode::Transform {
        attributes: Dict::default(),
        frames: vec![Frame::new(dict(&frame))],
        child,
        layer_id: 0,
    }
}

/// A group node.
pub fn group(children: &[u32]) -> SceneNode {
    SceneNode::Group {
        attributes: Dict::default(),
        children: children.to_vec(),
    }
}

/// A shape node placing model `model`.
pub fn shape(model: u32) -> SceneNode {
    SceneNode::Shape {
        attributes: Dict::default(),
        models: vec![ShapeModel {
            model_id: model,
            attributes: Dict::default(),
        }],
    }
}

/// A glass material for colour index `index` with transparency `trans` (MagicaVoxel's
/// `_trans`; opacity 1 − `trans`).
pub fn glass(index: u8, trans: f32) -> Material {
    Material {
        id: u32::from(index),
        properties: dict(&[
            ("_type", "_glass".into()),
            ("_trans", trans.to_string()),
            ("_ior", "0.3".into()),
        ]),
    }
}

/// A material of another type for colour index `index` (`_metal`, `_diffuse`, ...).
pub fn other(index: u8, kind: &str) -> Material {
    Material {
        id: u32::from(index),
        properties: dict(&[("_type", kind.into()), ("_rough", "0.2".into())]),
    }
}

/// A palette of 256 colours (entry k is colour index k + 1): grey where `colors` names none.
pub fn palette(colors: &[(u8, [u8; 3])]) -> Vec<Color> {
    let mut p = vec![
        Color {
            r: 128,
            g: 128,
            b: 128,
            a: 255
        };
        256
    ];
    for (i, c) in colors {
        p[usize::from(*i) - 1] = Color {
            r: c[0],
            g: c[1],
            b: c[2],
            a: 255,
        };
    }
    p
}

/// The file `dot_vox` writes for `data`.
pub fn bytes(data: &DotVoxData) -> Vec<u8> {
    let mut out = Vec::new();
    data.write_vox(&mut out).expect("writing to memory");
    out
}

/// Colour indices of the chapel.
pub mod chapel_colors {
    /// Pale limestone walls.
    pub const STONE: u8 = 1;
    /// Darker stone: floor, plinths, frames.
    pub const DARK: u8 = 2;
    /// Terracotta floor tiles.
    pub const TILE: u8 = 3;
    /// Pews and doors.
    pub const WOOD: u8 = 4;
    /// Slate roof.
    pub const SLATE: u8 = 5;
    /// Brass lantern frames (a `_metal` material: opaque).
    pub const BRASS: u8 = 8;
    /// Red stained glass, opacity 0.65.
    pub const RED: u8 = 10;
    /// Blue stained glass, opacity 0.5.
    pub const BLUE: u8 = 11;
    /// Amber stained glass, opacity 0.35.
    pub const AMBER: u8 = 12;
    /// Green stained glass, opacity 0.45.
    pub const GREEN: u8 = 13;
    /// Clear glass, opacity 0.15.
    pub const CLEAR: u8 = 14;
    /// Font water, a glass material of opacity 0.55.
    pub const WATER: u8 = 15;
}

/// `scenes/vox/chapel.vox`: a stained-glass chapel (a nave of 34 × 48 × 39 voxels, more
/// than a 32³ chunk on every axis, with a clear-glass skylight and a water font), its bell tower with a
/// glass lantern, and two glass kiosks in a garden group, one turned a quarter. Version 200
/// with `MATL` glass of five opacities and a scene graph of groups, translations and a
/// rotation.
pub fn chapel() -> DotVoxData {
    use chapel_colors::*;
    let colors = [
        (STONE, [196, 188, 170]),
        (DARK, [112, 106, 100]),
        (TILE, [158, 78, 58]),
        (WOOD, [112, 76, 44]),
        (SLATE, [66, 72, 90]),
        (BRASS, [205, 165, 70]),
        (RED, [200, 36, 40]),
        (BLUE, [40, 76, 210]),
        (AMBER, [240, 172, 40]),
        (GREEN, [56, 176, 84]),
        (CLEAR, [215, 235, 245]),
        (WATER, [36, 110, 170]),
    ];
    let stained = [RED, BLUE, AMBER, GREEN];

    // The nave: x across, y front (0) to back, z up.
    let (w, d, h) = (34, 48, 39);
    let mut nave = Builder::new([w as u32, d as u32, h as u32]);
    nave.fill([0, 0, 0], [w - 1, d - 1, 0], DARK);
    nave.fill([2, 2, 0], [w - 3, d - 3, 0], TILE);
    let eaves = 20;
    nave.fill([0, 0, 1], [0, d - 1, eaves], STONE);
    nave.fill([w - 1, 0, 1], [w - 1, d - 1, eaves], STONE);
    nave.fill([0, 0, 1], [w - 1, 0, eaves], STONE);
    nave.fill([0, d - 1, 1], [w - 1, d - 1, eaves], STONE);
    // Side windows: six bays, diamonds of stained glass.
    for bay in 0..5 {
        let y0 = 5 + bay * 8;
        for y in y0..y0 + 5 {
            for z in 5..17 {
                let c = stained[((y - y0 + z / 3 + bay) % 4) as usize];
                nave.set(0, y, z, c);
                nave.set(
                    w - 1,
                    y,
                    z,
                    stained[((y - y0 + z / 3 + bay + 2) % 4) as usize],
                );
            }
        }
        // Pointed arch tops.
        for (dy, z) in [(1, 17), (2, 17), (3, 17), (2, 18)] {
            nave.set(0, y0 + dy, z, AMBER);
            nave.set(w - 1, y0 + dy, z, AMBER);
        }
    }
    // The rose window over the door, rings of colour.
    let (cx, cz) = (16.5f64, 14.0f64);
    for x in 0..w {
        for z in 1..=eaves {
            let r = ((f64::from(x) - cx).powi(2) + (f64::from(z) - cz).powi(2)).sqrt();
            if r < 6.5 {
                let ring = [AMBER, RED, BLUE, BLUE, GREEN, RED, RED][r as usize];
                nave.set(x, 0, z, if r > 5.6 { DARK } else { ring });
            }
        }
    }
    // The door under it, and a tall window at the back.
    nave.carve([14, 0, 1], [19, 0, 6]);
    nave.fill([13, 0, 7], [20, 0, 7], DARK);
    for z in 3..18 {
        for x in 13..21 {
            nave.set(x, d - 1, z, if (x + z) % 5 == 0 { BLUE } else { CLEAR });
        }
    }
    // Gable roof: slate, with a clear-glass skylight along the middle of each slope.
    for k in 0..=w / 2 {
        let z = eaves + 1 + k;
        for y in 0..d {
            let c = if (12..36).contains(&y) && (3..13).contains(&k) {
                CLEAR
            } else {
                SLATE
            };
            nave.set(k, y, z, c);
            nave.set(w - 1 - k, y, z, c);
        }
        // Gable walls, front and back.
        for x in k + 1..w - 1 - k {
            nave.set(x, 0, z, STONE);
            nave.set(x, d - 1, z, STONE);
        }
    }
    // The font: a stone basin of water under the skylight, and pews in front of it.
    nave.fill([13, 20, 1], [20, 27, 3], DARK);
    nave.fill([14, 21, 1], [19, 26, 3], WATER);
    for y in (6..18).step_by(3).chain((31..44).step_by(3)) {
        nave.fill([4, y, 1], [12, y, 2], WOOD);
        nave.fill([21, y, 1], [29, y, 2], WOOD);
    }

    // The bell tower: hollow stone, amber windows, a glass lantern on top.
    let mut tower = Builder::new([10, 10, 44]);
    tower.fill([0, 0, 0], [9, 9, 33], STONE);
    tower.carve([1, 1, 1], [8, 8, 33]);
    for z in [10, 11, 12, 22, 23, 24] {
        for c in 3..7 {
            tower.set(c, 0, z, AMBER);
            tower.set(c, 9, z, AMBER);
            tower.set(0, c, z, AMBER);
            tower.set(9, c, z, AMBER);
        }
    }
    tower.fill([0, 0, 34], [9, 9, 34], DARK);
    tower.fill([1, 1, 35], [8, 8, 41], CLEAR);
    tower.carve([2, 2, 35], [7, 7, 41]);
    for (x, y) in [(1, 1), (1, 8), (8, 1), (8, 8)] {
        tower.fill([x, y, 35], [x, y, 41], BRASS);
    }
    tower.fill([3, 3, 35], [6, 6, 38], AMBER);
    tower.fill([0, 0, 42], [9, 9, 42], SLATE);
    tower.fill([2, 2, 43], [7, 7, 43], SLATE);

    // A kiosk: stone back wall, brass posts, a sloping green-glass roof, blue glass sides.
    let mut kiosk = Builder::new([7, 5, 9]);
    kiosk.fill([0, 4, 0], [6, 4, 6], STONE);
    kiosk.fill([0, 0, 0], [6, 4, 0], DARK);
    for (x, y) in [(0, 0), (6, 0)] {
        kiosk.fill([x, y, 1], [x, y, 6], BRASS);
    }
    kiosk.fill([0, 1, 1], [0, 3, 5], BLUE);
    kiosk.fill([6, 1, 1], [6, 3, 5], BLUE);
    for y in 0..5 {
        kiosk.fill(
            [0, y, 7 + (y >= 2) as i32],
            [6, y, 7 + (y >= 2) as i32],
            GREEN,
        );
    }
    kiosk.fill([2, 2, 1], [4, 2, 3], WOOD);

    let scenes = vec![
        transform(1, [0, 0, 0], None),
        group(&[2, 4, 6]),
        transform(3, [0, 0, 19], None),
        shape(0),
        transform(5, [24, -20, 22], None),
        shape(1),
        transform(7, [0, -34, 0], None),
        group(&[8, 10]),
        transform(9, [-11, 0, 4], None),
        shape(2),
        // A quarter turn about z: rows (-y, x, z).
        transform(11, [11, 0, 4], Some(0b0001_0001)),
        shape(2),
    ];
    let mut materials = vec![
        glass(RED, 0.35),
        glass(BLUE, 0.5),
        glass(AMBER, 0.65),
        glass(GREEN, 0.55),
        glass(CLEAR, 0.85),
        glass(WATER, 0.45),
        other(BRASS, "_metal"),
    ];
    materials.sort_by_key(|m| m.id);
    DotVoxData {
        version: 200,
        index_map: Vec::new(),
        models: vec![nave.model(), tower.model(), kiosk.model()],
        palette: palette(&colors),
        materials,
        scenes,
        layers: Vec::new(),
    }
}

/// The colour index of MagicaVoxel's default palette nearest `rgb`.
pub fn default_index(rgb: [u8; 3]) -> u8 {
    let p = voxel_core::vox::default_palette();
    let dist = |c: [u8; 3]| -> i32 {
        (0..3)
            .map(|i| (i32::from(c[i]) - i32::from(rgb[i])).pow(2))
            .sum()
    };
    (1..=255u8)
        .min_by_key(|i| dist(p[usize::from(*i)]))
        .unwrap_or(1)
}

/// Colour indices of the harbour, all from MagicaVoxel's default palette.
#[derive(Clone, Copy, Debug)]
pub struct HarbourColors {
    /// Sand.
    pub sand: u8,
    /// Grass.
    pub grass: u8,
    /// Earth under the grass.
    pub earth: u8,
    /// Quay and lighthouse stone.
    pub stone: u8,
    /// Pier and boat.
    pub wood: u8,
    /// The sea: a plain blue, made translucent by `harbour.toml`'s palette override.
    pub water: u8,
    /// The lighthouse lantern and the greenhouse: a plain pale cyan, made translucent.
    pub glass: u8,
    /// Red lighthouse bands and the boat's sail.
    pub red: u8,
    /// Plants in the greenhouse.
    pub leaf: u8,
}

/// The harbour's colour indices.
pub fn harbour_colors() -> HarbourColors {
    HarbourColors {
        sand: default_index([204, 204, 153]),
        grass: default_index([102, 153, 51]),
        earth: default_index([153, 102, 51]),
        stone: default_index([153, 153, 153]),
        wood: default_index([102, 51, 0]),
        water: default_index([51, 102, 153]),
        glass: default_index([204, 255, 255]),
        red: default_index([204, 51, 51]),
        leaf: default_index([51, 153, 51]),
    }
}

/// `scenes/vox/models/harbour.vox`: an older-style file (version 150, MagicaVoxel's
/// default palette, no materials, no scene graph): a 64 × 56 × 24 harbour whose sea is a
/// plain blue volume and whose lighthouse lantern and greenhouse are a plain pale cyan.
/// Only a scene file's palette overrides make them translucent.
pub fn harbour() -> DotVoxData {
    let c = harbour_colors();
    let (w, d) = (64, 56);
    let mut m = Builder::new([w as u32, d as u32, 24]);
    let quay = 36; // y where the land begins
    let sea = 7; // top of the water
    // Sea floor rising to a beach on the left, water above it.
    for x in 0..w {
        for y in 0..quay {
            let floor = 1 + (12 - x).max(0) / 2 + (y % 7 == 0) as i32;
            m.fill([x, y, 0], [x, y, floor.min(sea + 1)], c.sand);
            if floor < sea {
                m.fill([x, y, floor + 1], [x, y, sea], c.water);
            }
        }
    }
    // The land: earth with grass on top, a stone quay wall along the water.
    m.fill([0, quay, 0], [w - 1, d - 1, 9], c.earth);
    m.fill([0, quay, 10], [w - 1, d - 1, 10], c.grass);
    m.fill([12, quay, 1], [w - 1, quay + 1, 10], c.stone);
    // A pier on posts.
    m.fill([28, 6, 9], [33, quay - 1, 9], c.wood);
    for y in (6..quay).step_by(6) {
        for x in [28, 33] {
            m.fill([x, y, 1], [x, y, 8], c.wood);
        }
    }
    // A boat floating off the pier, with a mast and a sail.
    m.fill([41, 14, 6], [48, 19, 6], c.wood);
    m.fill([40, 15, 7], [49, 18, 8], c.wood);
    m.carve([41, 16, 8], [48, 17, 8]);
    m.fill([44, 16, 9], [44, 16, 18], c.wood);
    for z in 11..18 {
        m.fill([45, 16, z], [45 + (18 - z) / 2, 16, z], c.red);
    }
    // The lighthouse: a round stone tower with red bands and a glass lantern.
    for x in 46..56 {
        for y in 40..50 {
            let r = ((f64::from(x) - 50.5).powi(2) + (f64::from(y) - 44.5).powi(2)).sqrt();
            if r < 4.6 {
                for z in 11..20 {
                    let band = z % 4 == 0;
                    m.set(x, y, z, if band { c.red } else { c.stone });
                }
                m.set(x, y, 20, c.stone);
                if r > 3.4 {
                    m.fill([x, y, 21], [x, y, 23], c.glass);
                } else {
                    m.set(x, y, 23, c.red);
                }
            }
        }
    }
    m.fill([50, 44, 21], [51, 45, 22], c.red);
    // A greenhouse on the quay: glass walls and roof on a stone sill, plants inside.
    m.fill([6, 40, 11], [20, 50, 11], c.stone);
    m.fill([6, 40, 12], [20, 50, 17], c.glass);
    m.carve([7, 41, 12], [19, 49, 16]);
    m.carve([12, 40, 12], [14, 40, 14]);
    for (x, y, hgt) in [
        (9, 43, 3),
        (12, 46, 4),
        (16, 43, 2),
        (17, 47, 3),
        (9, 48, 2),
    ] {
        m.fill([x, y, 12], [x + 1, y + 1, 11 + hgt], c.leaf);
    }
    DotVoxData {
        version: 150,
        index_map: Vec::new(),
        models: vec![m.model()],
        palette: dot_vox::DEFAULT_PALETTE.to_vec(),
        materials: Vec::new(),
        scenes: Vec::new(),
        layers: Vec::new(),
    }
}

/// The committed models: path under the repository root, and what writes them.
pub fn committed() -> Vec<(&'static str, DotVoxData)> {
    vec![
        ("scenes/vox/chapel.vox", chapel()),
        ("scenes/vox/models/harbour.vox", harbour()),
    ]
}
