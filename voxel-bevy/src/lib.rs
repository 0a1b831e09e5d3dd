//! A Bevy plugin for `voxel-render`: the voxel world drawn into Bevy cameras with the
//! selected transparency technique, on Bevy's own device and queue, composed with Bevy's
//! opaque meshes both ways and with a game's translucent entities in exact order.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use voxel_bevy::{VoxelCamera, VoxelPlugin, VoxelWorld};
//!
//! let world = VoxelWorld::generated(&voxel_core::TerrainGenerator::new(Default::default()), 2)
//!     .expect("terrain");
//! App::new()
//!     .add_plugins((DefaultPlugins, VoxelPlugin::default()))
//!     .insert_resource(world)
//!     .add_systems(Startup, |mut commands: Commands| {
//!         commands.spawn((Camera3d::default(), VoxelCamera, Transform::from_xyz(0.0, 40.0, 0.0)));
//!     })
//!     .run();
//! ```
//!
//! - [`VoxelPlugin`]: the settings (the renderer's [`RendererConfig`], the far plane).
//! - [`VoxelWorld`] (resource): the blocks, a fixed [`World`] (filled by the game or
//!   generated) or chunks streamed around the camera from a [`ChunkSource`];
//!   block edits and picking.
//! - [`VoxelCamera`] (component on a `Camera3d`): that camera's view gets the world.
//! - [`VoxelTechnique`], [`VoxelLighting`] (resources): what the game controls;
//!   [`VoxelStatus`] (resource) and [`VoxelMessage`] (messages) what comes back.
//! - [`VoxelTranslucent`], [`VoxelParticles`] (components): a game's translucent things
//!   drawn inside the technique's passes, ordered with water and glass.
//!
//! See `docs/bevy.md` for what is composed how, and what it costs.

mod composite;
mod render;

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use bevy::app::{App, Plugin, PostUpdate};
use bevy::camera::{Camera, Camera3d, Projection};
use bevy::color::Color;
use bevy::ecs::message::{Message, MessageWriter};
use bevy::ecs::prelude::*;
use bevy::math::Vec3 as BevyVec3;
use bevy::render::view::{DebandDither, Msaa, Tonemapping};
use bevy::transform::TransformSystems;
use bevy::transform::components::{GlobalTransform, Transform};
use glam::{DQuat, DVec3};
use voxel_core::{BlockId, BlockRegistry, ChunkPos, RayHit, RenderClass, World, WorldPos};
use voxel_mesh::ChunkMeshes;
use voxel_render::content::{Content, Entity as ContentEntity, Particle};
use voxel_render::{ChunkSink, ChunkSource, ChunkStreamer, StreamConfig};
use voxel_render::{Lighting, RendererConfig, Technique};

pub use voxel_render;

/// The plugin. Add it with a [`VoxelWorld`] resource and a [`VoxelCamera`] on a `Camera3d`.
#[derive(Clone, Debug)]
pub struct VoxelPlugin {
    /// The renderer's settings; `width` and `height` are ignored (each camera's target's
    /// size is followed), `oit.technique` is overridden by [`VoxelTechnique`].
    pub renderer: RendererConfig,
    /// The crate camera's far plane, in blocks (Bevy's projection has none): the world and
    /// Bevy's meshes beyond it are not drawn. Default 4 096.
    pub far: f64,
}

impl Default for VoxelPlugin {
    fn default() -> Self {
        Self {
            renderer: RendererConfig::default(),
            far: 4096.0,
        }
    }
}

/// Marks a `Camera3d` whose view gets the voxel world. The plugin turns the camera's MSAA off
/// (the frame reads Bevy's depth one sample a pixel), its tonemapping and deband dither off
/// (the crate's tonemap maps the composed frame; Bevy's would map it twice) and lets its
/// depth texture be read.
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct VoxelCamera;

