//! The frame's stages a game joins, in the shape of egui-wgpu's paint callbacks and glyphon's
//! "render into the caller's pass": the game's own opaque geometry after the world's opaque
//! passes, its translucent geometry composed by the active transparency technique together
//! with the chunks, an HDR overlay before tonemapping and an overlay after it.
//!
//! A game implements [`GameStages`] and passes it to `Renderer::render`. The renderer
//! calls [`GameStages::prepare`] once the frame's camera is known (write uniforms there,
//! with [`GameFrame::write_buffer`]), then records each stage the game declared
//! ([`GameStages::stages`]) into a pass it opens.
//!
//! **Translucent geometry, the same for every technique.** The game's fragment shader ends
//! with `return oit_output(in.position, color);` after a prelude the renderer gives
//! ([`TranslucentVariant::wgsl`], like Bevy's `oit_draw`): it turns a linear colour and
//! opacity into whatever the technique's pass writes (weighted sums, a stipple test, a
//! peel layer, an A-buffer node, a blended colour). A technique draws in several passes, each a
//! [`TranslucentVariant`] with its own prelude, colour targets, depth state and bind group
//! layout at [`OIT_GROUP`]; the game builds one pipeline per variant of the
//! [`TranslucentContract`] in force and rebuilds them when its `id` changes (a technique
//! switch, or settings its pipelines depend on), before the frame or in
//! [`GameStages::follow_contract`] (the `content` module is such a game, ready-made). The
//! renderer binds its group at [`OIT_GROUP`] before calling [`GameStages::translucent`];
//! the game sets its pipeline and its own groups (0 to `OIT_GROUP - 1`).

use std::ops::Range;
use std::sync::{Mutex, PoisonError};

use glam::{DVec3, Mat4, Vec3};

use crate::submission::FrameWrites;
use crate::{Camera, Error, GpuContext, Result};

pub use crate::gpu::{
    Depth, Target, bind_group, load, overlay_depth, overlay_pipeline, shader, target,
};

/// The bind group index the renderer reserves in a game's translucent pipelines (the last
/// of the four every adapter offers): the game's own groups are 0, 1 and 2.
pub const OIT_GROUP: u32 = 3;

/// Which stages a game draws in this frame; a stage it leaves out costs nothing (no pass).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stages {
    /// Opaque geometry into the scene colour (linear HDR) and depth, after the world's
    /// opaque and cutout passes (before translucency, so water and glass are seen over it).
    pub opaque: bool,
    /// Translucent geometry, composed with the chunks by the active technique.
    pub translucent: bool,
    /// An overlay into the HDR scene colour (linear) with the scene depth (read-only) after
    /// translucency and fog, before tonemapping: a selection box.
    pub hdr_overlay: bool,
    /// An overlay into the output after tonemapping: a HUD. Its one colour target is the
    /// view the frame renders into, in that view's format ([`GameFrame::output_format`],
    /// one of `OUTPUT_FORMATS`; it changes only when the game renders into another view),
    /// single-sampled and without depth: the game builds its overlay pipelines for it.
    /// Colours written there are stored as the view's format stores them: an sRGB view
    /// takes linear colour (the GPU encodes it); a linear 8- or 10-bit view takes
    /// sRGB-encoded colour, as the tonemap writes there, to show the same.
    pub overlay: bool,
}

/// A translucent thing a game draws, as the sorted techniques order it: a ball around it,
/// and where known the axis-aligned box around it, placed among the chunks by where it
/// lies against their translucent quads and back to front by its centre among the other
/// objects (the sorted techniques' module docs say where that is exact). Order-independent
/// techniques ignore it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TranslucentObject {
    /// Centre, in world blocks.
    pub center: DVec3,
    /// Radius of a ball around the centre holding all of it, blocks (0: order it as a
    /// point).
    pub radius: f64,
    /// Half the sides of an axis-aligned box around the centre holding all of it, blocks,
    /// when known (`None`: only the ball). The object lies in both: a flat slab over water
    /// whose ball reaches through the surface is still wholly on one side of it.
    pub half_extents: Option<DVec3>,
}

impl TranslucentObject {
    /// An object known by a ball around it.
    pub fn ball(center: DVec3, radius: f64) -> Self {
        Self {
            center,
            radius,
            half_extents: None,
        }
    }

    /// An object known by an axis-aligned box around it (`center` ± `half_extents`), and
    /// the ball around that box.
    pub fn aabb(center: DVec3, half_extents: DVec3) -> Self {
        let half = half_extents.abs();
        Self {
            center,
            radius: half.length(),
            half_extents: Some(half),
        }
    }
}

