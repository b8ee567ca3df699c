//! Hashing of integer grid cells for spatial lookups (radiance and path graphs).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::IVec3;

/// A multiply-rotate hasher for grid cells: std's SipHash was an eighth of a graph render's
/// time, and cell keys need no protection against adversarial input.
#[derive(Default)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_i32(&mut self, i: i32) {
        self.write_u64(u64::from(i as u32));
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// A map keyed by grid cell.
pub type CellMap<V> = HashMap<IVec3, V, BuildHasherDefault<CellHasher>>;
