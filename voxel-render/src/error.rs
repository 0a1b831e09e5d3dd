//! Everything that can go wrong in the renderer. Each variant's message carries its whole
//! detail: what was at fault, and the message of the error it came from. That error is
//! kept in the variant (to match on), not returned by [`std::error::Error::source`], so
//! that a report printing the chain of sources does not repeat it.

use std::path::PathBuf;

/// An error of the renderer.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No adapter of the asked backends was found.
    #[error("no GPU adapter found for {backends:?}: {error}")]
    NoAdapter {
        /// The backends that were searched.
        backends: wgpu::Backends,
        /// Why wgpu found none.
        error: wgpu::RequestAdapterError,
    },
    /// The adapter refused to create a device.
    #[error("could not create a device: {0}")]
    Device(wgpu::RequestDeviceError),
    /// A camera with NaN, infinite or contradictory values.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// A technique, weight or other name that does not exist.
    #[error("unknown {kind} {name:?}; known: {known}")]
    UnknownName {
        /// What kind of name (technique, weight, Bayer size).
        kind: &'static str,
        /// The name given.
        name: String,
        /// The names that exist, comma-separated.
        known: String,
    },
    /// A block or world error (an unknown block id, a chunk outside the world, a
    /// terrain generator whose blocks the registry lacks).
    #[error("world: {0}")]
    World(voxel_core::Error),
    /// A setting outside what the renderer supports (the message names the setting and
    /// the allowed range).
    #[error("invalid setting: {0}")]
    InvalidSetting(String),
    /// A game's content (`content::Content`) holds a value outside its field's range: a
    /// NaN or infinite number, an opacity outside 0 to 1, a size of 0, a rotation that is
    /// not a unit quaternion. Nothing of it was taken.
    #[error("game content: {kind} {index}: {field}: {message}")]
    InvalidContent {
        /// `"particle"` or `"entity"`.
        kind: &'static str,
        /// Its index in `Content::particles` or `Content::entities`.
        index: usize,
        /// The field (`"opacity"`, `"center"`, …).
        field: &'static str,
        /// The value and the range it must lie in.
        message: String,
    },
    /// A size beyond what this adapter can do.
    #[error("{what} {value} exceeds this device's {limit_name} ({limit})")]
    TooLarge {
        /// What was too large (e.g. "render width").
        what: String,
        /// The size asked for.
        value: u64,
        /// The adapter limit it broke.
        limit_name: &'static str,
        /// The limit's value.
        limit: u64,
    },
    /// The texture given to draw into does not match the renderer.
    #[error("output texture: {0}")]
    Output(String),
    /// The device cannot do something that has no fallback: its adapter lacks it, or the
    /// limits it was made with (`LimitsPreset::WebGl2`) leave it out. The message names
    /// what needs what.
    #[error("not supported on this device: {0}")]
    Unsupported(String),
    /// A file could not be read or written.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// A PNG file could not be encoded.
    #[error("{}: PNG encoding: {error}", path.display())]
    PngEncode {
        /// The file.
        path: PathBuf,
        /// What the encoder said.
        error: png::EncodingError,
    },
    /// A PNG file could not be decoded (or holds a layout we do not read).
    #[error("{}: PNG decoding: {error}", path.display())]
    PngDecode {
        /// The file.
        path: PathBuf,
        /// What the decoder said.
        error: png::DecodingError,
    },
    /// An image file that cannot be a block texture (not square, not a power of two,
    /// too large).
    #[error("{}: {error}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        error: voxel_core::Error,
    },
    /// wgpu reported a validation or out-of-memory error for an operation of ours.
    #[error("GPU {operation} failed: {error}")]
    Gpu {
        /// What we were doing.
        operation: &'static str,
        /// wgpu's error.
        error: wgpu::Error,
    },
    /// Waiting for the GPU failed (device lost, timeout).
    #[error("waiting for the GPU: {0}")]
    Poll(wgpu::PollError),
    /// Mapping a buffer to read results back failed.
    #[error("reading GPU results back: {0}")]
    Readback(wgpu::BufferAsyncError),
    /// A mapped buffer's contents could not be accessed.
    #[error("reading GPU results back: {0}")]
    MapRange(wgpu::MapRangeError),
    /// A texture that cannot be read back as asked: without `COPY_SRC` usage (or, for
    /// `readback::read_depth`, `TEXTURE_BINDING`), multisampled, not a single 2D layer, a
    /// texel size that is not its format's, or a depth texture on a device that copies
    /// none to buffers (wgpu's GL backend: `readback::read_depth` reads those). Nothing
    /// was recorded.
    #[error("cannot read the texture back: {0}")]
    Unreadable(String),
    /// A game's buffer write the frame cannot make (`stages::GameFrame::write_buffer`):
    /// no `COPY_DST` usage, an offset or length not a multiple of 4, past the buffer's
    /// end, or after `GameStages::prepare`. Nothing was written.
    #[error("buffer write: {0}")]
    BufferWrite(String),
    /// A readback finished but its data cannot be what the GPU wrote (wrong length).
    #[error("reading GPU results back: {0}")]
    ReadbackData(String),
    /// A chunk source failed for a chunk: it panicked, or made block ids the registry does
    /// not hold (the chunk stands as air).
    #[error("the chunk source failed for chunk {pos:?}: {why}")]
    ChunkSource {
        /// The chunk.
        pos: voxel_core::ChunkPos,
        /// What went wrong.
        why: String,
    },
    /// A game draws translucent geometry with pipelines built for another contract than
    /// the technique's in force (a technique switch or a setting changed it): it must
    /// rebuild them for `Renderer::translucent_contract` and say so through
    /// `GameStages::translucent_contract_id`. Nothing of the frame was recorded.
    #[error(
        "the game's translucent pipelines were built for contract {}, but {technique}'s contract in force is {current}: rebuild them for Renderer::translucent_contract and return its id from GameStages::translucent_contract_id",
        built_for.map_or_else(|| "none (translucent_contract_id returned None)".to_owned(), |id| id.to_string())
    )]
    StaleContract {
        /// The id the game's pipelines were built for (`None`: not said).
        built_for: Option<u64>,
        /// The id of the contract in force.
        current: u64,
        /// The technique in force.
        technique: &'static str,
    },
    /// Something given to the renderer was made on another device than the renderer's
    /// (`Renderer::context`): a game's stages, or an output view. Nothing was recorded.
    #[error("made on another device than the renderer's: {0}")]
    OtherDevice(String),
    /// A frame that cannot be recorded into the encoder given now: an exact technique,
    /// which submits inside its frame, after a frame recorded into another encoder that is
    /// not submitted yet. Nothing was recorded.
    #[error("frame order: {0}")]
    FrameOrder(String),
    /// The device is lost (destroyed, reset, driver failure): nothing made on it can be
    /// used again. Make a new `GpuContext` (a new device) and a new renderer on it.
    #[error("the GPU device is lost ({reason}); make a new device and renderer")]
    DeviceLost {
        /// What wgpu said: the reason and its message.
        reason: String,
    },
}