/// Where a run of objects is drawn: after quads `..quad` of chunk `chunk` (its position
/// in the draw order; quad 0: before the chunk; past the last chunk: after every chunk),
/// the objects at positions `start..end` of the order, clipped by the frame's clip `clip`
/// (0: not clipped; the parts of an object cut at planes it reaches through), made by the
/// sorted techniques (`oit::sorted::interleave`). The runs are drawn in turn; each
/// position is in one run per part of its object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Split {
    /// The chunk, by its position in the draw order.
    pub chunk: u32,
    /// How many of its quads (in their drawn order) come before the objects.
    pub quad: u32,
    /// The first position of the order drawn here.
    pub start: u32,
    /// The position after the last one drawn here.
    pub end: u32,
    /// The clip of the run's parts (an index into the frame's clips; 0: none).
    pub clip: u32,
}

/// A plane a part of an object is cut at, and which side of it the part keeps: the world
/// coordinate `at` along `axis`, the part on the eye's side (`far` false: there and in the
/// plane itself, the rule for equal depths) or beyond it (`far`: strictly beyond).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClipPlane {
    /// The axis (0 x, 1 y, 2 z).
    pub axis: usize,
    /// Where the plane lies on it, world blocks.
    pub at: f64,
    /// Which side of it the eye is on: +1 above `at`, -1 below.
    pub eye_side: f64,
    /// The part keeps what lies beyond the plane (else the eye's side and the plane).
    pub far: bool,
}

/// The planes a part of an object is clipped by (none: the whole object; the sorted
/// techniques' order, `oit::sorted::interleave`).
pub(crate) type Clip = Vec<ClipPlane>;

/// What a game needs to draw in a stage.
#[derive(Debug)]
pub struct GameFrame<'a> {
    /// The camera the frame is drawn with (`Renderer::drawn_camera`: an eye on a
    /// translucent face moved off it, the near plane shrunk in front of one).
    pub camera: &'a Camera,
    /// Camera-relative view × reverse-Z projection: a world point `p` goes to clip space
    /// as `view_proj * vec4((p_int - eye_int) + (p_frac - eye_frac), 1)`, integer parts
    /// first so that precision does not depend on where the camera is.
    pub view_proj: Mat4,
    /// Integer part of the eye (`floor`).
    pub eye_int: [i64; 3],
    /// Fractional part of the eye, in [0, 1).
    pub eye_frac: Vec3,
    /// Render size in pixels.
    pub size: (u32, u32),
    /// Samples of the opaque stage's targets (4 with MSAA, else 1); every other stage
    /// draws single-sampled.
    pub opaque_samples: u32,
    /// Format of the output (the overlay stage's target).
    pub output_format: wgpu::TextureFormat,
    /// The lighting in force, to light the game's things as the world is lit: the unit
    /// direction towards the sun (or moon), the ambient share, and the brightness every
    /// lit colour is scaled by (`Lighting`): a face of normal `n` and linear colour `c` is
    /// `c * brightness * (ambient + (1 - ambient) * max(dot(n, sun_dir), 0))`.
    pub sun_dir: Vec3,
    /// The ambient share, 0 to 1 (see `sun_dir`).
    pub ambient: f32,
    /// The light's brightness, 1 by day (see `sun_dir`).
    pub brightness: f32,
    /// Sorted techniques: the game's translucent objects back to front (indices into
    /// [`GameStages::translucent_objects`], each once, never more than the objects);
    /// `None` when the technique does not sort. A game drawing instances uploads them in
    /// this order in `prepare`: instance buffers sized for its objects hold it. An object
    /// `sorted-quads` cuts into parts is at its first part's position, and
    /// [`GameStages::translucent`] draws that position once per part.
    pub order: Option<&'a [u32]>,
    /// The light volume's group (`Renderer::light_layout`), for the game's shaders to read
    /// the light field around the eye with [`light_wgsl`](crate::light_volume::light_wgsl)'s functions; always there
    /// to bind (without a volume they give the light of a world drawn unlit).
    pub light: &'a wgpu::BindGroup,
    /// The writes [`GameFrame::write_buffer`] gathers in `prepare`.
    pub(crate) writes: &'a GameWrites,
}

/// The writes a game makes in [`GameStages::prepare`] ([`GameFrame::write_buffer`]):
/// open until the renderer takes them, after `prepare`, to record into the frame's
/// encoder.
#[derive(Debug)]
pub(crate) struct GameWrites(Mutex<Option<FrameWrites>>);

impl GameWrites {
    /// Open for a frame's `prepare`.
    pub(crate) fn open() -> Self {
        Self(Mutex::new(Some(FrameWrites::default())))
    }

