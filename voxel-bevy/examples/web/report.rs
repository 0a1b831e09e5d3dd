//! The page's reports for the browser test (voxel-bevy/tests/bevy_web.rs), with `?report=1`:
//! every 15 frames after the 10th it posts its state and the canvas's picture, read back
//! right after Bevy presented the frame (as web/'s page does: a 2D canvas draws it). Once two
//! pictures in a row are the same (the world, the cube and the things all drawn), it hides
//! the game's things (the glass box, the sparks, the Bevy cube) and reports until the
//! picture is steady again: the test compares the two. Errors logged (Bevy's, and the `log`
//! crate's: the plugin's, wgpu's) and a panic (a beacon) are posted too.

use std::collections::HashSet;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::{Arc, Mutex, PoisonError};

use bevy::camera::primitives::Aabb;
use bevy::log::LogPlugin;
use bevy::log::tracing::field::{Field, Visit};
use bevy::log::tracing::{Event, Level, Subscriber};
use bevy::log::tracing_subscriber::Layer;
use bevy::log::tracing_subscriber::layer::Context;
use bevy::prelude::*;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::{Render, RenderApp, RenderSystems};
use voxel_bevy::{VoxelCamera, VoxelMessage, VoxelShape, VoxelStatus, VoxelTranslucent};
use wasm_bindgen::{JsCast, JsValue};

/// Frames between reports.
const EVERY: u64 = 15;
/// The first report.
const FIRST: u64 = 10;

/// Errors logged (Bevy's, and the `log` crate's: the plugin's, wgpu's).
static ERRORS: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// A URL parameter of the page.
pub fn url_parameter(name: &str) -> Option<String> {
    let search = web_sys::window()?.location().search().ok()?;
    web_sys::UrlSearchParams::new_with_str(&search)
        .ok()?
        .get(name)
}

/// Bevy's log plugin (to the browser's console, the `log` crate's records included), with
/// the errors kept for the reports.
pub fn log_plugin() -> LogPlugin {
    LogPlugin {
        custom_layer: |_| Some(Box::new(KeepErrors)),
        ..default()
    }
}

/// The reports, with `?report=1`: the systems in both worlds and the panic beacon.
pub fn add(app: &mut App) {
    if url_parameter("report").as_deref() != Some("1") {
        return;
    }
    // After Bevy's log plugin set its own hook (the console): this one posts, then calls it.
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Some(w) = web_sys::window() {
            let _ = w
                .navigator()
                .send_beacon_with_opt_str("/panic", Some(&format!("panic: {info}")));
        }
        previous(info);
    }));
    let shared = Shared::default();
    app.insert_resource(shared.clone())
        .add_systems(Last, request);
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        // After the frame is presented (`RenderSystems::Render` submits and presents),
        // in the same task: the canvas still holds the frame.
        render_app
            .insert_resource(shared)
            .add_systems(Render, capture.after(RenderSystems::Render));
    }
}

/// The game's things the page removes: its translucent entities and Bevy meshes.
type GameThings = Or<(With<VoxelTranslucent>, With<Mesh3d>)>;

/// Where the page is: the game's things shown, hidden, or both pictures posted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Phase {
    #[default]
    With,
    Without,
    Done,
}

/// From the main world to the render world and back.
#[derive(Resource, Clone, Default)]
struct Shared(Arc<Mutex<State>>);

#[derive(Default)]
struct State {
    /// The state to post with the next frame's picture.
    request: Option<String>,
    /// The hash of the last picture posted.
    last: Option<u64>,
    /// The last picture was the one before it.
    steady: bool,
}

