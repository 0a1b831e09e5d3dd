//! The render world: one `voxel_render::Renderer` on Bevy's device and queue, fed with the
//! chunks, technique, lighting and content the main world gathered, drawing each
//! [`crate::VoxelCamera`]'s view between Bevy's opaque and transparent passes.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::sync::Arc;
use std::sync::atomic::Ordering;

use bevy::app::App;
use bevy::core_pipeline::Core3d;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::ecs::prelude::*;
use bevy::render::renderer::{RenderAdapter, RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{ViewDepthStencilTexture, ViewTarget};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderSystems};
use voxel_core::BlockRegistry;
use voxel_render::content::ContentStages;
use voxel_render::{Both, GpuContext, Lighting, Renderer, RendererConfig, Technique};

use crate::composite::{BevyOpaque, Binding, BindingReads, Composite, depth_mapping};
use crate::{
    ChunkOp, ChunkQueue, Report, ReportQueue, VoxelFrame, VoxelMessage, VoxelPlugin, VoxelStatus,
    VoxelTechnique, drain, push,
};

/// The plugin's settings, in both worlds.
#[derive(Resource, Clone, Debug)]
pub(crate) struct PluginSettings {
    pub(crate) far: f64,
    pub(crate) renderer: RendererConfig,
}

/// The crate's renderer and what it draws with, in the render world.
#[derive(Resource, Default)]
struct VoxelRender {
    ctx: Option<GpuContext>,
    registry: Option<Arc<BlockRegistry>>,
    renderer: Option<Renderer>,
    content: Option<ContentStages>,
    composite: Option<Composite>,
    /// The request applied last (`None`: a new renderer applies it).
    technique: Option<VoxelTechnique>,
    lighting: Option<Lighting>,
    /// A frame is being counted (its figures are read at the next prepare).
    counting: bool,
    /// The generation of the content last handed to the content stages
    /// (`VoxelFrame::content_generation`: unchanged content is not handed again).
    content_generation: Option<u64>,
    /// The technique last reported in [`VoxelStatus`] (the status is reported when it
    /// changes).
    reported: Option<Technique>,
    /// Each camera's composite bind groups (by its main-world entity), kept while they
    /// read the same textures.
    bindings: HashMap<Entity, Binding>,
    /// A lit world's blocks, which the sun shadows follow the camera over.
    sun_world: Option<Arc<voxel_core::World>>,
}

pub(crate) fn build(app: &mut App, plugin: VoxelPlugin, chunks: ChunkQueue, reports: ReportQueue) {
    let settings = PluginSettings {
        far: plugin.far,
        renderer: plugin.renderer,
    };
    app.insert_resource(settings.clone());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .insert_resource(settings)
        .insert_resource(chunks)
        .insert_resource(reports)
        .init_resource::<VoxelFrame>()
        .init_resource::<VoxelRender>()
        .add_systems(ExtractSchedule, extract_frame)
        .add_systems(Render, prepare.in_set(RenderSystems::Prepare))
        .add_systems(
            Core3d,
            voxel_pass
                .after(main_opaque_pass_3d)
                .before(main_transparent_pass_3d),
        );
}

fn extract_frame(main: Extract<Res<VoxelFrame>>, mut frame: ResMut<VoxelFrame>) {
    frame.clone_from(&**main);
}

fn message(reports: &ReportQueue, m: VoxelMessage) {
    match &m {
        VoxelMessage::TechniqueChanged { requested, drawing } => {
            log::info!("voxel-bevy: {requested:?} draws as {}", drawing.name());
        }
        VoxelMessage::Unsupported { requested, reason } => {
            log::warn!("voxel-bevy: {requested:?} is not supported here: {reason}");
        }
        VoxelMessage::Error(e) => log::error!("voxel-bevy: {e}"),
    }
    push(&reports.queue, Report::Message(m));
}

