//! Everything that can go wrong in the demo: the lab's errors (scenes, files, the
//! renderer), the command line's values, and the window's. As in the lab
//! ([`voxel_lab::Error`]), each message carries its whole detail, and the error it came
//! from is kept in the variant rather than returned again by
//! [`std::error::Error::source`]; [`Error::Lab`] stands for the lab's error as it is.

use std::fmt;
use std::path::PathBuf;

/// An error of the demo.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// An error of the lab (a scene, a file, an option past its cap, the renderer).
    Lab(voxel_lab::Error),
    /// A command-line value that is not what the option takes; reads `"VALUE" is not WHAT`.
    NotA {
        /// The value given.
        value: String,
        /// What the option takes.
        what: String,
    },
    /// A command-line value that is none of the few the option takes.
    Expected {
        /// The value given.
        value: String,
        /// The values the option takes.
        expected: &'static str,
    },
    /// An option's value that was refused; reads `OPTION: why`.
    InOption {
        /// The option.
        option: &'static str,
        /// Why it was refused.
        error: Box<Error>,
    },
    /// An output folder with a file in its path.
    NotAFolder {
        /// The folder.
        dir: PathBuf,
        /// The file where a folder should be.
        file: PathBuf,
    },
    /// An output folder that cannot be written to.
    NotWritable {
        /// The folder.
        dir: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// An output file that is a folder.
    IsAFolder {
        /// The path.
        path: PathBuf,
    },
    /// A scene path that is neither a file nor a folder.
    NoSuchScene {
        /// The path.
        path: PathBuf,
    },
    /// `render` drew no frame.
    NoFrame,
    /// The window's event loop could not be made.
    NoEventLoop(winit::error::EventLoopError),
    /// The window's event loop failed.
    EventLoop(winit::error::EventLoopError),
    /// The window could not be made.
    CreateWindow(winit::error::OsError),
    /// No surface for the window.
    CreateSurface(wgpu::CreateSurfaceError),
    /// The window's surface was lost and could not be made again.
    SurfaceLost(wgpu::CreateSurfaceError),
    /// No adapter can draw to the window.
    NoWindowAdapter(wgpu::RequestAdapterError),
    /// The window's surface offers no texture format.
    NoSurfaceFormat,
    /// The window's view distance did not load in time (a scripted run).
    LoadTimeout {
        /// How long it was given, in seconds.
        seconds: u64,
    },
}

/// `Result` with the demo's [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// `self` as the refusal of `option`'s value.
    pub fn in_option(self, option: &'static str) -> Self {
        Self::InOption {
            option,
            error: Box::new(self),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Lab(e) => e.fmt(f),
            Self::NotA { value, what } => write!(f, "{value:?} is not {what}"),
            Self::Expected { value, expected } => write!(f, "{value:?}: expected {expected}"),
            Self::InOption { option, error } => write!(f, "{option}: {error}"),
            Self::NotAFolder { dir, file } => write!(
                f,
                "{}: cannot write into {} because {} is a file, not a folder",
                dir.display(),
                dir.display(),
                file.display()
            ),
            Self::NotWritable { dir, error } => {
                write!(f, "{}: cannot write here: {error}", dir.display())
            }
            Self::IsAFolder { path } => write!(f, "{}: is a folder, not a file", path.display()),
            Self::NoSuchScene { path } => {
                write!(f, "{}: no such scene file or folder", path.display())
            }
            Self::NoFrame => f.write_str("no frame rendered"),
            Self::NoEventLoop(e) => write!(f, "cannot open a window: {e}"),
            Self::EventLoop(e) => write!(f, "event loop: {e}"),
            Self::CreateWindow(e) => write!(f, "cannot create the window: {e}"),
            Self::CreateSurface(e) => write!(f, "cannot create a surface for the window: {e}"),
            Self::SurfaceLost(e) => write!(f, "surface lost and not recreated: {e}"),
            Self::NoWindowAdapter(e) => write!(
                f,
                "no GPU adapter can draw to this window: {e} (install mesa-vulkan-drivers)"
            ),
            Self::NoSurfaceFormat => f.write_str("the surface offers no format"),
            Self::LoadTimeout { seconds } => {
                write!(f, "the view distance did not load in {seconds} s")
            }
        }
    }
}

impl std::error::Error for Error {
    /// The lab error's sources for [`Error::Lab`]; `None` otherwise (every other message
    /// already carries the error it came from).
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Lab(e) => e.source(),
            _ => None,
        }
    }
}

/// The conversions `?` uses: the lab's errors, and those the lab wraps.
macro_rules! from {
    ($($ty:ty,)*) => {$(
        impl From<$ty> for Error {
            fn from(e: $ty) -> Self {
                Self::Lab(e.into())
            }
        }
    )*};
}

from! {
    voxel_lab::Error,
    voxel_render::Error,
    voxel_core::Error,
    voxel_mesh::Error,
}