impl Shared {
    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// The main world's side: the state (frames, the plugin's status and messages, where the
/// glass box and the cube are on the canvas) asked to be posted every [`EVERY`] frames;
/// the things hidden once the picture with them is steady.
#[allow(clippy::too_many_arguments)] // a Bevy system: one parameter per query
fn request(
    shared: Res<Shared>,
    status: Res<VoxelStatus>,
    mut messages: MessageReader<VoxelMessage>,
    camera: Single<(&Camera, &GlobalTransform), With<VoxelCamera>>,
    boxes: Query<(&GlobalTransform, &VoxelTranslucent)>,
    meshes: Query<(&GlobalTransform, &Aabb), With<Mesh3d>>,
    things: Query<Entity, GameThings>,
    mut commands: Commands,
    mut frames: Local<u64>,
    mut phase: Local<Phase>,
    mut notes: Local<Vec<String>>,
) {
    *frames += 1;
    for m in messages.read() {
        if !matches!(m, VoxelMessage::TechniqueChanged { .. }) {
            notes.push(format!("{m:?}"));
        }
    }
    let mut sync = shared.lock();
    if sync.steady && *phase != Phase::Done {
        sync.steady = false;
        sync.last = None;
        if *phase == Phase::With {
            for e in &things {
                commands.entity(e).despawn();
            }
            *phase = Phase::Without;
        } else {
            *phase = Phase::Done;
        }
    }
    if *frames < FIRST || !(*frames - FIRST).is_multiple_of(EVERY) {
        return;
    }
    let (camera, eye) = *camera;
    // The rectangle of a box's corners on the canvas (pixels, y down).
    let rect = |at: &GlobalTransform, center: Vec3, half: Vec3| -> String {
        let mut lo = Vec2::splat(f32::MAX);
        let mut hi = Vec2::splat(f32::MIN);
        for i in 0..8 {
            let s = Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            if let Ok(p) = camera.world_to_viewport(eye, at.transform_point(center + s * half)) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        format!("{} {} {} {}", lo.x, lo.y, hi.x, hi.y)
    };
    let mut text = format!(
        "phase: {}\nframes: {}\nvoxel frames: {}\ntechnique: {}\nadapter: {}\n",
        match *phase {
            Phase::With => "with things",
            Phase::Without => "without things",
            Phase::Done => "done",
        },
        *frames,
        status.frames,
        status.drawing.map_or("none", |t| t.name()),
        status.adapter.as_deref().unwrap_or("none"),
    );
    for (at, thing) in &boxes {
        if let VoxelShape::Box { half_extents } = thing.shape {
            text += &format!("glass: {}\n", rect(at, Vec3::ZERO, half_extents.into()));
        }
    }
    for (at, aabb) in &meshes {
        let (center, half) = (aabb.center.into(), aabb.half_extents.into());
        text += &format!("cube: {}\n", rect(at, center, half));
    }
    let errors = ERRORS.lock().unwrap_or_else(PoisonError::into_inner);
    text += &format!("errors: {}\n", errors.len() + notes.len());
    for e in errors.iter().chain(notes.iter()) {
        text += &format!("error: {}\n", e.replace('\n', " "));
    }
    sync.request = Some(text);
}

/// The render world's side, after the frame is presented: the canvas's picture read back
/// and posted with the state asked for.
fn capture(shared: Res<Shared>, adapter: Res<RenderAdapterInfo>) {
    let mut sync = shared.lock();
    let Some(text) = sync.request.take() else {
        return;
    };
    let (colours, hash, picture) = canvas_picture().unwrap_or_default();
    sync.steady = sync.last == Some(hash) && colours > 0;
    sync.last = Some(hash);
    let body = format!(
        "{text}backend: {:?}\ncolours: {colours}\nsteady: {}\npicture: {picture}\n",
        adapter.backend, sync.steady
    );
    post("/status", &body);
}

/// Distinct colours of what the canvas shows, their hash and the picture as a PNG data URL
/// (drawn into a 2D canvas, as web/'s page reads its canvas).
fn canvas_picture() -> Option<(usize, u64, String)> {
    let document = web_sys::window()?.document()?;
    let canvas: web_sys::HtmlCanvasElement = document.get_element_by_id("view")?.dyn_into().ok()?;
    let copy: web_sys::HtmlCanvasElement =
        document.create_element("canvas").ok()?.dyn_into().ok()?;
    let (w, h) = (canvas.width(), canvas.height());
    copy.set_width(w);
    copy.set_height(h);
    let ctx: web_sys::CanvasRenderingContext2d = copy.get_context("2d").ok()??.dyn_into().ok()?;
    ctx.draw_image_with_html_canvas_element(&canvas, 0.0, 0.0)
        .ok()?;
    let data = ctx
        .get_image_data(0.0, 0.0, w.into(), h.into())
        .ok()?
        .data();
    let colours: HashSet<&[u8]> = data.chunks_exact(4).collect();
    let mut hasher = DefaultHasher::new();
    data.0.hash(&mut hasher);
    Some((colours.len(), hasher.finish(), copy.to_data_url().ok()?))
}

/// Posts `body` to `path` on the server that served the page (not waited for).
fn post(path: &str, body: &str) {
    let Some(window) = web_sys::window() else {
        return;
    };
    let init = web_sys::RequestInit::new();
    init.set_method("POST");
    init.set_body(&JsValue::from_str(body));
    let _ = window.fetch_with_str_and_init(path, &init);
}

/// Errors logged, kept for the reports: a layer of Bevy's log subscriber, which also
/// receives the `log` crate's records (the plugin's, wgpu's) and writes everything to the
/// browser's console.
struct KeepErrors;

impl<S: Subscriber> Layer<S> for KeepErrors {
    fn on_event(&self, event: &Event<'_>, _: Context<'_, S>) {
        if *event.metadata().level() != Level::ERROR {
            return;
        }
        let mut line = format!("{}:", event.metadata().target());
        event.record(&mut Fields(&mut line));
        ERRORS
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(line);
    }
}

/// An event's fields as text.
struct Fields<'a>(&'a mut String);

impl Visit for Fields<'_> {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            *self.0 += &format!(" {value:?}");
        } else {
            *self.0 += &format!(" {}={value:?}", field.name());
        }
    }
}
