//! Uniform voxel hash over a point set, for fixed-radius neighbour queries without O(n²).

use bt_geom::hash::KeyMap;
use bt_geom::{Real, Vec3};
use std::hash::Hash;

use rayon::prelude::*;

/// Points bucketed into cubic voxels of edge `cell` (metres). Queries with a radius up to
/// `cell` visit the 27 surrounding voxels. Only lookups go through the hash map; nothing
/// iterates it, so results do not depend on hash order.
pub(crate) struct VoxelIndex {
    cell: Real,
    order: Vec<u32>,
    ranges: KeyRanges<[i64; 3]>,
}

/// Where each key's run lies in a slice sorted by key: `key -> (start, end)`, end exclusive.
pub(crate) type KeyRanges<K> = KeyMap<K, (u32, u32)>;

/// The runs of equal keys in `keyed`, which must be sorted by key (the bucket index of a
/// spatial hash: the items of one cell are `keyed[start..end]`).
pub(crate) fn key_ranges<K: Copy + Ord + Hash>(keyed: &[(K, u32)]) -> KeyRanges<K> {
    debug_assert!(keyed.is_sorted_by(|a, b| a.0 <= b.0));
    let mut ranges = KeyRanges::default();
    let mut start = 0;
    for i in 1..=keyed.len() {
        if i == keyed.len() || keyed[i].0 != keyed[start].0 {
            ranges.insert(keyed[start].0, (start as u32, i as u32));
            start = i;
        }
    }
    ranges
}

pub(crate) fn voxel_key(p: Vec3, cell: Real) -> [i64; 3] {
    // `as` saturates, so absurd coordinates land in the outermost voxel instead of wrapping.
    let k = (p / cell).floor();
    [k.x as i64, k.y as i64, k.z as i64]
}

impl VoxelIndex {
    pub(crate) fn build(points: &[Vec3], cell: Real) -> Self {
        let mut keyed: Vec<([i64; 3], u32)> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| (voxel_key(*p, cell), i as u32))
            .collect();
        keyed.par_sort_unstable();
        Self {
            cell,
            ranges: key_ranges(&keyed),
            order: keyed.into_iter().map(|(_, i)| i).collect(),
        }
    }

    /// Call `f` with the index of every point inside the axis-aligned box `[lo, hi]`
    /// (metres), voxel by voxel in key order.
    pub(crate) fn for_each_in_box(
        &self,
        points: &[Vec3],
        lo: Vec3,
        hi: Vec3,
        mut f: impl FnMut(u32),
    ) {
        let (a, b) = (voxel_key(lo, self.cell), voxel_key(hi, self.cell));
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    if let Some(&(s, e)) = self.ranges.get(&[x, y, z]) {
                        for &j in &self.order[s as usize..e as usize] {
                            let p = points[j as usize];
                            if p.cmpge(lo).all() && p.cmple(hi).all() {
                                f(j);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Call `f` with the index of every point within `radius` (≤ cell) of `p`.
    pub(crate) fn for_each_near(
        &self,
        points: &[Vec3],
        p: Vec3,
        radius: Real,
        mut f: impl FnMut(u32),
    ) {
        debug_assert!(radius <= self.cell * (1.0 + 1e-9));
        let k = voxel_key(p, self.cell);
        let r2 = radius * radius;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    if let Some(&(s, e)) = self.ranges.get(&key) {
                        for &j in &self.order[s as usize..e as usize] {
                            if points[j as usize].distance_squared(p) <= r2 {
                                f(j);
                            }
                        }
                    }
                }
            }
        }
    }
}
