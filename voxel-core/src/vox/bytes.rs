//! The bounded byte reader under the file's chunks and its scene graph: every length is
//! checked against the bytes that remain before anything is allocated.

use std::collections::HashMap;

use super::VoxError;

/// A bounded reader over `bytes[pos..end]`.
pub(super) struct Reader<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) pos: usize,
    pub(super) end: usize,
}

impl<'a> Reader<'a> {
    pub(super) fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], VoxError> {
        let left = self.end - self.pos;
        if n > left {
            return Err(VoxError::Truncated {
                what,
                at: self.pos,
                need: n as u64,
                left,
            });
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    pub(super) fn u32(&mut self, what: &'static str) -> Result<u32, VoxError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub(super) fn i32(&mut self, what: &'static str) -> Result<i64, VoxError> {
        Ok(i64::from(self.u32(what)? as i32))
    }

    /// A count of items of at least `min_size` bytes each: more than the bytes left can
    /// hold is a truncation, found before anything is allocated for them.
    pub(super) fn count(&mut self, min_size: usize, what: &'static str) -> Result<usize, VoxError> {
        let at = self.pos;
        let n = self.u32(what)? as usize;
        let left = self.end - self.pos;
        if n > left / min_size {
            return Err(VoxError::Truncated {
                what,
                at,
                need: n as u64 * min_size as u64,
                left,
            });
        }
        Ok(n)
    }

    pub(super) fn string(&mut self, what: &'static str) -> Result<String, VoxError> {
        let n = self.count(1, what)?;
        let at = self.pos;
        let b = self.take(n, what)?;
        String::from_utf8(b.to_vec()).map_err(|_| VoxError::Utf8(at))
    }

    pub(super) fn dict(&mut self, what: &'static str) -> Result<HashMap<String, String>, VoxError> {
        // Each entry holds two length words at least.
        let n = self.count(8, what)?;
        let mut d = HashMap::with_capacity(n);
        for _ in 0..n {
            let k = self.string(what)?;
            let v = self.string(what)?;
            d.insert(k, v);
        }
        Ok(d)
    }
}