/// The technique the game asks for. [`VoxelStatus::drawing`] says which draws (a device may
/// replace it), and a technique the device cannot run is a [`VoxelMessage::Unsupported`]
/// and a log line, the previous one drawing on.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VoxelTechnique {
    /// `Technique::best_available` on Bevy's device.
    #[default]
    BestAvailable,
    /// This technique (a real-time one: those that wait for the GPU inside a frame cannot
    /// run in Bevy's frame and are refused as unsupported).
    Use(Technique),
}

impl VoxelTechnique {
    /// The next of `Technique::REAL_TIME` (the first after `BestAvailable` or the last): what
    /// a key that cycles through the techniques sets.
    pub fn next(self) -> Self {
        let all = Technique::REAL_TIME;
        let i = match self {
            Self::Use(t) => all
                .iter()
                .position(|r| *r == t)
                .map_or(0, |i| (i + 1) % all.len()),
            Self::BestAvailable => 0,
        };
        Self::Use(all[i])
    }
}

/// The world's light (sun or moon, ambient, sky), e.g. `VoxelLighting(Lighting::daytime(20.0))`.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct VoxelLighting(pub Lighting);

impl Default for VoxelLighting {
    fn default() -> Self {
        Self(Lighting::default_day())
    }
}

/// What the render world reports back: `frames` every frame, the rest when it changes.
#[derive(Resource, Clone, Debug, Default)]
pub struct VoxelStatus {
    /// The technique drawing, once the renderer exists.
    pub drawing: Option<Technique>,
    /// The adapter Bevy renders with.
    pub adapter: Option<String>,
    /// Frames the plugin has drawn (all cameras).
    pub frames: u64,
    /// What the last frame counted ([`VoxelCountNextFrame`]) asked of the GPU: the crate's
    /// cost counters (draws, passes, fragments shaded where the device counts them).
    pub last_cost: Option<voxel_render::low_level::FrameCost>,
}

/// Set to `true` to count what the plugin's next frame asks of the GPU (the crate's cost
/// counters, `voxel_render::low_level::count_next_frame`); the figures arrive in
/// [`VoxelStatus::last_cost`] a frame or two later. The plugin sets it back to `false`.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VoxelCountNextFrame(pub bool);

/// What the plugin reports to the game (also logged).
#[derive(Message, Clone, Debug, PartialEq)]
pub enum VoxelMessage {
    /// The technique now drawing (the one asked for, or the device's replacement).
    TechniqueChanged {
        /// What [`VoxelTechnique`] asked for.
        requested: VoxelTechnique,
        /// What draws.
        drawing: Technique,
    },
    /// The device cannot run the technique asked for; the previous one draws on.
    Unsupported {
        /// What [`VoxelTechnique`] asked for.
        requested: VoxelTechnique,
        /// Why, from the renderer.
        reason: String,
    },
    /// Anything else that failed (a frame, content with a bad value, an upload): the
    /// renderer's error message.
    Error(String),
}

/// A game's translucent (or opaque) thing drawn by the crate: placed by the entity's
/// `GlobalTransform` (a box turns with it; scale multiplies its size), composed by every
/// technique inside its passes with water and glass.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[require(Transform)]
pub struct VoxelTranslucent {
    /// Its shape.
    pub shape: VoxelShape,
    /// Its colour (sRGB, as a colour picker shows it; alpha is ignored: see `opacity`).
    pub color: Color,
    /// Coverage, 0 to 1 (a box of 1 is opaque, drawn with the world's opaque geometry).
    pub opacity: f32,
    /// Its own light, times its colour (0 to `voxel_render::content::MAX_EMISSIVE`).
    pub emissive: f32,
}

impl VoxelTranslucent {
    /// A camera-facing particle `half_size` blocks across, no light of its own.
    pub fn particle(half_size: f32, color: Color, opacity: f32) -> Self {
        Self {
            shape: VoxelShape::Particle { half_size },
            color,
            opacity,
            emissive: 0.0,
        }
    }

    /// A box of `half_extents` (turned with the entity), no light of its own.
    pub fn cuboid(half_extents: [f32; 3], color: Color, opacity: f32) -> Self {
        Self {
            shape: VoxelShape::Box { half_extents },
            color,
            opacity,
            emissive: 0.0,
        }
    }

