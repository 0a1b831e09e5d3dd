//! Chunk meshes on the GPU: one storage buffer of packed quads per non-empty mesh (the
//! vertex shader pulls from it), a small uniform per chunk, and frustum culling.
//!
//! Each upload of a chunk gets a new *generation* number, so that what a technique derives
//! from a chunk's quads (a sort structure, a summary of its layers) can be cached by
//! position and generation and recomputed only when the chunk is remeshed.

use std::collections::HashMap;

use glam::{DVec3, Mat4, Vec3, Vec4};
use voxel_core::{CHUNK_SIZE, ChunkPos};
use voxel_mesh::{ChunkMeshes, PackedQuad};
use wgpu::util::DeviceExt;

use crate::GpuContext;
use crate::bindings::ChunkUniforms;

/// Which of a chunk's three meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshKind {
    /// Drawn in the opaque pass.
    Opaque = 0,
    /// Drawn in the cutout (alpha-tested) pass.
    Cutout = 1,
    /// Drawn by the transparency technique.
    Translucent = 2,
}

/// One mesh of one chunk on the GPU.
#[derive(Debug)]
pub struct GpuMesh {
    buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    quads: u32,
}

impl GpuMesh {
    /// The bind group (group 1: quads and chunk uniform) to draw this mesh with.
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// Number of quads (6 vertices each).
    pub fn quads(&self) -> u32 {
        self.quads
    }

    /// Records the draw of this mesh (pipeline and group 0 already set).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.draw(0..self.quads * 6, 0..1);
    }
}

/// A chunk's meshes and uniform on the GPU.
#[derive(Debug)]
pub struct GpuChunk {
    uniform: wgpu::Buffer,
    meshes: [Option<GpuMesh>; 3],
    /// The translucent quads in their current GPU order, kept for techniques that derive
    /// something from them (sorting, the fitted WBOIT weight).
    translucent: Vec<PackedQuad>,
    /// Changes with every upload of the chunk.
    generation: u64,
}

impl GpuChunk {
    /// The mesh of `kind`, if not empty.
    pub fn mesh(&self, kind: MeshKind) -> Option<&GpuMesh> {
        self.meshes[kind as usize].as_ref()
    }

    /// The translucent quads in their current GPU order.
    pub fn translucent_quads(&self) -> &[PackedQuad] {
        &self.translucent
    }

    /// A number that changes with every upload (remesh) of this chunk, never repeated by
    /// the store.
    pub fn generation(&self) -> u64 {
        self.generation
    }
}

/// A visible chunk mesh, with the view distance of the chunk's centre.
#[derive(Clone, Copy, Debug)]
pub struct Visible<'a> {
    /// Where the chunk is.
    pub pos: ChunkPos,
    /// The mesh to draw.
    pub mesh: &'a GpuMesh,
    /// Distance from the eye to the chunk's centre.
    pub distance: f64,
}

/// All chunks on the GPU.
#[derive(Debug)]
pub struct ChunkStore {
    layout: wgpu::BindGroupLayout,
    chunks: HashMap<ChunkPos, GpuChunk>,
    next_generation: u64,
}

impl ChunkStore {
    /// An empty store whose bind groups use `layout` (group 1 of
    /// [`crate::SharedLayouts`]).
    pub fn new(layout: wgpu::BindGroupLayout) -> Self {
        Self {
            layout,
            chunks: HashMap::new(),
            next_generation: 1,
        }
    }

