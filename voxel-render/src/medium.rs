//! Translucent volumes seen from inside: under water, inside glass.
//!
//! **The model.** Along a view ray, a translucent block type counts once each time the ray
//! passes through a volume of it. From outside, the ray meets the volume's entry face: a
//! face seen from its front (the mesher emits every face of a translucent block toward air,
//! cutout blocks and other translucent types; back faces are culled). From inside the
//! volume that holds the eye (the camera's [`medium`](crate::Camera::medium)), the eye is
//! already in it: that passage counts at its exit face, the first surface of the medium's
//! type the ray meets, seen from behind. Later surfaces of the same type are entries (front
//! faces, counted) and exits of other passages (back faces, not counted). Where the medium
//! meets another translucent type, the crossing counts once, at the other type's entry face
//! (the medium's face there carries the mesher's interface flag and does not count): the
//! two faces lie at one depth, which depth peeling could not keep apart. With the eye in
//! air nothing of this applies and every picture is what it was.
//!
//! **Volumes.** A translucent block type with absorption `σ`
//! ([`voxel_core::BlockDef::absorption`]; the built-in water's 16 blocks dim as much as
//! one water surface, [`voxel_core::WATER_ABSORPTION`]) is a volume: along a path of `d`
//! blocks inside it, what lies beyond keeps `exp(−σ d)` of its light and takes the
//! block's colour, lit like a face turned to the sky, for the rest. A block type without
//! absorption (glass) is a thin surface seen from outside; inside one the eye sees the fog
//! every translucent block had before volumes existed: 16 blocks of it dim as much as one of
//! its surfaces ([`voxel_core::BlockDef::eye_absorption`]), so that a game's own water keeps
//! its look without being made a volume.
//!
//! **The path, for the real-time techniques** (`shaders/path.wgsl`). Per pixel the frame
//! knows three stretches of medium along the ray: the eye's own medium up to its boundary;
//! the nearest volume entered beyond it (`volume_entry` and its look, a depth pass of the
//! volumes' front faces) up to where volumes end (`volume_depth`: the nearest back face of a
//! volume, or the opaque surface); and the nearest volume entered beyond that end
//! (`volume_entry2`) up to the farthest back face of a volume beyond it (`volume_far`) or the
//! opaque surface. The exit passes draw the quads grown (a sliver where merged quads meet
//! must not leave a way out open). A full-screen media pass lays the whole path over the
//! opaque picture before the technique draws; every translucent fragment takes the part of
//! the path in front of it (`fogged`), so that the blend of the layers in order is the path
//! split at every layer, for any number of things inside the water. The passes run only when
//! a volume is in view or the eye is in an absorbing medium.
//!
//! **The exact references** walk the media from the eye along their sorted fragments and need
//! only the opaque depth, plus (grown) the nearest back face of a volume, where a medium
//! still open after their last fragment ends.
//!
//! **The boundary.** With the eye inside a medium, a depth pass over the visible translucent
//! meshes keeps, per pixel, the nearest surface of the medium's type (both sides) in front
//! of the opaque depth. The technique draws both sides of translucent faces (its two-sided
//! pipeline variant) and each fragment asks `counts()` in `common.wgsl`: front faces count; a
//! back face counts when it is of the medium's type, not an interface, and at exactly that
//! first depth (positions are `@invariant`, so the depths are bit-identical). No quad is
//! added: the cost is paid only under water. A face of the medium toward a cutout block
//! lies in the plane of that block's face; where the cutout texel is solid the boundary pass
//! leaves the tie to the opaque surface (within 1/16384 of its depth), as an opaque block
//! hides the medium's face: the passage ends there; through a hole in the texel the face is
//! the way out. A waterlogged block holds its medium (the mesher draws no face of the medium
//! toward it).
//!
//! **Crossing a surface.** The near plane would cut away a translucent face closer to the
//! eye than it (the surface the eye is passing through), so that a band of the picture
//! lost it. [`guard`] shrinks the near plane for that frame until the face lies beyond the
//! near plane's corners, and, when the eye is within [`crate::MIN_NEAR`] of the face, moves
//! the eye that far off it, to the side its medium says it is on.

use glam::DVec3;
use voxel_core::{BlockId, BlockRegistry, CHUNK_SIZE, ChunkPos, RenderClass};