/// The conversions `?` uses; by hand, because `#[from]` would also make the wrapped error
/// the [`std::error::Error::source`], which the message already carries.
macro_rules! from {
    ($($variant:ident($ty:ty),)*) => {$(
        impl From<$ty> for Error {
            fn from(e: $ty) -> Self {
                Error::$variant(e)
            }
        }
    )*};
}

from! {
    Device(wgpu::RequestDeviceError),
    World(voxel_core::Error),
    Poll(wgpu::PollError),
    Readback(wgpu::BufferAsyncError),
    MapRange(wgpu::MapRangeError),
}

/// `Result` with this crate's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::UnknownName`] listing `known`.
    pub(crate) fn unknown_name<'a>(
        kind: &'static str,
        name: &str,
        known: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        Error::UnknownName {
            kind,
            name: name.to_owned(),
            known: known.into_iter().collect::<Vec<_>>().join(", "),
        }
    }
}

/// The one of `all` whose `name_of` is `name` (what the named enums' `FromStr` does); the
/// error lists the known names.
pub(crate) fn parse_name<T: Copy>(
    kind: &'static str,
    name: &str,
    all: &[T],
    name_of: fn(T) -> &'static str,
) -> Result<T> {
    all.iter()
        .copied()
        .find(|&t| name_of(t) == name)
        .ok_or_else(|| Error::unknown_name(kind, name, all.iter().map(|&t| name_of(t))))
}

/// Runs `f` inside a wgpu validation and out-of-memory error scope, so that what wgpu
/// would report to the device's uncaptured-error handler (a panic by default) comes back
/// as an [`Error::Gpu`] instead.
///
/// In a browser the page's one thread cannot wait: a scope whose result is not ready at
/// once (WebGPU answers on the page's event loop; WebGL2, run by wgpu itself, at once)
/// is logged as an error when it arrives, and `f`'s value is returned.
pub(crate) fn scoped<T>(
    device: &wgpu::Device,
    operation: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let validation = wait_for_scope(operation, validation.pop());
    let oom = wait_for_scope(operation, oom.pop());
    match validation.or(oom) {
        Some(error) => Err(Error::Gpu { operation, error }),
        None => Ok(value),
    }
}

/// The error a popped scope caught (blocking until wgpu says).
#[cfg(not(target_arch = "wasm32"))]
fn wait_for_scope(
    _operation: &'static str,
    pop: impl std::future::Future<Output = Option<wgpu::Error>>,
) -> Option<wgpu::Error> {
    pollster::block_on(pop)
}

/// The error a popped scope caught when wgpu says at once; else `None`, and the error, if
/// any, is logged when it arrives.
#[cfg(target_arch = "wasm32")]
fn wait_for_scope(
    operation: &'static str,
    pop: impl std::future::Future<Output = Option<wgpu::Error>> + 'static,
) -> Option<wgpu::Error> {
    use std::task::{Context, Poll, Waker};
    let mut pop = Box::pin(pop);
    match pop.as_mut().poll(&mut Context::from_waker(Waker::noop())) {
        Poll::Ready(error) => error,
        Poll::Pending => {
            wasm_bindgen_futures::spawn_local(async move {
                if let Some(error) = pop.await {
                    log::error!("GPU {operation} failed: {error}");
                }
            });
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    /// Every message carries its detail, and no source repeats it.
    #[test]
    fn messages_carry_their_detail() {
        let world = Error::from(voxel_core::Error::TooManyBlocks);
        assert_eq!(
            world.to_string(),
            "world: the registry is full (65536 blocks)"
        );
        let io = Error::Io {
            path: "a/b.png".into(),
            error: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        };
        assert_eq!(io.to_string(), "a/b.png: no such file");
        let image = Error::Image {
            path: "c.png".into(),
            error: voxel_core::Error::InvalidImage("12x12 texels".into()),
        };
        assert_eq!(
            image.to_string(),
            "c.png: invalid block image: 12x12 texels"
        );
        let decode = Error::PngDecode {
            path: "d.png".into(),
            error: png::DecodingError::LimitsExceeded,
        };
        assert!(decode.to_string().starts_with("d.png: PNG decoding: "));
        assert!(decode.to_string().len() > "d.png: PNG decoding: ".len());
        for e in [world, io, image, decode] {
            assert!(e.source().is_none(), "{e}");
        }
    }
}