/// Applies the chunk changes, the technique, the lighting and the content.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per resource
fn prepare(
    mut state: ResMut<VoxelRender>,
    frame: Res<VoxelFrame>,
    chunks: Res<ChunkQueue>,
    reports: Res<ReportQueue>,
    settings: Res<PluginSettings>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    adapter: Res<RenderAdapter>,
) {
    let state = &mut *state;
    let ctx = state.ctx.get_or_insert_with(|| {
        GpuContext::from_device(&adapter, device.wgpu_device().clone(), (**queue).clone())
    });
    let reports = &*reports;
    // A camera gone (or not drawn this frame) lets its textures go.
    state
        .bindings
        .retain(|camera, _| frame.cameras.contains_key(camera));
    for op in drain(&chunks.0) {
        match op {
            ChunkOp::Reset(registry) => {
                state.renderer = None;
                state.content = None;
                state.technique = None;
                state.lighting = None;
                state.content_generation = None;
                state.reported = None;
                state.sun_world = None;
                let config = RendererConfig {
                    width: 64,
                    height: 64,
                    ..settings.renderer.clone()
                };
                match Renderer::new(ctx, &registry, config) {
                    Ok(r) => {
                        match ContentStages::new(&r, Default::default()) {
                            Ok(c) => state.content = Some(c),
                            Err(e) => message(reports, VoxelMessage::Error(e.to_string())),
                        }
                        state.renderer = Some(r);
                    }
                    Err(e) => message(reports, VoxelMessage::Error(format!("renderer: {e}"))),
                }
                state.registry = Some(registry);
            }
            ChunkOp::Upload(pos, meshes) => {
                if let Some(r) = &mut state.renderer
                    && let Err(e) = r.upload_chunk(pos, &meshes)
                {
                    message(reports, VoxelMessage::Error(format!("chunk {pos:?}: {e}")));
                }
            }
            ChunkOp::Remove(pos) => {
                if let Some(r) = &mut state.renderer {
                    r.remove_chunk(pos);
                }
            }
            ChunkOp::Sun {
                world,
                changed,
                eye,
            } => {
                if let Some(r) = &mut state.renderer {
                    match changed {
                        Some(chunks) => r.update_sun_shadows(&world, &chunks),
                        None => {
                            let at = voxel_core::WorldPos::containing(eye.to_array());
                            if let Some(region) = voxel_render::SunRegion::around(&world, at)
                                && let Err(e) = r.set_sun_shadows(&world, region)
                            {
                                message(reports, VoxelMessage::Error(format!("sun shadows: {e}")));
                            }
                        }
                    }
                }
                state.sun_world = Some(world);
            }
        }
    }
    // The sun shadows follow the (first) camera.
    if let (Some(r), Some(w), Some(c)) = (
        &mut state.renderer,
        &state.sun_world,
        frame.cameras.values().next(),
    ) {
        r.follow_sun_shadows(w, voxel_core::WorldPos::containing(c.eye.to_array()));
    }
    let Some(renderer) = &mut state.renderer else {
        return;
    };
    let mut last_cost = None;
    if std::mem::take(&mut state.counting) {
        match voxel_render::low_level::frame_cost(renderer) {
            Ok(cost) => last_cost = cost,
            Err(e) => message(reports, VoxelMessage::Error(format!("frame cost: {e}"))),
        }
    }
    if frame.count {
        voxel_render::low_level::count_next_frame(renderer);
        state.counting = true;
    }
    if state.technique != Some(frame.technique) {
        let requested = frame.technique;
        state.technique = Some(requested);
        let wanted = match requested {
            VoxelTechnique::BestAvailable => Technique::best_available(&ctx.caps),
            VoxelTechnique::Use(t) if t.stalls() => Err(voxel_render::Error::Unsupported(format!(
                "{} waits for the GPU inside its frame, which Bevy submits after every camera \
                 is recorded; use one of Technique::REAL_TIME",
                t.name()
            ))),
            VoxelTechnique::Use(t) => Ok(t),
        };
        match wanted.and_then(|t| renderer.set_technique(t)) {
            Ok(drawing) => message(
                reports,
                VoxelMessage::TechniqueChanged { requested, drawing },
            ),
            Err(e) => message(
                reports,
                VoxelMessage::Unsupported {
                    requested,
                    reason: e.to_string(),
                },
            ),
        }
    }
    if let Some(l) = frame.lighting
        && state.lighting != Some(l)
    {
        state.lighting = Some(l);
        if let Err(e) = renderer.set_lighting(l) {
            message(reports, VoxelMessage::Error(format!("lighting: {e}")));
        }
    }
    if let Some(content) = &mut state.content
        && state.content_generation != Some(frame.content_generation)
    {
        // Content the crate refuses is reported once, not every frame until it changes.
        state.content_generation = Some(frame.content_generation);
        if let Err(e) = content.set_content(ctx, (*frame.content).clone()) {
            message(reports, VoxelMessage::Error(e.to_string()));
        }
    }
    let drawing = renderer.config().oit.technique;
    if last_cost.is_some() || state.reported != Some(drawing) {
        state.reported = Some(drawing);
        push(
            &reports.queue,
            Report::Status(VoxelStatus {
                drawing: Some(drawing),
                adapter: Some(ctx.caps.adapter_name.clone()),
                frames: reports.frames.load(Ordering::Relaxed),
                last_cost,
            }),
        );
    }
}