use crate::bindings::SharedLayouts;
use crate::camera::MIN_NEAR;
use crate::chunks::{ChunkStore, DrawList, FrameDraws, MeshKind};
use crate::gpu::{self, ChunkPipeline, Depth, DepthMode, FullscreenPipeline, Pass, Target};
use crate::timing::{GpuPass, Timer};
use crate::{Camera, GpuContext};

/// What the renderer needs of a block type to treat it as a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MediumLook {
    /// Linear base colour.
    pub color: [f32; 3],
    /// Opacity of one layer.
    pub opacity: f32,
    /// Absorption per block of the volume ([`voxel_core::BlockDef::absorption`]; 0: a
    /// thin surface).
    pub absorption: f32,
    /// Absorption per block of the fog an eye inside it sees
    /// ([`voxel_core::BlockDef::eye_absorption`]: a volume's absorption, or a thin
    /// block's fog).
    pub fog: f32,
}

/// The look of every translucent block type, by block id (`None`: not translucent).
pub(crate) fn looks(registry: &BlockRegistry) -> Vec<Option<MediumLook>> {
    let linear = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    registry
        .iter()
        .map(|(_, def)| {
            (def.class == RenderClass::Translucent).then(|| MediumLook {
                color: def.color.map(linear),
                opacity: def.opacity,
                absorption: def.absorption,
                fog: def.eye_absorption(),
            })
        })
        .collect()
}

/// The boundary pass's shader (after the shared chunk code).
pub(crate) fn boundary_wgsl() -> String {
    crate::bindings::common_wgsl() + include_str!("shaders/medium_boundary.wgsl")
}

/// The volume exit pass's shader.
pub(crate) fn volume_exit_wgsl() -> String {
    crate::bindings::common_wgsl() + include_str!("shaders/volume_exit.wgsl")
}

/// The media pass's shader (after `fullscreen.wgsl`): the scene group as group 0, the
/// volume and path functions.
pub(crate) fn media_wgsl() -> String {
    gpu::WgslConsts::default()
        .u32("NO_MEDIUM", crate::bindings::NO_MEDIUM)
        .u32("FLAG_INTERFACE", crate::bindings::FLAG_INTERFACE)
        .finish()
        + &crate::bindings::frame_wgsl()
        + gpu::DEPTH_UV_WGSL
        + "@group(0) @binding(0) var<uniform> frame: Frame;\n\
           @group(0) @binding(3) var medium_boundary: texture_2d<f32>;\n\
           @group(0) @binding(6) var depth_sampler: sampler;\n\
           @group(0) @binding(7) var volume_depth: texture_2d<f32>;\n\
           @group(0) @binding(9) var volume_entry: texture_2d<f32>;\n\
           @group(0) @binding(10) var entry_look: texture_2d<f32>;\n\
           @group(0) @binding(11) var opaque_copy: texture_2d<f32>;\n\
           @group(0) @binding(12) var volume_far: texture_2d<f32>;\n\
           @group(0) @binding(13) var volume_entry2: texture_2d<f32>;\n\
           @group(0) @binding(14) var entry2_look: texture_2d<f32>;\n\n\
           fn boundary_depth(xy: vec2<f32>) -> f32 {\n    \
           return depth_at(medium_boundary, xy);\n}\n\n"
        + crate::bindings::VOLUME_WGSL
        + crate::bindings::PATH_WGSL
        + include_str!("shaders/media.wgsl")
}

/// The format of the nearest volume entry's look (linear colour, absorption).
pub(crate) const ENTRY_LOOK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The pipelines of the two passes a frame inside a medium adds.
#[derive(Debug)]
pub(crate) struct MediumPass {
    boundary: wgpu::RenderPipeline,
    /// The nearest back face of a volume in front of the opaque surface (`volume_exit.wgsl`).
    volume_exit: wgpu::RenderPipeline,
    /// The nearest front face of a volume and its look (`volume_exit.wgsl`).
    volume_entry: wgpu::RenderPipeline,
    /// The farthest back face of a volume (`volume_exit.wgsl`).
    volume_far: wgpu::RenderPipeline,
    /// The nearest entry beyond where the nearest volume ends (`volume_exit.wgsl`).
    volume_entry2: wgpu::RenderPipeline,
    /// The media over the opaque picture (`media.wgsl`), with the scene group.
    media: wgpu::RenderPipeline,
    /// Copies the opaque depth into the boundary and the volume depths.
    depth_copy: gpu::DepthCopy,
}

