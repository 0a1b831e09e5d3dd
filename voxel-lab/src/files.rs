//! Result files (pictures, JSON, charts, reports) are written in one checked call each: a
//! failure is an error naming the file, and a write that fails part way (a full disk)
//! leaves no partial file that would look like a result.

use crate::{Error, Result};

use std::path::Path;

/// Writes `bytes` to `path` ([`voxel_render::readback::write_file`]); the error names the
/// file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    voxel_render::readback::write_file(path, bytes).map_err(Error::Render)
}