    /// What was written; later writes are refused.
    pub(crate) fn take(&self) -> FrameWrites {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
            .unwrap_or_default()
    }
}

impl GameFrame<'_> {
    /// Writes `data` into `buffer` at `offset` where this frame's commands are: a copy
    /// recorded into the frame's encoder before its first pass. `Queue::write_buffer`
    /// lands at the next submit instead, before every command of it, so a game that
    /// records two frames before one submit and writes its uniforms with it draws both
    /// with the second's; written here, each frame draws with its own. Call it in
    /// [`GameStages::prepare`].
    ///
    /// As for `Queue::write_buffer`, `buffer` needs `COPY_DST` usage and `offset` and the
    /// length are multiples of 4 ([`wgpu::COPY_BUFFER_ALIGNMENT`]) within the buffer;
    /// otherwise, or after `prepare` has returned, it is an `Error::BufferWrite` and
    /// nothing is written. An empty `data` writes nothing.
    pub fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) -> Result<()> {
        let align = wgpu::COPY_BUFFER_ALIGNMENT;
        let len = data.len() as u64;
        let bad = |why: String| Err(Error::BufferWrite(why));
        if !buffer.usage().contains(wgpu::BufferUsages::COPY_DST) {
            return bad(format!(
                "the buffer has no COPY_DST usage ({:?})",
                buffer.usage()
            ));
        }
        if !offset.is_multiple_of(align) || !len.is_multiple_of(align) {
            return bad(format!(
                "offset {offset} and length {len}: both must be multiples of {align}"
            ));
        }
        if offset
            .checked_add(len)
            .is_none_or(|end| end > buffer.size())
        {
            return bad(format!(
                "{len} bytes at offset {offset} end past the buffer's {} bytes",
                buffer.size()
            ));
        }
        match self
            .writes
            .0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .as_mut()
        {
            Some(writes) => {
                writes.write(buffer, offset, data);
                Ok(())
            }
            None => bad(
                "after GameStages::prepare: the frame's writes are recorded by then (write in \
                 prepare)"
                    .into(),
            ),
        }
    }

    /// The camera-relative position of a world point (what `view_proj` takes).
    pub fn relative(&self, p: DVec3) -> Vec3 {
        let i = self.eye_int.map(|v| v as f64);
        Vec3::new(
            (p.x - i[0]) as f32,
            (p.y - i[1]) as f32,
            (p.z - i[2]) as f32,
        ) - self.eye_frac
    }
}

/// The rule for equal depths between a game's translucent object and a block's face (foam
/// lying in a water surface, a decal on a pane): the object is on the eye's side of the
/// face, in front of it, seen from either side. The exact methods compare an object's
/// fragment at its depth times `1 + OBJECT_DEPTH_BIAS` (reverse-Z: a little nearer, 32
/// steps of a 32-bit float) and the lab's ray march an object's hit at its distance times
/// `1 - OBJECT_DEPTH_BIAS`, so they agree on which is in front instead of each breaking the
/// tie its own way; the sorted techniques draw such an object after the face (the order of
/// `interleave`), and the weighted ones do not order. Surfaces farther apart than that
/// (about 4e-4 blocks at a distance of 100) are ordered by where they are. An object lying
/// in an *opaque* face's plane z-fights with it in every real-time technique (its
/// fragments and the face's are depth-tested): offset such decals.
pub const OBJECT_DEPTH_BIAS: f32 = 1.0 / 262_144.0;

/// Depth convention of every stage: 32-bit float, reverse-Z (1 at the near plane, 0 far),
/// nearer passes with `Greater`.
pub const DEPTH_COMPARE: wgpu::CompareFunction = wgpu::CompareFunction::Greater;

/// One pass of the active technique as a game's translucent pipeline must match it.
#[derive(Clone, Debug)]
pub struct TranslucentVariant {
    /// Which pass (for labels and logs): `"wboit_accumulate_mrt"`, `"peel_front"`, …
    pub name: &'static str,
    /// WGSL to put before the game's fragment shader: declares `OitOutput` and
    /// `fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput` (position the
    /// fragment's `@builtin(position)`, colour linear and straight, alpha its opacity), and
    /// the bindings of group [`OIT_GROUP`]. The names it declares besides those two start
    /// with `oit_` or belong to the technique (`params`, `frame`, `heads`, …): keep the
    /// game's own names apart.
    pub wgsl: String,
    /// The pass's colour targets, blend states included.
    pub targets: Vec<Option<wgpu::ColorTargetState>>,
    /// The pass's depth state (format [`crate::DEPTH_FORMAT`]).
    pub depth_stencil: wgpu::DepthStencilState,
    /// The layout of the group the renderer binds at [`OIT_GROUP`].
    pub layout: wgpu::BindGroupLayout,
}

