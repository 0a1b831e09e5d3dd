//! The scene graph: rotations, the placements of models, and the flattening of a file's
//! transforms, groups, shapes and layers into those placements.

use std::collections::HashMap;

use super::bytes::Reader;
use super::{VoxError, VoxFile};

/// A rotation of the scene graph: a signed permutation, `(R v)[r] = sign[r] · v[axis[r]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxRotation {
    /// Per row, the axis it takes.
    pub axis: [u8; 3],
    /// Per row, its sign (±1).
    pub sign: [i8; 3],
}

impl VoxRotation {
    /// No turn.
    pub const IDENTITY: Self = Self {
        axis: [0, 1, 2],
        sign: [1, 1, 1],
    };

    /// Decodes MagicaVoxel's rotation byte: bits 0–1 the axis of row 0, bits 2–3 that of
    /// row 1, bits 4–6 the signs of rows 0–2 (set: negative). `None` unless a signed
    /// permutation below 128.
    pub fn from_byte(b: u8) -> Option<Self> {
        let (a0, a1) = (b & 3, (b >> 2) & 3);
        if b >= 128 || a0 > 2 || a1 > 2 || a0 == a1 {
            return None;
        }
        let sign = |bit: u8| if b & (1 << bit) == 0 { 1 } else { -1 };
        Some(Self {
            axis: [a0, a1, 3 - a0 - a1],
            sign: [sign(4), sign(5), sign(6)],
        })
    }

    /// `self · v`.
    pub fn apply(&self, v: [i64; 3]) -> [i64; 3] {
        std::array::from_fn(|r| i64::from(self.sign[r]) * v[usize::from(self.axis[r])])
    }

    /// `self · other`: `other` first, then `self`.
    pub fn then_after(&self, other: &Self) -> Self {
        Self {
            axis: std::array::from_fn(|r| other.axis[usize::from(self.axis[r])]),
            sign: std::array::from_fn(|r| self.sign[r] * other.sign[usize::from(self.axis[r])]),
        }
    }
}

/// One placement of a model by the scene graph, its transforms flattened.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxInstance {
    /// Index into [`VoxFile::models`].
    pub model: usize,
    /// The product of the rotations from the root down.
    pub rotation: VoxRotation,
    /// The translation, in MagicaVoxel's axes.
    pub translation: [i64; 3],
}

impl VoxInstance {
    /// This crate's block (y-up) that the instance's voxel `v` of a model of size `size`
    /// fills (see the module docs).
    pub fn block(&self, size: [u32; 3], v: [u8; 3]) -> [i64; 3] {
        // Doubled coordinates keep the voxel centre v + 1/2 - floor(s/2) an integer.
        let centre2 = std::array::from_fn(|i| 2 * i64::from(v[i]) + 1 - 2 * i64::from(size[i] / 2));
        let r = self.rotation.apply(centre2);
        // r is odd on every axis: floor(r / 2) is exact.
        let mv: [i64; 3] = std::array::from_fn(|i| self.translation[i] + r[i].div_euclid(2));
        [mv[0], mv[2], -mv[1] - 1]
    }
}

/// A scene graph node as read.
#[derive(Debug)]
pub(super) enum Node {
    Transform {
        child: i64,
        layer: i64,
        hidden: bool,
        rotation: VoxRotation,
        translation: [i64; 3],
    },
    Group(Vec<i64>),
    Shape(Option<i64>),
}

pub(super) fn hidden(d: &HashMap<String, String>) -> bool {
    d.get("_hidden").is_some_and(|v| v == "1")
}

pub(super) fn transform_node(node: i64, r: &mut Reader<'_>) -> Result<Node, VoxError> {
    let attrs = r.dict("nTRN attributes")?;
    let child = r.i32("nTRN child")?;
    let _reserved = r.i32("nTRN reserved id")?;
    let layer = r.i32("nTRN layer")?;
    let frames = r.count(4, "nTRN frames")?;
    let mut rotation = VoxRotation::IDENTITY;
    let mut translation = [0; 3];
    for f in 0..frames {
        let d = r.dict("nTRN frame")?;
        if f > 0 {
            continue; // animation frames after the first are not used
        }
        if let Some(v) = d.get("_r") {
            rotation = v
                .trim()
                .parse::<u8>()
                .ok()
                .and_then(VoxRotation::from_byte)
                .ok_or_else(|| VoxError::Rotation {
                    node,
                    value: v.clone(),
                })?;
        }
        if let Some(v) = d.get("_t") {
            let bad = || VoxError::Translation {
                node,
                value: v.clone(),
            };
            let parts: Vec<i64> = v
                .split_whitespace()
                .map(|p| p.parse::<i32>().map(i64::from))
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            translation = parts.try_into().map_err(|_| bad())?;
        }
    }
    Ok(Node::Transform {
        child,
        layer,
        hidden: hidden(&attrs),
        rotation,
        translation,
    })
}

