//! Everything that can go wrong in the lab. Each variant's message carries its whole
//! detail (the file, option or scene at fault, and the message of the error it came
//! from), as the renderer's [`voxel_render::Error`] does: the error it came from is kept
//! in the variant, to match on, and not returned again by [`std::error::Error::source`],
//! so that a report printing the chain of sources does not repeat it. The one exception is
//! [`Error::Render`], which stands for the renderer's error as it is (its message and its
//! sources).

use std::fmt;
use std::path::{Path, PathBuf};

/// An error of the lab.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// A file or folder could not be read, written or created.
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A scene file longer than the most one may hold
    /// (`limits::MAX_SCENE_FILE_BYTES`).
    FileTooLarge {
        /// The file.
        path: PathBuf,
        /// The most bytes it may hold.
        limit: u64,
    },
    /// A scene file that is not UTF-8 text.
    NotUtf8 {
        /// The file.
        path: PathBuf,
        /// Where the text stops being UTF-8.
        source: std::string::FromUtf8Error,
    },
    /// A scene (a scene file, or a generated scene's text) that does not parse or asks for
    /// something it may not: its message reads `FILE:LINE: field: message`.
    Scene {
        /// The file, or a generated scene's name; `None` for text parsed on its own.
        file: Option<String>,
        /// The line at fault (from 1); `None` where the parser could not say.
        line: Option<usize>,
        /// What is wrong: the field (`table.key`) and why.
        message: String,
    },
    /// Another error (the renderer refusing the camera that frames a scene's models) while
    /// building the scene of a file or a generated scene; reads `FILE:error`.
    InScene {
        /// The file, or a generated scene's name.
        file: String,
        /// What went wrong.
        error: Box<Error>,
    },
    /// No scene files to evaluate: none given, or a folder holding none.
    NoScenes {
        /// The folder searched, if one was.
        dir: Option<PathBuf>,
    },
    /// A MagicaVoxel model whose blocks cannot be registered or placed.
    Model {
        /// The model file.
        path: PathBuf,
        /// What is wrong with it.
        source: voxel_core::Error,
    },
    /// A MagicaVoxel model that places no voxels at all.
    EmptyModel {
        /// The model file.
        path: PathBuf,
    },
    /// No glass structure near the origin for the default scene of a seed.
    NoGlassStructure {
        /// The terrain seed.
        seed: u32,
    },
    /// A block, world, terrain or MagicaVoxel error of `voxel-core`.
    Core(voxel_core::Error),
    /// A chunk that could not be meshed.
    Mesh(voxel_mesh::Error),
    /// An error of the renderer (making a device, rendering, reading back, saving a PNG),
    /// as it is: its message and its sources are the renderer error's.
    Render(voxel_render::Error),
    /// No adapter of the given backends (`demo backends`).
    NoAdapter {
        /// The backends searched.
        backends: wgpu::Backends,
        /// Why wgpu found none.
        source: wgpu::RequestAdapterError,
    },
    /// The adapter refused a device with WebGL2's limits (`demo backends`).
    NoWebGl2Device(wgpu::RequestDeviceError),
    /// No device of `demo backends` drew a technique (the report, written anyway, gives
    /// each one's error).
    NoDeviceRuns {
        /// Each device's name and why it did not run, `; `-joined.
        devices: String,
    },
    /// A picture size past the caps of `limits`.
    Size {
        /// The option or field that gave it.
        what: String,
        /// The size, width × height.
        size: (u32, u32),
        /// The widest and tallest allowed (`limits::MAX_SIDE`).
        max_side: u32,
        /// The most pixels allowed (`limits::MAX_PIXELS`).
        max_pixels: u64,
    },
    /// A number outside the range an option allows.
    OutOfRange {
        /// The option or field that gave it.
        what: String,
        /// The value given.
        value: u64,
        /// The least value allowed.
        min: u64,
        /// The greatest value allowed.
        max: u64,
    },
    /// An option given a value it may not take; the message reads `OPTION MESSAGE`.
    InvalidOption {
        /// The option (a flag such as `--speed`, or what it sets).
        option: String,
        /// The value and what is wrong with it.
        message: String,
    },
    /// A random scene set of no scenes.
    NoRandomScenes,
    /// A random scene set of more than `random::MAX_SCENES` scenes.
    TooManyRandomScenes {
        /// The count as given (it may be too large for a number).
        count: String,
        /// The most allowed (`random::MAX_SCENES`).
        max: usize,
    },
    /// A backend name that is none of `headless::BACKENDS`.
    UnknownBackend {
        /// The name given.
        name: String,
        /// The names there are, comma-separated.
        known: String,
    },
    /// A chart (or the gallery's sheet) that plotters could not draw.
    Chart {
        /// What was drawn: `chart` or `gallery`.
        what: &'static str,
        /// Plotters' error, as it prints itself for debugging (it is generic over the
        /// drawing backend).
        detail: String,
    },
    /// A value that could not be written as JSON.
    Json(serde_json::Error),
}