/// Every pass of the active technique a game's translucent geometry is drawn in.
#[derive(Clone, Debug)]
pub struct TranslucentContract {
    /// Changes whenever the variants do: a game rebuilds its pipelines then. The same
    /// technique with the same settings keeps its id on a renderer (switching away and
    /// back, pipelines built for it are still right). Ids are unique in the process: no
    /// two renderers give out the same one, so pipelines built for another renderer (whose
    /// group layouts are its own) are refused, never drawn with. The game tells the
    /// renderer which id its pipelines were built for
    /// ([`GameStages::translucent_contract_id`]).
    pub id: u64,
    /// The name of the technique in force (`Technique::name`).
    pub technique: &'static str,
    /// One per pass kind; [`GameStages::translucent`] gets the index of the one in use.
    pub variants: Vec<TranslucentVariant>,
}

/// A game's part of a frame. Every method has an empty default; [`GameStages::stages`]
/// says which are used.
pub trait GameStages {
    /// Which stages the game draws this frame.
    fn stages(&self) -> Stages;

    /// The context the game's resources were made on, when it keeps one (default: `None`,
    /// not checked). A frame whose game names a context of another device than the
    /// renderer's ([`GpuContext::same_device`]) is refused with `Error::OtherDevice` before
    /// anything is recorded: its pipelines and buffers cannot be used there.
    fn context(&self) -> Option<&GpuContext> {
        None
    }

    /// The translucent things it draws, for the sorted techniques' order (default: none,
    /// drawn after the chunks, in one call).
    fn translucent_objects(&self) -> &[TranslucentObject] {
        &[]
    }

    /// The [`TranslucentContract::id`] its translucent pipelines were built for. A frame
    /// whose game declares the translucent stage with another id (or none: the default)
    /// is refused before anything is recorded (`Error::StaleContract`): its pipelines
    /// would not match the technique's passes.
    fn translucent_contract_id(&self) -> Option<u64> {
        None
    }

    /// Called at the start of every frame that declares the translucent stage, with the
    /// contract in force, before [`GameStages::translucent_contract_id`] is checked: a game
    /// that builds its translucent pipelines by itself builds them here when it has none
    /// for `contract.id` (`content::ContentStages` does). The default does nothing: the
    /// game built them before the frame.
    fn follow_contract(&mut self, _ctx: &GpuContext, _contract: &TranslucentContract) {}

    /// Before any pass is recorded: write uniforms and instance buffers (`frame.order`
    /// gives the sorted order when the technique sorts) with
    /// [`GameFrame::write_buffer`], which lands in this frame's encoder (a frame recorded
    /// before this one and not yet submitted keeps what it wrote).
    fn prepare(&mut self, _ctx: &GpuContext, _frame: &GameFrame<'_>) {}

    /// Opaque geometry, into the scene colour ([`crate::SCENE_FORMAT`], linear HDR) and depth
    /// ([`crate::DEPTH_FORMAT`], reverse-Z, test `Greater` and write) with
    /// `frame.opaque_samples` samples.
    fn opaque(&self, _pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {}

    /// Translucent geometry in one pass of the technique: set the pipeline built for
    /// `contract.variants[variant]` (group [`OIT_GROUP`] is bound) and draw the objects of
    /// `objects` — positions in `frame.order` for a sorted technique, else indices into
    /// [`GameStages::translucent_objects`] — or everything when there are none. A sorted
    /// technique asks for the ranges in its draw order, not in increasing order, and may
    /// ask for a position again (the parts of an object cut where it reaches through a
    /// plane, each drawn with its own clip).
    fn translucent(
        &self,
        _pass: &mut wgpu::RenderPass<'_>,
        _frame: &GameFrame<'_>,
        _variant: usize,
        _objects: Range<usize>,
    ) {
    }

    /// An overlay into the HDR scene colour (linear) with the scene depth, read-only.
    fn hdr_overlay(&self, _pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {}

    /// An overlay into the output (format `frame.output_format`), no depth.
    fn overlay(&self, _pass: &mut wgpu::RenderPass<'_>, _frame: &GameFrame<'_>) {}
}

/// No game stage: what `Renderer::render` draws with.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoGame;

impl GameStages for NoGame {
    fn stages(&self) -> Stages {
        Stages::default()
    }
}

/// A game's stages borrowed: `Both::new(&mut content, &mut own)` keeps both where the game
/// keeps them.
impl<T: GameStages + ?Sized> GameStages for &mut T {
    fn stages(&self) -> Stages {
        (**self).stages()
    }
    fn context(&self) -> Option<&GpuContext> {
        (**self).context()
    }
    fn translucent_objects(&self) -> &[TranslucentObject] {
        (**self).translucent_objects()
    }
    fn translucent_contract_id(&self) -> Option<u64> {
        (**self).translucent_contract_id()
    }
    fn follow_contract(&mut self, ctx: &GpuContext, contract: &TranslucentContract) {
        (**self).follow_contract(ctx, contract);
    }
    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        (**self).prepare(ctx, frame);
    }
    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        (**self).opaque(pass, frame);
    }
    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &GameFrame<'_>,
        variant: usize,
        objects: Range<usize>,
    ) {
        (**self).translucent(pass, frame, variant, objects);
    }
    fn hdr_overlay(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        (**self).hdr_overlay(pass, frame);
    }
    fn overlay(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        (**self).overlay(pass, frame);
    }
}