    /// The same with its own light, `emissive` times its colour.
    pub fn with_emissive(self, emissive: f32) -> Self {
        Self { emissive, ..self }
    }
}

/// The shape of a [`VoxelTranslucent`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VoxelShape {
    /// A camera-facing particle (a ball's look), half its size across.
    Particle {
        /// Half the side, in blocks.
        half_size: f32,
    },
    /// A box turned with the entity.
    Box {
        /// Half its extents along its own axes, in blocks.
        half_extents: [f32; 3],
    },
}

/// A cloud of particles placed by the entity's `GlobalTransform` (rain, bubbles, sparks):
/// each one's `center` is in the entity's space.
#[derive(Component, Clone, Debug, Default, PartialEq)]
#[require(Transform)]
pub struct VoxelParticles(pub Vec<Particle>);

/// A game's content as the crate takes it (particles and boxes in world coordinates, f64),
/// drawn with the [`VoxelTranslucent`] and [`VoxelParticles`] entities: for content the game
/// already builds as a `voxel_render::content::Content` (a scene file's, a particle system's).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct VoxelContent(pub Content);

/// Where the world's blocks come from.
#[allow(clippy::large_enum_variant)] // one per app: boxing the streamer saves nothing
enum Source {
    /// A world the game filled (or generated): meshed where it changes.
    Fixed(World),
    /// Chunks streamed around the first [`VoxelCamera`] (a mutex: the streamer's channel
    /// from its workers is not `Sync`, a Bevy resource must be).
    Streamed(Mutex<ChunkStreamer>),
}

/// The voxel world (resource): a fixed [`World`] or chunks streamed around the first
/// [`VoxelCamera`] by the crate's [`ChunkStreamer`]. Edits and picking go through it.
/// Inserting another `VoxelWorld` replaces the drawn world.
#[derive(Resource)]
pub struct VoxelWorld {
    source: Source,
    /// Every chunk is sent again (a new world).
    reset: bool,
    /// A fixed world drawn with its light ([`VoxelWorld::with_light`]).
    light: Option<LitWorld>,
}

/// A fixed world's light field, and whether the sun casts shadows.
struct LitWorld {
    field: voxel_core::LightField,
    sun_shadows: bool,
}

impl std::fmt::Debug for VoxelWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match &self.source {
            Source::Fixed(_) => "fixed",
            Source::Streamed(_) => "streamed",
        };
        f.debug_struct("VoxelWorld")
            .field("source", &kind)
            .field("chunks", &self.with_world(World::len))
            .finish()
    }
}

impl VoxelWorld {
    /// A world the game filled; chunks are meshed when it is inserted and again where edits
    /// change them.
    pub fn from_world(world: World) -> Self {
        Self {
            source: Source::Fixed(world),
            reset: true,
            light: None,
        }
    }

    /// Drawn with its light (`docs/light.md`): sky and block light through glass and water
    /// from a `LightField` lit now, meshed into every chunk, and the sun's shadows through
    /// them over the chunks nearest the first [`VoxelCamera`] (`Renderer::set_sun_shadows`,
    /// following the camera); edits ([`VoxelWorld::set_block`]) relight what they change.
    /// A streamed world is lit as it streams (`ChunkStreamer::set_light`: on the
    /// streamer's workers), without sun shadows.
    pub fn with_light(mut self) -> Self {
        match &mut self.source {
            Source::Fixed(w) => {
                self.light = Some(LitWorld {
                    field: voxel_core::LightField::new(w),
                    sun_shadows: true,
                });
            }
            Source::Streamed(s) => {
                s.get_mut()
                    .unwrap_or_else(PoisonError::into_inner)
                    .set_light(true);
            }
        }
        self
    }

    /// With light, no sun shadows: the sky light stands for the sun's.
    pub fn without_sun_shadows(mut self) -> Self {
        if let Some(l) = &mut self.light {
            l.sun_shadows = false;
        }
        self
    }

