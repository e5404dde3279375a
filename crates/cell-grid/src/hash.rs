//! Keys and hasher for the hashed-cell fallback.
//!
//! The keys are small integer tuples produced by our own arithmetic, never by an adversary,
//! so a DoS-resistant hasher (std's SipHash) would only cost time: one multiply-rotate round
//! per coordinate is enough to spread neighbouring cells over the table.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// Integer coordinates of a cell, hashed one coordinate at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CellKey<const D: usize>(pub(crate) [i64; D]);

impl<const D: usize> Hash for CellKey<D> {
    fn hash<H: Hasher>(&self, state: &mut H) {
        for &k in &self.0 {
            state.write_i64(k);
        }
    }
}

/// Multiply-rotate hasher in the spirit of rustc's FxHash (written here from the idea).
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct CellHasher(u64);

// An odd constant close to 2^64 / golden ratio: multiplication by it mixes low bits upwards.
const MIX: u64 = 0x9e37_79b9_7f4a_7c15;

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(5) ^ u64::from(b)).wrapping_mul(MIX);
        }
    }

    fn write_i64(&mut self, k: i64) {
        self.0 = (self.0.rotate_left(5) ^ (k as u64)).wrapping_mul(MIX);
    }

    fn finish(&self) -> u64 {
        // hashbrown takes the top 7 bits as the control byte and the low bits as the bucket:
        // fold the well-mixed high half into the low half so both are usable.
        self.0 ^ (self.0 >> 32)
    }
}

/// Map from cell coordinates to the slot of a non-empty cell.
pub(crate) type CellMap<const D: usize> =
    HashMap<CellKey<D>, usize, BuildHasherDefault<CellHasher>>;