impl MediumPass {
    /// Creates the pipelines.
    pub(crate) fn new(ctx: &GpuContext, layouts: &SharedLayouts) -> Self {
        let device = &ctx.device;
        let module = gpu::shader(device, "medium_boundary", &[&boundary_wgsl()]);
        let groups = layouts.with(&[]);
        // Both sides, nearest kept and written: the depth of the first surface.
        let boundary = ChunkPipeline {
            label: "medium_boundary",
            module: &module,
            fragment_entry: "fs_boundary",
            groups: &groups,
            targets: &[],
            depth: DepthMode::Write,
            samples: 1,
        }
        .build_two_sided(device);
        let exit_module = gpu::shader(device, "volume_exit", &[&volume_exit_wgsl()]);
        let look = [Some(wgpu::ColorTargetState {
            format: ENTRY_LOOK_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        // The volumes' pipelines: entry points of `volume_exit.wgsl`, writing the entry's
        // look or no colour.
        let volume =
            |label: &'static str, fragment_entry: &'static str, writes_look, depth| ChunkPipeline {
                label,
                module: &exit_module,
                fragment_entry,
                groups: &groups,
                targets: if writes_look { &look[..] } else { &[] },
                depth,
                samples: 1,
            };
        let volume_exit = volume("volume_exit", "fs_volume_exit", false, DepthMode::Write)
            .build_two_sided_solid(device);
        let volume_far = volume(
            "volume_far",
            "fs_volume_far",
            false,
            DepthMode::WriteFarthest,
        )
        .build_two_sided_solid(device);
        let volume_entry2 = volume("volume_entry2", "fs_volume_entry2", true, DepthMode::Write)
            .build_two_sided(device);
        let volume_entry = volume("volume_entry", "fs_volume_entry", true, DepthMode::Write)
            .build_two_sided(device);
        let media = FullscreenPipeline {
            label: "media",
            source: &media_wgsl(),
            fragment_entry: "fs_media",
            groups: &[Some(&layouts.scene)],
            targets: &[gpu::scene_target(Some(
                wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
            ))],
            writes_depth: false,
            constants: &[],
        }
        .build(device);
        Self {
            boundary,
            volume_exit,
            volume_entry,
            volume_far,
            volume_entry2,
            media,
            depth_copy: gpu::DepthCopy::new(ctx),
        }
    }

    /// Writes into `boundary` the depth of the first surface of the medium (the frame's
    /// `medium`) in front of `opaque_depth`, per pixel. `scene` is group 0 without the
    /// boundary in it (the pass writes it).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn boundary_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        opaque_depth: &Target,
        boundary: &Target,
        scene: &wgpu::BindGroup,
        draws: &FrameDraws<'_>,
        chunks: &DrawList,
        timer: Option<&Timer>,
    ) {
        self.depth_copy
            .record(encoder, opaque_depth, boundary, GpuPass::Medium, timer);
        let faces = (scene, draws, chunks);
        nearest_faces(
            encoder,
            "medium_boundary",
            &self.boundary,
            boundary,
            &[],
            faces,
            timer,
        );
    }

    /// Writes `volume_depth`, what volumes read (`common.wgsl`): the opaque depth, and
    /// with `exits` (the translucent chunks to draw, and group 0 with the opaque depth in
    /// `volume_depth`'s place) the nearest back face of a volume in front of it, where the
    /// techniques that compose a volume at its entry face end it. The exact references,
    /// which see every face, take the opaque depth alone. After the boundary pass.
    pub(crate) fn volume_depth_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        opaque_depth: &Target,
        volume_depth: &Target,
        exits: Option<(&wgpu::BindGroup, &FrameDraws<'_>, &DrawList)>,
        timer: Option<&Timer>,
    ) {
        self.depth_copy
            .record(encoder, opaque_depth, volume_depth, GpuPass::Medium, timer);
        if let Some(faces) = exits {
            nearest_faces(
                encoder,
                "volume_exit",
                &self.volume_exit,
                volume_depth,
                &[],
                faces,
                timer,
            );
        }
    }

    /// Writes into `entry_depth` and `entry_look` the nearest front face of a volume in
    /// front of `opaque_depth` and its medium's look (`scene`: group 0 with the opaque depth
    /// in `volume_entry`'s place), and a copy of the opaque depth into `opaque_copy`. After
    /// [`Self::volume_depth_pass`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn volume_entry_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        opaque_depth: &Target,
        (entry_depth, entry_look, opaque_copy): (&Target, &Target, &Target),
        scene: &wgpu::BindGroup,
        draws: &FrameDraws<'_>,
        chunks: &DrawList,
        timer: Option<&Timer>,
    ) {
        self.depth_copy
            .record(encoder, opaque_depth, opaque_copy, GpuPass::Medium, timer);
        self.entry_faces(
            encoder,
            ("volume_entry", &self.volume_entry),
            opaque_depth,
            (entry_depth, entry_look),
            (scene, draws, chunks),
            timer,
        );
    }

    /// Writes into `entry_depth` and `entry_look` the nearest front face of a volume beyond
    /// where the nearest volume ends (`volume_depth`) and beyond its entry, in front of
    /// `opaque_depth`, and its medium's look (`scene`: group 0 with the opaque depth in
    /// `volume_entry2`'s place). After [`Self::volume_entry_pass`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn volume_entry2_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        opaque_depth: &Target,
        (entry_depth, entry_look): (&Target, &Target),
        scene: &wgpu::BindGroup,
        draws: &FrameDraws<'_>,
        chunks: &DrawList,
        timer: Option<&Timer>,
    ) {
        self.entry_faces(
            encoder,
            ("volume_entry2", &self.volume_entry2),
            opaque_depth,
            (entry_depth, entry_look),
            (scene, draws, chunks),
            timer,
        );
    }