/// Two games' stages drawn as one frame's game: the ready-made content beside a game's
/// own stages (its own translucent shader, its overlays), or any two. Each stage draws
/// `first`'s part, then `second`'s. Their translucent objects are one list (`first`'s, then
/// `second`'s) that the sorted techniques order together: each part uploads its own
/// objects in its share of that order (its [`GameFrame::order`] holds indices into its own
/// objects) and draws its own runs of it, so things of both are blended back to front with
/// each other and the chunks. A part that declares the translucent stage with no objects
/// is drawn after the last object (as the renderer draws a game without objects). Each
/// part follows or checks the technique's contract as it would alone: the pair's
/// contract id is the one in force only when both parts' are.
///
/// ```no_run
/// # fn f(renderer: &mut voxel_render::Renderer, content: voxel_render::content::ContentStages,
/// #      mine: voxel_render::NoGame, camera: &voxel_render::Camera,
/// #      encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView) -> voxel_render::Result<()> {
/// use voxel_render::stages::Both;
/// let mut game = Both::new(content, mine);
/// renderer.render(encoder, view, camera, &mut game)?;
/// // game.first.set_content(..) and game.second between frames.
/// # Ok(()) }
/// ```
#[derive(Debug, Default)]
pub struct Both<A, B> {
    /// Drawn first in each stage.
    pub first: A,
    /// Drawn second in each stage.
    pub second: B,
    /// Which parts draw translucent geometry this frame (noted at `follow_contract`).
    translucent: [bool; 2],
    /// `first`'s translucent objects, then `second`'s.
    objects: Vec<TranslucentObject>,
    /// How many of `objects` are `first`'s.
    split: usize,
    /// The id of the contract in force (noted at `follow_contract`).
    contract: Option<u64>,
    /// Sorted techniques: each part's share of the frame's order (indices into its own
    /// objects), and per position of the frame's order the part that draws it and the
    /// position in its share.
    orders: [Vec<u32>; 2],
    positions: Vec<(u8, u32)>,
}

impl<A: GameStages, B: GameStages> Both<A, B> {
    /// `first` and `second` drawn as one game.
    pub fn new(first: A, second: B) -> Self {
        Self {
            first,
            second,
            translucent: [false; 2],
            objects: Vec::new(),
            split: 0,
            contract: None,
            orders: [Vec::new(), Vec::new()],
            positions: Vec::new(),
        }
    }

    fn part(&self, k: usize) -> &dyn GameStages {
        if k == 0 { &self.first } else { &self.second }
    }

    /// `frame` with part `k`'s share of the order.
    fn frame_of<'f>(&'f self, frame: &GameFrame<'f>, k: usize) -> GameFrame<'f> {
        GameFrame {
            order: frame.order.map(|_| self.orders[k].as_slice()),
            ..*frame
        }
    }
}

impl<A: GameStages, B: GameStages> GameStages for Both<A, B> {
    fn stages(&self) -> Stages {
        let (a, b) = (self.first.stages(), self.second.stages());
        Stages {
            opaque: a.opaque || b.opaque,
            translucent: a.translucent || b.translucent,
            hdr_overlay: a.hdr_overlay || b.hdr_overlay,
            overlay: a.overlay || b.overlay,
        }
    }

    fn translucent_objects(&self) -> &[TranslucentObject] {
        &self.objects
    }

    /// The first part's context, else the second's; where both name one and they are of two
    /// devices, the second's (one of them is not the renderer's: the frame is refused
    /// unless the renderer's is the second's).
    fn context(&self) -> Option<&GpuContext> {
        match (self.first.context(), self.second.context()) {
            (Some(a), Some(b)) if !a.same_device(b) => Some(b),
            (a, b) => a.or(b),
        }
    }

