//! A fast hasher for keys made of integers (grid cells, vertex ids), for hash maps that are
//! only looked up, never iterated for output, so results do not depend on hash order.

use std::hash::{BuildHasherDefault, Hasher};

/// Multiply-rotate hasher for integer keys (voxel cells, ids): lookups dominate spatial
/// hashes and the default SipHash is several times slower. Keys come from coordinates and
/// ids, not from an adversary choosing collisions.
#[derive(Default)]
pub struct KeyHasher(u64);

/// A hash map over [`KeyHasher`].
pub type KeyMap<K, V> = std::collections::HashMap<K, V, BuildHasherDefault<KeyHasher>>;

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_map_finds_what_it_holds() {
        let mut map: KeyMap<[i64; 3], u32> = KeyMap::default();
        for i in 0..1000i64 {
            map.insert([i, -i, i / 7], i as u32);
        }
        assert_eq!(map.len(), 1000);
        assert_eq!(map.get(&[500, -500, 71]), Some(&500));
        assert_eq!(map.get(&[500, 500, 71]), None);
    }
}
