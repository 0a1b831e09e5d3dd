//! A game's own page: what it shows ([`GamePage`]: its blocks, where the camera starts,
//! its things and what moves them each frame), handed to `voxel_web::run` (wasm32) from
//! the game's own crate, which then gets the page this crate's page is: WebGPU falling
//! back to WebGL2, a new device and renderer after a loss, the canvas following the
//! window, the technique picker and the fly camera (docs/browser.md, "A game's own page";
//! a template in `templates/web-game/`).
//!
//! ```no_run
//! use voxel_core::{BlockRegistry, TerrainConfig, TerrainGenerator};
//! use voxel_render::{Camera, ChunkStreamer, StreamConfig, content::Content};
//! use voxel_web::game::{Blocks, GamePage};
//! # fn page() -> Result<GamePage, Box<dyn std::error::Error>> {
//! let registry = std::sync::Arc::new(BlockRegistry::default());
//! let terrain = TerrainGenerator::new(TerrainConfig::default());
//! let config = StreamConfig { view_distance: 4, vertical_distance: 2, ..Default::default() };
//! // On wasm32 the streamer makes its chunks on the page's thread, within
//! // `config.local_budget` a frame.
//! let streamer = ChunkStreamer::new(registry, terrain, config)?;
//! let eye = glam::DVec3::new(0.0, 90.0, 0.0);
//! let camera = Camera::look_at(eye, eye + glam::DVec3::new(1.0, -0.3, 0.0), 70.0, 0.1, 600.0)?;
//! Ok(GamePage::new("my game", Blocks::Stream(Box::new(streamer)), camera)
//!     .with_content(Content::default())
//!     .on_frame(|tick, content| {
//!         // Move the things: return the new content, or None to keep it.
//!         let _ = (tick.seconds, content);
//!         None
//!     }))
//! # }
//! ```

use glam::DVec3;
use voxel_core::World;
use voxel_render::content::Content;
use voxel_render::{Camera, ChunkStreamer};

/// Where a page's blocks come from.
#[derive(Debug)]
pub enum Blocks {
    /// A whole world, meshed and uploaded before the first frame.
    World(World),
    /// Chunks streamed around the eye; on wasm32 made on the page's thread within its
    /// `StreamConfig::local_budget` each frame.
    Stream(Box<ChunkStreamer>),
}

impl Blocks {
    /// The resident world (all of it, or what the streamer holds).
    pub fn world(&self) -> &World {
        match self {
            Blocks::World(w) => w,
            Blocks::Stream(s) => s.world(),
        }
    }
}

/// What a frame's callback is told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tick {
    /// Seconds since the page started drawing.
    pub seconds: f64,
    /// Seconds since the last frame (at most 0.25).
    pub dt: f64,
    /// Where the camera is.
    pub eye: DVec3,
}

/// Called every frame with the tick and the things drawn now; returns new things, or
/// `None` to keep them.
pub type OnFrame = Box<dyn FnMut(Tick, &Content) -> Option<Content>>;

/// What a game's page shows.
pub struct GamePage {
    /// The page's title (the header and the tab).
    pub title: String,
    /// Its blocks.
    pub blocks: Blocks,
    /// Where the fly camera starts.
    pub camera: Camera,
    /// Its things (particles, boxes) at the start.
    pub content: Content,
    /// What moves them.
    pub on_frame: Option<OnFrame>,
    /// Whether a [`Blocks::World`] is drawn with its light field (`docs/light.md`): sky
    /// light through glass and water, torches. Default false.
    pub light: bool,
}

impl GamePage {
    /// A page of `blocks` seen from `camera`, with no things.
    pub fn new(title: impl Into<String>, blocks: Blocks, camera: Camera) -> Self {
        Self {
            title: title.into(),
            blocks,
            camera,
            content: Content::default(),
            on_frame: None,
            light: false,
        }
    }

    /// With its world drawn with its light field ([`GamePage::light`]).
    pub fn with_light(mut self, light: bool) -> Self {
        self.light = light;
        self
    }

    /// With `content` at the start.
    pub fn with_content(mut self, content: Content) -> Self {
        self.content = content;
        self
    }

    /// With `f` called every frame ([`OnFrame`]).
    pub fn on_frame(mut self, f: impl FnMut(Tick, &Content) -> Option<Content> + 'static) -> Self {
        self.on_frame = Some(Box::new(f));
        self
    }
}

impl std::fmt::Debug for GamePage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GamePage")
            .field("title", &self.title)
            .field("camera", &self.camera)
            .field("particles", &self.content.particles.len())
            .field("entities", &self.content.entities.len())
            .field("on_frame", &self.on_frame.is_some())
            .finish_non_exhaustive()
    }
}