    fn translucent_contract_id(&self) -> Option<u64> {
        let ids = [
            self.first.translucent_contract_id(),
            self.second.translucent_contract_id(),
        ];
        // The first part whose id is not the one in force, else the one in force.
        (0..2)
            .filter(|&k| self.translucent[k])
            .map(|k| ids[k])
            .find(|&id| id != self.contract)
            .unwrap_or(self.contract)
    }

    fn follow_contract(&mut self, ctx: &GpuContext, contract: &TranslucentContract) {
        self.contract = Some(contract.id);
        self.translucent = [
            self.first.stages().translucent,
            self.second.stages().translucent,
        ];
        if self.translucent[0] {
            self.first.follow_contract(ctx, contract);
        }
        if self.translucent[1] {
            self.second.follow_contract(ctx, contract);
        }
        // The objects after following (a part may change them there).
        self.objects.clear();
        if self.translucent[0] {
            self.objects
                .extend_from_slice(self.first.translucent_objects());
        }
        self.split = self.objects.len();
        if self.translucent[1] {
            self.objects
                .extend_from_slice(self.second.translucent_objects());
        }
    }

    fn prepare(&mut self, ctx: &GpuContext, frame: &GameFrame<'_>) {
        let stages = [self.first.stages(), self.second.stages()];
        if !(stages[0].translucent || stages[1].translucent) {
            // No translucent stage this frame: `follow_contract` was not called.
            self.translucent = [false; 2];
            self.objects.clear();
            self.split = 0;
        }
        let [a, b] = &mut self.orders;
        a.clear();
        b.clear();
        self.positions.clear();
        if let Some(order) = frame.order {
            let split = self.split as u32;
            for &i in order {
                let (k, share, index) = if i < split {
                    (0, &mut *a, i)
                } else {
                    (1, &mut *b, i - split)
                };
                self.positions.push((k, share.len() as u32));
                share.push(index);
            }
        }
        let sorted = frame.order.is_some();
        if stages[0] != Stages::default() {
            let f = GameFrame {
                order: sorted.then_some(self.orders[0].as_slice()),
                ..*frame
            };
            self.first.prepare(ctx, &f);
        }
        if stages[1] != Stages::default() {
            let f = GameFrame {
                order: sorted.then_some(self.orders[1].as_slice()),
                ..*frame
            };
            self.second.prepare(ctx, &f);
        }
    }

    fn opaque(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        if self.first.stages().opaque {
            self.first.opaque(pass, frame);
        }
        if self.second.stages().opaque {
            self.second.opaque(pass, frame);
        }
    }

    fn translucent(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &GameFrame<'_>,
        variant: usize,
        objects: Range<usize>,
    ) {
        // Positions in the order (an object cut into parts is there once per part), or
        // indices into the objects.
        let total = if frame.order.is_some() {
            self.positions.len()
        } else {
            self.objects.len()
        };
        let (start, end) = (objects.start.min(total), objects.end.min(total));
        if frame.order.is_some() {
            // Positions in the order: each run of one part's objects in one call.
            let mut i = start;
            while i < end {
                let k = self.positions[i].0;
                let mut j = i + 1;
                while j < end && self.positions[j].0 == k {
                    j += 1;
                }
                let range = self.positions[i].1 as usize..self.positions[j - 1].1 as usize + 1;
                let part = usize::from(k);
                self.part(part)
                    .translucent(pass, &self.frame_of(frame, part), variant, range);
                i = j;
            }
        } else {
            // Indices: `first`'s below the split, `second`'s above it.
            let a = start.min(self.split)..end.min(self.split);
            if self.translucent[0] && !a.is_empty() {
                self.first.translucent(pass, frame, variant, a);
            }
            let b = start.max(self.split) - self.split..end.max(self.split) - self.split;
            if self.translucent[1] && !b.is_empty() {
                self.second.translucent(pass, frame, variant, b);
            }
        }
        // A part without objects draws everything, after the last object.
        if end == total {
            let counts = [self.split, total - self.split];
            for (k, count) in counts.into_iter().enumerate() {
                if self.translucent[k] && count == 0 {
                    self.part(k)
                        .translucent(pass, &self.frame_of(frame, k), variant, 0..0);
                }
            }
        }
    }

    fn hdr_overlay(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        if self.first.stages().hdr_overlay {
            self.first.hdr_overlay(pass, frame);
        }
        if self.second.stages().hdr_overlay {
            self.second.hdr_overlay(pass, frame);
        }
    }