    /// The body of the two entry passes: `entry_depth` starts as the opaque depth, and
    /// `pipeline` writes the nearest front face it keeps and its medium's look.
    fn entry_faces(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (label, pipeline): (&str, &wgpu::RenderPipeline),
        opaque_depth: &Target,
        (entry_depth, entry_look): (&Target, &Target),
        faces: (&wgpu::BindGroup, &FrameDraws<'_>, &DrawList),
        timer: Option<&Timer>,
    ) {
        self.depth_copy
            .record(encoder, opaque_depth, entry_depth, GpuPass::Medium, timer);
        let colors = [gpu::clear(&entry_look.view, wgpu::Color::TRANSPARENT)];
        nearest_faces(encoder, label, pipeline, entry_depth, &colors, faces, timer);
    }

    /// Writes into `far` the farthest back face of a volume in front of the opaque surface
    /// (1, the near plane, where there is none; `scene`: group 0 with the opaque depth in
    /// `volume_far`'s place). After [`Self::volume_entry_pass`], which copies the opaque
    /// depth the pass reads.
    pub(crate) fn volume_far_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        far: &Target,
        scene: &wgpu::BindGroup,
        draws: &FrameDraws<'_>,
        chunks: &DrawList,
        timer: Option<&Timer>,
    ) {
        Pass::new("volume_far", GpuPass::Medium, &[])
            .depth(Depth::Clear(&far.view, 1.0))
            .record(encoder, timer, |pass| {
                pass.set_pipeline(&self.volume_far);
                pass.set_bind_group(0, scene, &[]);
                draws.draw(chunks, pass);
            });
    }

    /// Blends over `target` (the opaque picture) the media in front of it: the eye's
    /// medium up to its boundary and the nearest volume (`scene`: the scene group, after
    /// the boundary and volume passes).
    pub(crate) fn media_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &Target,
        scene: &wgpu::BindGroup,
        timer: Option<&Timer>,
    ) {
        let colors = [gpu::load(&target.view)];
        Pass::new("media", GpuPass::Medium, &colors).record(encoder, timer, |pass| {
            pass.set_pipeline(&self.media);
            pass.set_bind_group(0, scene, &[]);
            pass.draw_full_screen();
        });
    }
}

/// The medium's depth passes: `chunks` drawn with `pipeline` (group 0 `scene`) into
/// `depth`, which holds a copy of the opaque depth, the nearest fragment kept, with
/// `colors` beside.
fn nearest_faces(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::RenderPipeline,
    depth: &Target,
    colors: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    (scene, draws, chunks): (&wgpu::BindGroup, &FrameDraws<'_>, &DrawList),
    timer: Option<&Timer>,
) {
    Pass::new(label, GpuPass::Medium, colors)
        .depth(Depth::Load(&depth.view))
        .record(encoder, timer, |pass| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, scene, &[]);
            draws.draw(chunks, pass);
        });
}

