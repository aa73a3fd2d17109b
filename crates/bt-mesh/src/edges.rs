//! Faces by edge: the adjacency of a face list without a hash map per edge.

/// The key of the undirected edge `a`-`b`.
pub(crate) fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// Every (undirected edge, face) pair of a face list, sorted by edge then face, with a cursor
/// per edge past the faces already settled (grouped, placed in a piece), so that many faces on
/// one edge (duplicated or fanned triangles) cost linear, not quadratic, time.
pub(crate) struct EdgeTable {
    entries: Vec<(u64, u32)>,
    /// For the first entry of an edge's run: where its unsettled faces may begin.
    skip: Vec<u32>,
}

impl EdgeTable {
    /// The table of `faces`, each given by its vertex cycle; faces are numbered in order.
    pub fn new<'a>(faces: impl IntoIterator<Item = &'a [u32]>) -> Self {
        let faces = faces.into_iter();
        // Room for triangles; larger faces grow it.
        let mut entries = Vec::with_capacity(3 * faces.size_hint().0);
        for (f, vs) in faces.enumerate() {
            for i in 0..vs.len() {
                entries.push((edge_key(vs[i], vs[(i + 1) % vs.len()]), f as u32));
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let skip = (0..entries.len() as u32).collect();
        EdgeTable { entries, skip }
    }

    /// The faces on edge `key` from the first one not `settled` on, in face order. `settled`
    /// must only ever grow between calls.
    pub fn unsettled(&mut self, key: u64, settled: impl Fn(usize) -> bool) -> Faces<'_> {
        let start = self.entries.partition_point(|&(k, _)| k < key);
        let end = self.entries.partition_point(|&(k, _)| k <= key);
        let mut first = self.skip.get(start).map_or(start, |&s| s as usize);
        while first < end && settled(self.entries[first].1 as usize) {
            first += 1;
        }
        if let Some(s) = self.skip.get_mut(start) {
            *s = first as u32;
        }
        let face: fn(&(u64, u32)) -> usize = |&(_, f)| f as usize;
        self.entries[first..end].iter().map(face)
    }
}

/// Face numbers on one edge, from [`EdgeTable::unsettled`].
pub(crate) type Faces<'a> =
    std::iter::Map<std::slice::Iter<'a, (u64, u32)>, fn(&(u64, u32)) -> usize>;