    fn overlay(&self, pass: &mut wgpu::RenderPass<'_>, frame: &GameFrame<'_>) {
        if self.first.stages().overlay {
            self.first.overlay(pass, frame);
        }
        if self.second.stages().overlay {
            self.second.overlay(pass, frame);
        }
    }
}

/// The game's translucent part of a frame as the techniques see it.
pub(crate) struct GameDraw<'a> {
    /// The game.
    pub stages: &'a dyn GameStages,
    /// The frame it draws in.
    pub frame: &'a GameFrame<'a>,
    /// How many objects (positions in the order, or indices).
    pub objects: usize,
    /// Sorted techniques: where runs of the ordered objects are drawn among the visible
    /// translucent chunks (in draw order); the objects after the last run come after every
    /// chunk, unclipped.
    pub splits: &'a [Split],
    /// Sorted techniques: the planes that clip the parts of objects cut where they reach
    /// through a plane of quads ([`Split::clip`]; the first is none).
    pub clips: &'a [Clip],
    /// The resources a technique binds into its group for the game (group 0's frame
    /// uniforms and medium boundary, besides its own).
    pub frame_buffer: &'a wgpu::Buffer,
    /// The nearest sampler depth textures are read with (`gpu::DEPTH_READ`).
    pub depth_sampler: &'a wgpu::Sampler,
    /// The media the fragments are seen through (`shaders/path.wgsl`), in the order of
    /// [`MEDIA_WGSL_NAMES`]: the medium boundary depth (see `medium.rs`), where volumes
    /// end, the nearest entry into a volume and its medium's look, the nearest entry beyond
    /// where that one ends and its look, the farthest back face of a volume, the opaque
    /// depth.
    pub media: [&'a wgpu::TextureView; MEDIA_VIEWS],
}

/// How many views of the media a game's group binds ([`GameDraw::media`]).
pub(crate) const MEDIA_VIEWS: usize = 8;

/// The WGSL names of [`GameDraw::media`] (group 0's in the chunk shaders).
const MEDIA_WGSL_NAMES: [&str; MEDIA_VIEWS] = [
    "medium_boundary",
    "volume_depth",
    "volume_entry",
    "entry_look",
    "volume_entry2",
    "entry2_look",
    "volume_far",
    "opaque_copy",
];

impl std::fmt::Debug for GameDraw<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GameDraw")
            .field("objects", &self.objects)
            .finish_non_exhaustive()
    }
}

impl GameDraw<'_> {
    /// Draws the objects `range` in pass `variant`, with `group` bound at [`OIT_GROUP`].
    pub(crate) fn draw(
        &self,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
        variant: usize,
        group: &wgpu::BindGroup,
        range: Range<usize>,
    ) {
        self.draw_offsets(pass, variant, group, &[], range);
    }

    /// Like [`GameDraw::draw`], with dynamic `offsets` for the group.
    pub(crate) fn draw_offsets(
        &self,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
        variant: usize,
        group: &wgpu::BindGroup,
        offsets: &[u32],
        range: Range<usize>,
    ) {
        pass.set_bind_group(OIT_GROUP, group, offsets);
        pass.game(|raw| self.stages.translucent(raw, self.frame, variant, range));
    }

    /// Draws every object in pass `variant`.
    pub(crate) fn draw_all(
        &self,
        pass: &mut crate::gpu::CountedPass<'_, '_>,
        variant: usize,
        group: &wgpu::BindGroup,
    ) {
        self.draw(pass, variant, group, 0..self.objects);
    }
}

/// The group a technique binds for games at [`OIT_GROUP`]: binding 0 the frame uniforms,
/// 1 the sampler depth textures are read with, then the media ([`GameDraw::media`], what
/// the techniques' WGSL reads of group 0), then the technique's own entries (its chunk
/// pipelines' group 2) moved up by [`OWN_SHIFT`].
pub(crate) fn game_layout(
    device: &wgpu::Device,
    label: &str,
    own: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    use wgpu::ShaderStages as S;
    let mut entries = vec![
        crate::gpu::buffer_entry(0, S::VERTEX_FRAGMENT, wgpu::BufferBindingType::Uniform),
        crate::gpu::depth_sampler_entry(1),
    ];
    // The looks are colours, the rest depths (both read unfiltered).
    entries.extend(MEDIA_WGSL_NAMES.iter().enumerate().map(|(i, name)| {
        let kind = if name.ends_with("_look") {
            wgpu::TextureSampleType::Float { filterable: false }
        } else {
            crate::gpu::DEPTH_READ
        };
        crate::gpu::texture_entry(2 + i as u32, kind)
    }));
    entries.extend(own.iter().map(|e| wgpu::BindGroupLayoutEntry {
        binding: e.binding + OWN_SHIFT,
        visibility: S::FRAGMENT,
        ..*e
    }));
    crate::gpu::layout(device, label, &entries)
}