/// How far the corners of the near plane are from the eye, per unit of near distance.
fn corner_factor(camera: &Camera, aspect: f64) -> f64 {
    let t = (camera.fov_y_deg.to_radians() / 2.0).tan();
    (1.0 + t * t * (1.0 + aspect * aspect)).sqrt()
}

/// A translucent quad's plane near the eye.
#[derive(Clone, Copy, Debug)]
struct NearFace {
    /// Distance from the eye to the quad.
    distance: f64,
    /// The plane's normal axis.
    axis: usize,
    /// The plane's coordinate on that axis.
    plane: f64,
    /// Whether the quad's block lies on the plane's low side (a + face).
    block_below: bool,
    /// The quad's block.
    block: BlockId,
}

/// The translucent quads within `reach` of `eye`.
fn translucent_near(chunks: &ChunkStore, eye: DVec3, reach: f64) -> Vec<NearFace> {
    let s = CHUNK_SIZE as f64;
    let lo = ((eye - reach) / s).floor();
    let hi = ((eye + reach) / s).floor();
    let mut near = Vec::new();
    for cx in lo.x as i64..=hi.x as i64 {
        for cy in lo.y as i64..=hi.y as i64 {
            for cz in lo.z as i64..=hi.z as i64 {
                let [Ok(x), Ok(y), Ok(z)] = [cx, cy, cz].map(i32::try_from) else {
                    continue;
                };
                let pos = ChunkPos::new(x, y, z);
                let Some(chunk) = chunks.get(pos) else {
                    continue;
                };
                if chunk.mesh(MeshKind::Translucent).is_none() {
                    continue;
                }
                let o = DVec3::from(pos.origin().map(|v| v as f64));
                let scale = DVec3::from(chunk.scale());
                for q in chunk.translucent_quads() {
                    let Some(u) = q.unpack() else { continue };
                    let axis = u.face.axis();
                    let (min, max) = u.bounds();
                    let (min, max) = (DVec3::from(min) * scale + o, DVec3::from(max) * scale + o);
                    let distance = (eye.clamp(min, max) - eye).length();
                    if distance <= reach {
                        // A +face's block lies below its plane, a -face's above.
                        near.push(NearFace {
                            distance,
                            axis,
                            plane: min[axis],
                            block_below: u.face.is_positive(),
                            block: u.block,
                        });
                    }
                }
            }
        }
    }
    near
}

/// `camera` for this frame, kept from cutting away a translucent face with its near plane
/// (see the module docs): the near plane shrunk until the nearest translucent face lies
/// beyond its corners, and an eye within [`MIN_NEAR`] of faces moved off each of their
/// planes (off both at an edge, all three at a corner) to the side of its medium.
/// Unchanged when no translucent face is that close. The result does not depend on the
/// order the quads are stored in (sorting rewrites it).
pub(crate) fn guard(camera: &Camera, aspect: f64, chunks: &ChunkStore) -> Camera {
    let corner = corner_factor(camera, aspect);
    let reach = camera.near * corner;
    let mut near = translucent_near(chunks, camera.eye, reach);
    if near.is_empty() {
        return *camera;
    }
    let mut c = *camera;
    // The closest the eye may be to a face: twice the smallest near plane's corners.
    let keep = 2.0 * MIN_NEAR * corner;
    // One move per axis; where faces disagree (never, when the medium is the block at the
    // eye), the same one wins whatever their order.
    near.sort_by(|a, b| {
        (a.axis, a.block_below, a.block.index())
            .cmp(&(b.axis, b.block_below, b.block.index()))
            .then(a.plane.total_cmp(&b.plane))
    });
    let mut moved = [false; 3];
    for f in near.iter().filter(|f| f.distance < keep) {
        if !std::mem::replace(&mut moved[f.axis], true) {
            // Which side of the plane: the block's when the eye is inside that block
            // type, else the other.
            let inside = camera.medium == Some(f.block);
            let up = inside != f.block_below;
            c.eye[f.axis] = f.plane + if up { keep } else { -keep };
        }
    }
    let d = if moved.contains(&true) {
        translucent_near(chunks, c.eye, reach)
            .iter()
            .map(|f| f.distance)
            .fold(reach, f64::min)
    } else {
        near.iter().map(|f| f.distance).fold(reach, f64::min)
    };
    c.near = (0.5 * d / corner).clamp(MIN_NEAR, camera.near);
    c
}
