//! One indirect draw command: what the store uploads and a frame's draw lists hold.

use bytemuck::{Pod, Zeroable};

#[cfg(doc)]
use crate::QuadFetch;

/// One draw command, as `multi_draw_indirect` reads it with [`QuadFetch::Storage`] (with
/// [`QuadFetch::Instanced`] each is a direct draw of its own).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct DrawCommand {
    /// Vertices: 6 per quad.
    pub vertex_count: u32,
    /// Always 1.
    pub instance_count: u32,
    /// The mesh's first quad in its page, times 6.
    pub first_vertex: u32,
    /// The chunk's slot.
    pub first_instance: u32,
}
