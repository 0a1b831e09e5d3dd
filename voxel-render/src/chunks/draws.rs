//! A frame's draws: the runs of commands per page, the draw lists of the passes and the
//! builder that fills them with [`DrawCommand`]s.

#[cfg(doc)]
use super::Culled;
use super::DrawMode;
use super::command::DrawCommand;
use super::store::ChunkStore;
use crate::arena::Alloc;

/// A run of commands drawing from one page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    page: u32,
    first: u32,
    count: u32,
}

/// The draws of one pass: runs of commands in a frame's [`FrameDraws`].
#[derive(Clone, Debug, Default)]
pub(crate) struct DrawList {
    runs: Vec<Run>,
    meshes: usize,
    quads: u64,
}

impl DrawList {
    /// Whether it draws nothing.
    pub(crate) fn is_empty(&self) -> bool {
        self.meshes == 0
    }

    /// Meshes drawn.
    pub(crate) fn meshes(&self) -> usize {
        self.meshes
    }

    /// Quads drawn.
    pub(crate) fn quads(&self) -> u64 {
        self.quads
    }

    /// Draw calls it records: one per run of a page with indirect draws, one per mesh
    /// without.
    pub(crate) fn calls(&self, mode: DrawMode) -> usize {
        match mode {
            DrawMode::Indirect => self.runs.len(),
            DrawMode::PerChunk => self.meshes,
        }
    }
}

/// Every draw command of a frame, on the CPU and in the indirect buffer.
#[derive(Debug)]
pub(crate) struct FrameDraws<'a> {
    /// The store whose pages the commands draw from.
    pub store: &'a ChunkStore,
    /// The commands.
    pub commands: &'a [DrawCommand],
    /// How they are issued.
    pub mode: DrawMode,
}

impl FrameDraws<'_> {
    /// Records the draws of `list` (pipeline and group 0 already set; group 1 set here).
    pub(crate) fn draw(&self, list: &DrawList, pass: &mut crate::gpu::CountedPass<'_, '_>) {
        self.draw_range(list, 0..list.meshes, pass);
    }

    /// Records the draws of meshes `range` of `list` (in its order), like [`Self::draw`].
    pub(crate) fn draw_range(
        &self,
        list: &DrawList,
        range: std::ops::Range<usize>,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
    ) {
        let Some(base) = list.runs.first().map(|r| r.first as usize) else {
            return;
        };
        let (lo, hi) = (base + range.start, base + range.end.min(list.meshes));
        for run in &list.runs {
            let (first, end) = (run.first as usize, (run.first + run.count) as usize);
            let (a, b) = (first.max(lo), end.min(hi));
            if a >= b {
                continue;
            }
            let run = &Run {
                page: run.page,
                first: a as u32,
                count: (b - a) as u32,
            };
            if !self.store.bind_page(run.page, pass) {
                continue;
            }
            match self.mode {
                DrawMode::Indirect if self.store.fetch.indirect() => pass.multi_draw_indirect(
                    &self.store.indirect,
                    u64::from(run.first) * std::mem::size_of::<DrawCommand>() as u64,
                    run.count,
                ),
                _ => {
                    let cmds = &self.commands[run.first as usize..(run.first + run.count) as usize];
                    for c in cmds {
                        self.store.draw(run.page, c, 0..c.vertex_count / 6, pass);
                    }
                }
            }
        }
    }

    /// Draws quads `quads` (positions in the mesh's drawn order, clamped to it) of mesh
    /// `index` of `list`: part of a chunk, for objects drawn among its quads.
    pub(crate) fn draw_quads(
        &self,
        list: &DrawList,
        index: usize,
        quads: std::ops::Range<u32>,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
    ) {
        let Some(base) = list.runs.first().map(|r| r.first as usize) else {
            return;
        };
        if index >= list.meshes {
            return;
        }
        let at = (base + index) as u32;
        let Some(run) = list
            .runs
            .iter()
            .find(|r| (r.first..r.first + r.count).contains(&at))
        else {
            return;
        };
        let Some(c) = self.commands.get(at as usize) else {
            return;
        };
        let n = c.vertex_count / 6;
        let (a, b) = (quads.start.min(n), quads.end.min(n));
        if a >= b || !self.store.bind_page(run.page, pass) {
            return;
        }
        self.store.draw(run.page, c, a..b, pass);
    }
}

/// Builds a frame's draw lists: commands appended per list, runs split where the page
/// changes.
#[derive(Debug, Default)]
pub(crate) struct DrawBuilder {
    commands: Vec<DrawCommand>,
}

impl DrawBuilder {
    /// A list drawing `meshes` (slot and place of each, as [`Culled::meshes`] gives them),
    /// in order.
    pub(crate) fn list(&mut self, meshes: impl IntoIterator<Item = (u32, Alloc)>) -> DrawList {
        let mut list = DrawList::default();
        for (slot, mesh) in meshes {
            let index = self.commands.len() as u32;
            self.commands.push(DrawCommand {
                vertex_count: mesh.quads * 6,
                instance_count: 1,
                first_vertex: mesh.offset * 6,
                first_instance: slot,
            });
            match list.runs.last_mut() {
                Some(r) if r.page == mesh.page => r.count += 1,
                _ => list.runs.push(Run {
                    page: mesh.page,
                    first: index,
                    count: 1,
                }),
            }
            list.meshes += 1;
            list.quads += u64::from(mesh.quads);
        }
        list
    }

    /// Forgets the commands (keeping their room), for the next frame.
    pub(crate) fn clear(&mut self) {
        self.commands.clear();
    }

    /// The commands of every list, to be uploaded with [`ChunkStore::upload_draws`].
    pub(crate) fn commands(&self) -> &[DrawCommand] {
        &self.commands
    }
}