    /// The layout of group 1.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Uploads (or replaces) a chunk's meshes. A chunk whose meshes are all empty is
    /// removed: no buffer and no draw exists for an empty mesh.
    pub fn upload(&mut self, ctx: &GpuContext, pos: ChunkPos, meshes: &ChunkMeshes) {
        if meshes.is_empty() {
            self.chunks.remove(&pos);
            return;
        }
        let origin = pos.origin().map(|v| v as i32);
        let uniform_data = ChunkUniforms { origin, alpha: 1.0 };
        let uniform = match self.chunks.remove(&pos) {
            Some(old) => {
                ctx.queue
                    .write_buffer(&old.uniform, 0, bytemuck::bytes_of(&uniform_data));
                old.uniform
            }
            None => ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("chunk_uniform"),
                    contents: bytemuck::bytes_of(&uniform_data),
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                }),
        };
        let make = |quads: &[PackedQuad], label| {
            (!quads.is_empty()).then(|| {
                let buffer = ctx
                    .device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: bytemuck::cast_slice(quads),
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    });
                let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(label),
                    layout: &self.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: buffer.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: uniform.as_entire_binding(),
                        },
                    ],
                });
                GpuMesh {
                    buffer,
                    bind_group,
                    quads: quads.len() as u32,
                }
            })
        };
        let chunk = GpuChunk {
            meshes: [
                make(&meshes.opaque, "chunk_opaque_quads"),
                make(&meshes.cutout, "chunk_cutout_quads"),
                make(&meshes.translucent, "chunk_translucent_quads"),
            ],
            translucent: meshes.translucent.clone(),
            uniform,
            generation: self.next_generation,
        };
        self.next_generation += 1;
        self.chunks.insert(pos, chunk);
    }

    /// Removes a chunk and frees its buffers.
    pub fn remove(&mut self, pos: ChunkPos) {
        self.chunks.remove(&pos);
    }

    /// Removes every chunk.
    pub fn clear(&mut self) {
        self.chunks.clear();
    }

    /// The chunk at `pos`, if uploaded.
    pub fn get(&self, pos: ChunkPos) -> Option<&GpuChunk> {
        self.chunks.get(&pos)
    }

    /// Number of chunks on the GPU.
    pub fn len(&self) -> usize {
        self.chunks.len()
    }

    /// Whether no chunk is on the GPU.
    pub fn is_empty(&self) -> bool {
        self.chunks.is_empty()
    }

    /// Rewrites a chunk's translucent quads in a new order (the same quads: a permutation
    /// of [`GpuChunk::translucent_quads`]), for sorting. The generation stays.
    pub fn reorder_translucent(&mut self, ctx: &GpuContext, pos: ChunkPos, quads: Vec<PackedQuad>) {
        let Some(c) = self.chunks.get_mut(&pos) else {
            return;
        };
        if let Some(mesh) = &c.meshes[MeshKind::Translucent as usize]
            && quads.len() == mesh.quads as usize
        {
            ctx.queue
                .write_buffer(&mesh.buffer, 0, bytemuck::cast_slice(&quads));
            c.translucent = quads;
        }
    }

    /// Sets a chunk's whole-chunk opacity (fade-in).
    pub fn set_alpha(&mut self, ctx: &GpuContext, pos: ChunkPos, alpha: f32) {
        if self.chunks.contains_key(&pos) {
            let origin = pos.origin().map(|v| v as i32);
            if let Some(c) = self.chunks.get(&pos) {
                let data = ChunkUniforms {
                    origin,
                    alpha: alpha.clamp(0.0, 1.0),
                };
                ctx.queue
                    .write_buffer(&c.uniform, 0, bytemuck::bytes_of(&data));
            }
        }
    }

    /// The meshes of `kind` of the chunks inside the view frustum, nearest first.
    pub fn visible(&self, kind: MeshKind, frustum: &Frustum) -> Vec<Visible<'_>> {
        let mut out: Vec<Visible<'_>> = self
            .chunks
            .iter()
            .filter_map(|(pos, c)| {
                let mesh = c.meshes[kind as usize].as_ref()?;
                frustum.chunk_distance(*pos).map(|distance| Visible {
                    pos: *pos,
                    mesh,
                    distance,
                })
            })
            .collect();
        out.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.pos.cmp(&b.pos)));
        out
    }
}

/// The six planes of a camera-relative view frustum, and the eye they are relative to.
#[derive(Clone, Debug)]
pub struct Frustum {
    planes: [Vec4; 6],
    eye: DVec3,
}

impl Frustum {
    /// From a camera-relative view-projection (clip z in [0, w], either direction).
    pub fn new(view_proj: Mat4, eye: DVec3) -> Self {
        let r = [
            view_proj.row(0),
            view_proj.row(1),
            view_proj.row(2),
            view_proj.row(3),
        ];
        let planes = [
            r[3] + r[0],
            r[3] - r[0],
            r[3] + r[1],
            r[3] - r[1],
            r[2],
            r[3] - r[2],
        ];
        Self { planes, eye }
    }

    /// Distance from the eye to the chunk's centre, or `None` when the chunk's box lies
    /// wholly outside one plane.
    pub fn chunk_distance(&self, pos: ChunkPos) -> Option<f64> {
        let s = CHUNK_SIZE as f64;
        let o = pos.origin();
        let min = DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) - self.eye;
        let lo = min.as_vec3();
        let hi = (min + DVec3::splat(s)).as_vec3();
        for p in &self.planes {
            let n = p.truncate();
            // The box corner farthest along the plane normal.
            let v = Vec3::select(n.cmpge(Vec3::ZERO), hi, lo);
            if n.dot(v) + p.w < 0.0 {
                return None;
            }
        }
        Some((min + DVec3::splat(s / 2.0)).length())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;

    #[test]
    fn frustum_keeps_chunks_in_view_and_drops_the_rest() {
        let cam = Camera::look_at(
            DVec3::new(16.0, 16.0, 100.0),
            DVec3::new(16.0, 16.0, 0.0),
            60.0,
            0.1,
            500.0,
        )
        .unwrap();
        let f = Frustum::new(cam.view_proj(1.0), cam.eye);
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 0)).is_some(),
            "straight ahead"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 5)).is_none(),
            "behind the eye"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(40, 0, 0)).is_none(),
            "far to the side"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, -20)).is_none(),
            "past the far plane"
        );
        assert!(
            f.chunk_distance(ChunkPos::new(0, 0, 3)).is_some(),
            "the eye's own chunk"
        );
    }
}