    /// The generator's terrain over the default registry, `radius` chunks around the origin
    /// horizontally (chunk rows -1 to 3 vertically).
    pub fn generated(
        generator: &voxel_core::TerrainGenerator,
        radius: i32,
    ) -> voxel_core::Result<Self> {
        let world = generator.generate_world(
            Arc::new(BlockRegistry::default()),
            ChunkPos::new(-radius, -1, -radius),
            ChunkPos::new(radius, 3, radius),
        )?;
        Ok(Self::from_world(world))
    }

    /// Chunks streamed from `source` around the first [`VoxelCamera`] (generated and meshed
    /// on the streamer's worker threads; on wasm32, which has none, on Bevy's thread in
    /// each update within `StreamConfig::local_budget`: see `voxel_render::ChunkStreamer`).
    pub fn streamed(
        registry: Arc<BlockRegistry>,
        source: impl ChunkSource,
        config: StreamConfig,
    ) -> voxel_render::Result<Self> {
        Ok(Self {
            source: Source::Streamed(Mutex::new(ChunkStreamer::new(registry, source, config)?)),
            reset: true,
            light: None,
        })
    }

    /// `f` of the blocks held (all of a fixed world; the resident chunks of a streamed one).
    pub fn with_world<R>(&self, f: impl FnOnce(&World) -> R) -> R {
        match &self.source {
            Source::Fixed(w) => f(w),
            Source::Streamed(s) => f(s.lock().unwrap_or_else(PoisonError::into_inner).world()),
        }
    }

    /// The blocks held (all of a fixed world; the resident chunks of a streamed one).
    pub fn world(&mut self) -> &World {
        match &mut self.source {
            Source::Fixed(w) => w,
            Source::Streamed(s) => s.get_mut().unwrap_or_else(PoisonError::into_inner).world(),
        }
    }

    /// The streamer, for a streamed world (its edits to save, its memory, whether it is idle).
    pub fn streamer(&mut self) -> Option<&mut ChunkStreamer> {
        match &mut self.source {
            Source::Streamed(s) => Some(s.get_mut().unwrap_or_else(PoisonError::into_inner)),
            Source::Fixed(_) => None,
        }
    }

    /// Sets a block (an edit: the chunks it touches are meshed again before the next frame
    /// of a fixed world, first thing for a streamed one); returns the block it replaced.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> voxel_render::Result<BlockId> {
        match &mut self.source {
            Source::Fixed(w) => match &mut self.light {
                Some(l) => Ok(l.field.set_block(w, pos, id)?),
                None => Ok(w.set_block(pos, id)?),
            },
            Source::Streamed(s) => s
                .get_mut()
                .unwrap_or_else(PoisonError::into_inner)
                .set_block(pos, id),
        }
    }

    /// The first visible block along a ray (picking): `RayHit::adjacent` is where a placed
    /// block goes. Errors on a non-finite or zero direction.
    pub fn raycast(
        &self,
        origin: DVec3,
        direction: DVec3,
        max_distance: f64,
    ) -> voxel_core::Result<Option<RayHit>> {
        self.with_world(|w| {
            w.raycast(
                origin.to_array(),
                direction.to_array(),
                max_distance,
                &RenderClass::VISIBLE,
            )
        })
    }
}

/// A chunk change on its way to the render world.
enum ChunkOp {
    /// A new world: drop every chunk, renderer over this registry.
    Reset(Arc<BlockRegistry>),
    Upload(ChunkPos, ChunkMeshes),
    Remove(ChunkPos),
    /// A lit world's blocks for the sun shadows: all of them over the chunks nearest `eye`
    /// (`changed` `None`), or again for the chunks `changed`.
    Sun {
        world: Arc<World>,
        changed: Option<Vec<ChunkPos>>,
        eye: DVec3,
    },
}

/// A queue shared by the main and render worlds (one per app, made by the plugin).
type Shared<T> = Arc<Mutex<Vec<T>>>;

fn push<T>(queue: &Shared<T>, item: T) {
    queue
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(item);
}

fn drain<T>(queue: &Shared<T>) -> Vec<T> {
    std::mem::take(&mut *queue.lock().unwrap_or_else(PoisonError::into_inner))
}