/// `Result` with the lab's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// The [`Error::Io`] of `path`, for `map_err`.
    pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Self + '_ {
        move |source| Self::Io {
            path: path.to_owned(),
            source,
        }
    }

    /// An [`Error::InvalidOption`].
    pub fn option(option: impl Into<String>, message: impl Into<String>) -> Self {
        Self::InvalidOption {
            option: option.into(),
            message: message.into(),
        }
    }

    /// A scene error of text parsed on its own, at `line`.
    pub(crate) fn scene(line: Option<usize>, message: impl fmt::Display) -> Self {
        Self::Scene {
            file: None,
            line,
            message: message.to_string(),
        }
    }

    /// This error as one of the scene read from `file` (a path or a generated scene's
    /// name): an [`Error::Scene`] names the file, another error is wrapped in an
    /// [`Error::InScene`].
    pub fn in_file(self, file: impl fmt::Display) -> Self {
        match self {
            Self::Scene {
                file: None,
                line,
                message,
            } => Self::Scene {
                file: Some(file.to_string()),
                line,
                message,
            },
            Self::Scene { .. } | Self::InScene { .. } => self,
            other => Self::InScene {
                file: file.to_string(),
                error: Box::new(other),
            },
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::FileTooLarge { path, limit } => write!(
                f,
                "{}: larger than {limit} bytes, the most a scene file may hold",
                path.display()
            ),
            Self::NotUtf8 { path, source } => {
                write!(f, "{}: not UTF-8 text ({source})", path.display())
            }
            Self::Scene {
                file,
                line,
                message,
            } => {
                if let Some(file) = file {
                    write!(f, "{file}:")?;
                }
                match line {
                    Some(line) => write!(f, "{line}: {message}"),
                    None => write!(f, "?: {message}"),
                }
            }
            Self::InScene { file, error } => write!(f, "{file}:{error}"),
            Self::NoScenes { dir: None } => f.write_str("no scene files to evaluate"),
            Self::NoScenes { dir: Some(dir) } => {
                write!(f, "{}: no .toml or .vox scene files", dir.display())
            }
            Self::Model { path, source } => write!(f, "{}: {source}", path.display()),
            Self::EmptyModel { path } => {
                write!(f, "{}: the file places no voxels", path.display())
            }
            Self::NoGlassStructure { seed } => write!(
                f,
                "seed {seed}: no glass structure within 768 blocks of the origin"
            ),
            Self::Core(e) => e.fmt(f),
            Self::Mesh(e) => e.fmt(f),
            Self::Render(e) => e.fmt(f),
            Self::NoAdapter { backends, source } => write!(f, "no {backends:?} adapter: {source}"),
            Self::NoWebGl2Device(e) => write!(f, "no device with WebGL2's limits: {e}"),
            Self::NoDeviceRuns { devices } => write!(f, "no device drew a technique: {devices}"),
            Self::Size {
                what,
                size: (w, h),
                max_side,
                max_pixels,
            } => {
                if !(1..=*max_side).contains(w) || !(1..=*max_side).contains(h) {
                    write!(
                        f,
                        "{what} {w}x{h}: each side must be from 1 to {max_side} pixels"
                    )
                } else {
                    write!(
                        f,
                        "{what} {w}x{h}: at most {max_pixels} pixels (7680x4320) in all"
                    )
                }
            }
            Self::OutOfRange {
                what,
                value,
                min,
                max,
            } => write!(f, "{what} {value}: it must be from {min} to {max}"),
            Self::InvalidOption { option, message } => write!(f, "{option} {message}"),
            Self::NoRandomScenes => f.write_str("a random set needs at least 1 scene"),
            Self::TooManyRandomScenes { count, max } => write!(
                f,
                "{count} random scenes: at most {max} (at about a second per scene that is already more than a day, and every record stays in memory)"
            ),
            Self::UnknownBackend { name, known } => write!(f, "{name:?}: expected one of {known}"),
            Self::Chart { what, detail } => write!(f, "{what}: {detail}"),
            Self::Json(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for Error {
    /// `None` but for [`Error::Render`], whose sources are the renderer error's: every
    /// other message already carries the error it came from.
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Render(e) => e.source(),
            _ => None,
        }
    }
}

/// The conversions `?` uses.
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
    Core(voxel_core::Error),
    Mesh(voxel_mesh::Error),
    Render(voxel_render::Error),
    Json(serde_json::Error),
}