/// The game group of [`game_layout`] for one pass: `own` are the resources of the
/// technique's group 2, in binding order.
pub(crate) fn game_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    draw: &GameDraw<'_>,
    own: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let mut resources = vec![
        draw.frame_buffer.as_entire_binding(),
        wgpu::BindingResource::Sampler(draw.depth_sampler),
    ];
    resources.extend(draw.media.map(wgpu::BindingResource::TextureView));
    resources.extend(own.iter().cloned());
    crate::gpu::bind_group(device, label, layout, &resources)
}

/// How far a technique's own bindings (its group 2) move up in the game's group.
const OWN_SHIFT: u32 = 2 + MEDIA_VIEWS as u32;

/// A game's prelude: the frame uniforms, the medium boundary and the depth sampler at
/// [`OIT_GROUP`], the technique's WGSL `own` (its group-2 bindings moved to [`OIT_GROUP`],
/// [`OWN_SHIFT`] up), and `output` (which declares `OitOutput` and `oit_output`).
pub(crate) fn game_prelude(own: &str, output: &str) -> String {
    let media: String = MEDIA_WGSL_NAMES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            format!(
                "@group({OIT_GROUP}) @binding({}) var {name}: texture_2d<f32>;\n",
                2 + i
            )
        })
        .collect();
    let header = crate::gpu::WgslConsts::default()
        .u32("NO_MEDIUM", crate::bindings::NO_MEDIUM)
        .u32("FLAG_INTERFACE", voxel_mesh::FLAG_INTERFACE)
        .f32("OIT_OBJECT_DEPTH_BIAS", OBJECT_DEPTH_BIAS)
        .finish()
        + &crate::bindings::frame_wgsl()
        + crate::gpu::DEPTH_UV_WGSL
        + &format!(
            "@group({OIT_GROUP}) @binding(0) var<uniform> frame: Frame;\n\
             @group({OIT_GROUP}) @binding(1) var depth_sampler: sampler;\n\
             {media}\n\
             // The medium boundary's depth at pixel `xy`.\n\
             fn boundary_depth(xy: vec2<f32>) -> f32 {{\n    \
             let uv = depth_uv(xy, textureDimensions(medium_boundary));\n    \
             return textureSampleLevel(medium_boundary, depth_sampler, uv, 0.0).x;\n}}\n\n\
             // View depth of a fragment from its reverse-Z depth.\n\
             fn oit_view_depth(position: vec4<f32>) -> f32 {{\n    \
             return frame.near * frame.far / (position.z * (frame.far - frame.near) + frame.near);\n}}\n\n\
             // The fragment's position with its depth as the exact methods compare an\n\
             // object's (OBJECT_DEPTH_BIAS: at equal depth the object is in front).\n\
             fn oit_object_position(position: vec4<f32>) -> vec4<f32> {{\n    \
             return vec4<f32>(position.xy, min(position.z * (1.0 + OIT_OBJECT_DEPTH_BIAS), 1.0), position.w);\n}}\n\n"
        );
    header
        + crate::bindings::VOLUME_WGSL
        + crate::bindings::PATH_WGSL
        + &regroup(own, 2, OIT_GROUP, OWN_SHIFT)
        + "\n"
        + output
}

/// `src` with every `@group(from) @binding(k)` made `@group(to) @binding(k + shift)`.
fn regroup(src: &str, from: u32, to: u32, shift: u32) -> String {
    let pattern = format!("@group({from}) @binding(");
    let mut out = String::with_capacity(src.len());
    let mut rest = src;
    while let Some(i) = rest.find(&pattern) {
        out.push_str(&rest[..i]);
        rest = &rest[i + pattern.len()..];
        let end = rest.find(')').unwrap_or(rest.len());
        let k: u32 = rest[..end].trim().parse().unwrap_or(0);
        out.push_str(&format!("@group({to}) @binding({})", k + shift));
        rest = rest.get(end + 1..).unwrap_or("");
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regroup_moves_group_and_bindings() {
        let src = "@group(2) @binding(0) var<uniform> a: A;\n@group(0) @binding(1) var b: B;\n@group(2) @binding(3) var c: C;";
        assert_eq!(
            regroup(src, 2, 3, 2),
            "@group(3) @binding(2) var<uniform> a: A;\n@group(0) @binding(1) var b: B;\n@group(3) @binding(5) var c: C;"
        );
    }
}