/// Chunk changes from the main world to the render world.
#[derive(Resource, Clone, Default)]
struct ChunkQueue(Shared<ChunkOp>);

/// Reports from the render world to the main world.
#[derive(Resource, Clone, Default)]
struct ReportQueue {
    /// Messages, and the status when it changes.
    queue: Shared<Report>,
    /// Frames drawn ([`VoxelStatus::frames`]): counted without a report each frame.
    frames: Arc<AtomicU64>,
}

enum Report {
    Message(VoxelMessage),
    Status(VoxelStatus),
}

struct QueueSink<'a>(&'a Shared<ChunkOp>);

impl ChunkSink for QueueSink<'_> {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> voxel_render::Result<()> {
        push(self.0, ChunkOp::Upload(pos, meshes.clone()));
        Ok(())
    }

    fn remove(&mut self, pos: ChunkPos) {
        push(self.0, ChunkOp::Remove(pos));
    }
}

/// What one frame draws, gathered in the main world and copied into the render world (a
/// cheap copy: the content is shared, rebuilt only when its sources change).
#[derive(Resource, Clone, Debug, Default)]
struct VoxelFrame {
    /// Per camera entity (main world): the crate's camera, or why there is none.
    cameras: HashMap<Entity, voxel_render::Camera>,
    /// The game's content: [`VoxelContent`] and the entities, in world coordinates.
    content: Arc<Content>,
    /// Counts the rebuilds of `content`: the render world hands the content to the crate
    /// again only when it differs from the generation it handed last.
    content_generation: u64,
    technique: VoxelTechnique,
    lighting: Option<Lighting>,
    count: bool,
}

impl Plugin for VoxelPlugin {
    fn build(&self, app: &mut App) {
        let chunks = ChunkQueue::default();
        let reports = ReportQueue::default();
        app.add_message::<VoxelMessage>()
            .init_resource::<VoxelTechnique>()
            .init_resource::<VoxelLighting>()
            .init_resource::<VoxelStatus>()
            .init_resource::<VoxelFrame>()
            .init_resource::<VoxelContent>()
            .init_resource::<VoxelCountNextFrame>()
            .insert_resource(chunks.clone())
            .insert_resource(reports.clone())
            .add_systems(
                PostUpdate,
                (
                    configure_cameras,
                    update_world,
                    gather_frame,
                    receive_reports,
                )
                    .chain()
                    .after(TransformSystems::Propagate),
            );
        render::build(app, self.clone(), chunks, reports);
    }
}

/// A new [`VoxelCamera`]: MSAA, tonemapping and dither off, its depth readable.
fn configure_cameras(
    mut commands: Commands,
    mut cameras: Query<(Entity, &mut Camera3d), Added<VoxelCamera>>,
) {
    for (entity, mut camera) in &mut cameras {
        let usages = wgpu::TextureUsages::from_bits_truncate(camera.depth_texture_usages.0)
            | wgpu::TextureUsages::TEXTURE_BINDING;
        camera.depth_texture_usages = usages.into();
        commands
            .entity(entity)
            .insert((Msaa::Off, Tonemapping::None, DebandDither::Disabled));
    }
}