/// Draws the world into a [`crate::VoxelCamera`]'s view, after Bevy's opaque pass.
fn voxel_pass(
    view: ViewQuery<(&MainEntity, &ViewTarget, &ViewDepthStencilTexture)>,
    mut state: ResMut<VoxelRender>,
    frame: Res<VoxelFrame>,
    reports: Res<ReportQueue>,
    mut render_context: RenderContext,
) {
    let (main, target, depth) = view.into_inner();
    let Some(camera) = frame.cameras.get(&main.id()) else {
        return;
    };
    let state = &mut *state;
    let (Some(ctx), Some(renderer), Some(content)) =
        (&state.ctx, &mut state.renderer, &mut state.content)
    else {
        return;
    };
    let composite = state
        .composite
        .get_or_insert_with(|| Composite::new(&ctx.device));
    let color = target.main_texture();
    let size = (color.width(), color.height());
    if renderer.size() != size
        && let Err(e) = renderer.resize(size.0, size.1)
    {
        message(&reports, VoxelMessage::Error(format!("resize: {e}")));
        return;
    }
    if depth.texture().sample_count() != 1 {
        message(
            &reports,
            VoxelMessage::Error("the camera's depth is multisampled: set Msaa::Off".into()),
        );
        return;
    }
    let reads = BindingReads {
        bevy_color: (**target.main_texture_view()).clone(),
        bevy_depth: (**depth.texture()).clone(),
        scene_depth: renderer.scene_depth_view().clone(),
        mapping: depth_mapping(camera.near, camera.far),
        ldr: !matches!(
            target.main_texture_format(),
            wgpu::TextureFormat::Rgba16Float | wgpu::TextureFormat::Rgba32Float
        ),
    };
    // The bind groups are made again only when what they read changed.
    let binding = match state.bindings.entry(main.id()) {
        Entry::Occupied(e) if e.get().reads == reads => e.into_mut(),
        Entry::Occupied(mut e) => {
            e.insert(composite.binding(&ctx.device, reads));
            e.into_mut()
        }
        Entry::Vacant(e) => e.insert(composite.binding(&ctx.device, reads)),
    };
    let encoder: &mut wgpu::CommandEncoder = render_context.command_encoder();
    let color_view: &wgpu::TextureView = target.main_texture_view();
    let mut opaque = BevyOpaque::new(composite, &binding.into_world);
    let mut game = Both::new(&mut *content, &mut opaque);
    match renderer.render(encoder, color_view, camera, &mut game) {
        Ok(_) => {
            drop(game);
            let BevyOpaque { composite, .. } = opaque;
            // The frame may have made the scene's depth again (its first volume in view).
            if binding.reads.scene_depth != *renderer.scene_depth_view() {
                let reads = BindingReads {
                    scene_depth: renderer.scene_depth_view().clone(),
                    ..binding.reads.clone()
                };
                *binding = composite.binding(&ctx.device, reads);
            }
            composite.depth_into_bevy(encoder, &binding.bevy_depth, &binding.into_bevy);
            reports.frames.fetch_add(1, Ordering::Relaxed);
        }
        Err(e) => message(&reports, VoxelMessage::Error(format!("frame: {e}"))),
    }
}