impl VoxFile {
    /// Voxels the instances place, all together.
    pub fn voxel_count(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.models[i.model].voxels.len() as u64)
            .sum()
    }

    /// Every placed voxel: this crate's block (y-up, before any
    /// [`VoxPlacement`](super::VoxPlacement)) and its colour index.
    pub fn voxels(&self) -> impl Iterator<Item = ([i64; 3], u8)> + '_ {
        self.instances.iter().flat_map(move |inst| {
            let m = &self.models[inst.model];
            m.voxels
                .iter()
                .map(move |v| (inst.block(m.size, [v[0], v[1], v[2]]), v[3]))
        })
    }

    /// Whether colour index `i` is used by a placed voxel, per index.
    pub fn used(&self) -> [bool; 256] {
        let mut per_model = vec![[false; 256]; self.models.len()];
        for (m, used) in self.models.iter().zip(&mut per_model) {
            for v in &m.voxels {
                used[usize::from(v[3])] = true;
            }
        }
        let mut used = [false; 256];
        for inst in &self.instances {
            for (u, m) in used.iter_mut().zip(&per_model[inst.model]) {
                *u |= *m;
            }
        }
        used
    }

    /// The blocks' bounding box (inclusive corners, y-up, before placement), or `None`
    /// when nothing is placed.
    pub fn bounds(&self) -> Option<([i64; 3], [i64; 3])> {
        let mut b: Option<([i64; 3], [i64; 3])> = None;
        for inst in &self.instances {
            let m = &self.models[inst.model];
            if m.voxels.is_empty() {
                continue;
            }
            for corner in 0..8u8 {
                let v = std::array::from_fn(|i| {
                    if corner & (1 << i) == 0 {
                        0
                    } else {
                        (m.size[i] - 1) as u8
                    }
                });
                let p = inst.block(m.size, v);
                let (lo, hi) = b.get_or_insert((p, p));
                for i in 0..3 {
                    lo[i] = lo[i].min(p[i]);
                    hi[i] = hi[i].max(p[i]);
                }
            }
        }
        b
    }
}

/// The visible instances of the scene graph under node 0. Each node is entered once: a
/// node met again is a cycle (when it is an ancestor) or shared (two parents).
pub(super) fn flatten(
    nodes: &HashMap<i64, Node>,
    hidden_layers: &[i64],
    models: usize,
) -> Result<Vec<VoxInstance>, VoxError> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        OnPath,
        Done,
    }
    enum Step {
        Enter(i64, i64, VoxRotation, [i64; 3]),
        Leave(i64),
    }
    let mut state: HashMap<i64, State> = HashMap::with_capacity(nodes.len());
    let mut out = Vec::new();
    let mut stack = vec![Step::Enter(0, -1, VoxRotation::IDENTITY, [0; 3])];
    while let Some(step) = stack.pop() {
        let (id, from, rot, t) = match step {
            Step::Leave(id) => {
                state.insert(id, State::Done);
                continue;
            }
            Step::Enter(id, from, rot, t) => (id, from, rot, t),
        };
        let node = nodes
            .get(&id)
            .ok_or(VoxError::MissingNode { from, missing: id })?;
        match state.get(&id) {
            Some(State::OnPath) => return Err(VoxError::Cycle(id)),
            Some(State::Done) => return Err(VoxError::SharedNode(id)),
            None => {}
        }
        state.insert(id, State::OnPath);
        stack.push(Step::Leave(id));
        match node {
            Node::Transform {
                child,
                layer,
                hidden,
                rotation,
                translation,
            } => {
                if *hidden || hidden_layers.contains(layer) {
                    continue;
                }
                // Parent after child: p = R_parent (R_child v + t_child) + t_parent.
                let moved = rot.apply(*translation);
                let t2 = std::array::from_fn(|i| t[i] + moved[i]);
                // Deep chains could grow without bound; MAX_EXTENT is checked per instance
                // later, this keeps the sums themselves far from overflow.
                if let Some(far) = t2.iter().map(|c: &i64| c.abs()).find(|c| *c > 1 << 40) {
                    return Err(VoxError::OutsideWorld(far));
                }
                stack.push(Step::Enter(*child, id, rot.then_after(rotation), t2));
            }
            Node::Group(children) => {
                for c in children.iter().rev() {
                    stack.push(Step::Enter(*c, id, rot, t));
                }
            }
            Node::Shape(model) => {
                if let Some(m) = *model {
                    let index = usize::try_from(m).ok().filter(|i| *i < models).ok_or(
                        VoxError::MissingModel {
                            node: id,
                            model: m,
                            count: models,
                        },
                    )?;
                    out.push(VoxInstance {
                        model: index,
                        rotation: rot,
                        translation: t,
                    });
                }
            }
        }
    }
    Ok(out)
}