/// Meshes a fixed world's changed chunks, or streams around the first camera.
fn update_world(
    world: Option<ResMut<VoxelWorld>>,
    cameras: Query<&GlobalTransform, With<VoxelCamera>>,
    queue: Res<ChunkQueue>,
    mut messages: MessageWriter<VoxelMessage>,
) {
    let Some(mut world) = world else {
        return;
    };
    let world = &mut *world;
    let reset = world.reset;
    if world.reset {
        world.reset = false;
        push(&queue.0, ChunkOp::Reset(world.world().registry().clone()));
        if let Source::Fixed(w) = &mut world.source {
            let all: Vec<ChunkPos> = w.iter().map(|(p, _)| p).collect();
            for p in all {
                w.mark_dirty(p);
            }
        }
    }
    let eye = cameras.iter().next().map(|t| dvec3(t.translation()));
    match &mut world.source {
        Source::Fixed(w) => {
            if w.dirty().is_empty() {
                return;
            }
            let meshed = match &mut world.light {
                Some(l) => voxel_mesh::mesh_dirty_lit(w, &mut l.field),
                None => voxel_mesh::mesh_dirty(w),
            };
            match meshed {
                Ok(meshes) => {
                    let changed: Vec<ChunkPos> = meshes.iter().map(|(p, _)| *p).collect();
                    for (pos, m) in meshes {
                        push(&queue.0, ChunkOp::Upload(pos, m));
                    }
                    if world.light.as_ref().is_some_and(|l| l.sun_shadows) {
                        push(
                            &queue.0,
                            ChunkOp::Sun {
                                world: Arc::new(w.clone()),
                                changed: (!reset).then_some(changed),
                                eye: eye.unwrap_or(DVec3::ZERO),
                            },
                        );
                    }
                }
                Err(e) => report_error(&mut messages, format!("meshing: {e}")),
            }
        }
        Source::Streamed(s) => {
            let Some(eye) = eye else {
                return;
            };
            let s = s.get_mut().unwrap_or_else(PoisonError::into_inner);
            if let Err(e) = s.update(eye, &mut QueueSink(&queue.0)) {
                report_error(&mut messages, format!("streaming: {e}"));
            }
        }
    }
}

fn report_error(messages: &mut MessageWriter<VoxelMessage>, e: String) {
    log::error!("voxel-bevy: {e}");
    messages.write(VoxelMessage::Error(e));
}

