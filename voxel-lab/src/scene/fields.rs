//! What every table of a scene file shares: fixed-length arrays, and errors at a line.

use serde::Deserialize;

use crate::Error;

/// The scene error `message` at the line of the byte offset `at` of `text` (it reads
/// `LINE: message`).
pub(super) fn at_line(text: &str, at: usize, message: impl std::fmt::Display) -> Error {
    let line = text[..at.min(text.len())].matches('\n').count() + 1;
    Error::scene(Some(line), message)
}

/// A fixed-length array in a scene file: exactly `N` values (serde's arrays take the first
/// `N` of a longer list and ignore the rest).
pub(super) fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let n = v.len();
    v.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of length {N}").as_str())
    })
}

/// [`exact`] for an optional array.
pub(super) fn exact_opt<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact(d).map(Some)
}