/// Bevy's vector (Bevy's glam) as the crate's.
pub fn dvec3(v: BevyVec3) -> DVec3 {
    DVec3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// Linear f32 colour to the sRGB bytes the content takes.
fn srgb_bytes(c: Color) -> [u8; 3] {
    let s = c.to_srgba();
    [s.red, s.green, s.blue].map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// The crate's camera for a Bevy camera: Bevy's transform and perspective (its near plane and
/// vertical field of view), the plugin's far plane, the medium the eye is in.
pub fn crate_camera(
    transform: &GlobalTransform,
    projection: &Projection,
    far: f64,
    world: Option<&World>,
) -> Result<voxel_render::Camera, String> {
    let Projection::Perspective(p) = projection else {
        return Err("only perspective cameras are drawn".into());
    };
    let eye = dvec3(transform.translation());
    let forward = dvec3(*transform.forward());
    let camera = voxel_render::Camera {
        eye,
        forward,
        fov_y_deg: f64::from(p.fov).to_degrees(),
        near: f64::from(p.near),
        far,
        medium: world.and_then(|w| w.medium_at(eye.to_array())),
    };
    camera.validate().map_err(|e| e.to_string())?;
    Ok(camera)
}

/// Whether the Bevy camera's up is the crate camera's (no roll): the crate's camera keeps
/// world up, so a rolled Bevy camera would not line up with the world.
fn rolled(transform: &GlobalTransform) -> bool {
    let f = dvec3(*transform.forward());
    let up_hint = if f.y.abs() > 0.999 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    let right = f.cross(up_hint).normalize();
    let up = right.cross(f);
    dvec3(*transform.up()).dot(up) < 0.9999
}

#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per query and resource
fn gather_frame(
    settings: Res<render::PluginSettings>,
    world: Option<Res<VoxelWorld>>,
    cameras: Query<(Entity, &GlobalTransform, &Projection, &Camera), With<VoxelCamera>>,
    things: Query<(Ref<GlobalTransform>, Ref<VoxelTranslucent>)>,
    clouds: Query<(Ref<GlobalTransform>, Ref<VoxelParticles>)>,
    technique: Res<VoxelTechnique>,
    lighting: Res<VoxelLighting>,
    extra: Res<VoxelContent>,
    mut count: ResMut<VoxelCountNextFrame>,
    mut frame: ResMut<VoxelFrame>,
    mut warned: Local<bool>,
    mut gathered: Local<Option<(usize, usize)>>,
    mut messages: MessageWriter<VoxelMessage>,
) {
    let frame = &mut *frame;
    frame.cameras.clear();
    for (entity, transform, projection, camera) in &cameras {
        if !camera.is_active {
            continue;
        }
        let camera = match &world {
            Some(w) => w.with_world(|w| crate_camera(transform, projection, settings.far, Some(w))),
            None => crate_camera(transform, projection, settings.far, None),
        };
        match camera {
            Ok(c) => {
                if rolled(transform) && !*warned {
                    *warned = true;
                    log::warn!(
                        "voxel-bevy: camera {entity} is rolled; the world is drawn with world up"
                    );
                }
                frame.cameras.insert(entity, c);
            }
            Err(e) if !*warned => {
                *warned = true;
                report_error(&mut messages, format!("camera {entity}: {e}"));
            }
            Err(_) => {}
        }
    }
    // The content is rebuilt only when something it is made of changed: the resource, an
    // entity's component or transform (`Ref::is_changed` is also true for one just added),
    // or the number of entities (one removed or despawned).
    let counts = (things.iter().count(), clouds.iter().count());
    let changed = extra.is_changed()
        || *gathered != Some(counts)
        || things
            .iter()
            .any(|(t, thing)| t.is_changed() || thing.is_changed())
        || clouds
            .iter()
            .any(|(t, cloud)| t.is_changed() || cloud.is_changed());
    if changed {
        *gathered = Some(counts);
        frame.content = Arc::new(gather_content(&extra.0, &things, &clouds));
        frame.content_generation += 1;
    }
    frame.count = std::mem::take(&mut count.0);
    frame.technique = *technique;
    frame.lighting = Some(lighting.0);
}

/// The game's content: `extra` and the entities' things, in world coordinates.
fn gather_content(
    extra: &Content,
    things: &Query<(Ref<GlobalTransform>, Ref<VoxelTranslucent>)>,
    clouds: &Query<(Ref<GlobalTransform>, Ref<VoxelParticles>)>,
) -> Content {
    let mut content = extra.clone();
    for (transform, thing) in things {
        let (scale, rotation, center) = transform.to_scale_rotation_translation();
        let center = dvec3(center);
        let color = srgb_bytes(thing.color);
        match thing.shape {
            VoxelShape::Particle { half_size } => content.particles.push(Particle {
                center,
                half_size: half_size * scale.abs().max_element(),
                color,
                opacity: thing.opacity,
                emissive: thing.emissive,
            }),
            VoxelShape::Box { half_extents } => content.entities.push(ContentEntity {
                center,
                half_extents: [
                    half_extents[0] * scale.x.abs(),
                    half_extents[1] * scale.y.abs(),
                    half_extents[2] * scale.z.abs(),
                ],
                rotation: DQuat::from_xyzw(
                    f64::from(rotation.x),
                    f64::from(rotation.y),
                    f64::from(rotation.z),
                    f64::from(rotation.w),
                )
                .normalize(),
                color,
                opacity: thing.opacity,
                emissive: thing.emissive,
            }),
        }
    }
    for (transform, cloud) in clouds {
        let affine = transform.affine();
        let scale = transform.scale().abs().max_element();
        content.particles.extend(cloud.0.iter().map(|p| Particle {
            center: dvec3(affine.transform_point3(BevyVec3::new(
                p.center.x as f32,
                p.center.y as f32,
                p.center.z as f32,
            ))),
            half_size: p.half_size * scale,
            ..*p
        }));
    }
    content
}

fn receive_reports(
    reports: Res<ReportQueue>,
    mut status: ResMut<VoxelStatus>,
    mut messages: MessageWriter<VoxelMessage>,
) {
    let frames = reports.frames.load(Ordering::Relaxed);
    if status.frames != frames {
        status.frames = frames;
    }
    for r in drain(&reports.queue) {
        match r {
            Report::Message(m) => {
                messages.write(m);
            }
            Report::Status(s) => {
                let cost = s.last_cost.clone().or_else(|| status.last_cost.take());
                *status = VoxelStatus {
                    last_cost: cost,
                    frames,
                    ..s
                };
            }
        }
    }
}
