//! Faces by edge: the adjacency of a face list without a hash map per edge.

/// The key of the undirected edge `a`-`b`.
pub(crate) fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// Every (undirected edge, face) pair of a face list, sorted by edge then face, with a cursor
/// per edge past the faces already settled (grouped, placed in a piece), so that many faces on
/// one edge (duplicated or fanned triangles) cost linear, not quadratic, time. Each face's
/// edges know where their run of pairs starts, so a look-up is no search (a binary search
/// per edge was the largest part of merging a 192,000-triangle terrain).
pub(crate) struct EdgeTable {
    entries: Vec<(u64, u32)>,
    /// For the first entry of an edge's run: where its unsettled faces may begin.
    skip: Vec<u32>,
    /// Per face edge (face `f`'s edge `i` at `firsts[f] + i`): the first entry of its run.
    runs: Vec<u32>,
    /// Per face: where its edges start in `runs`.
    firsts: Vec<u32>,
}

impl EdgeTable {
    /// The table of `faces`, each given by its vertex cycle; faces are numbered in order.
    #[inline(never)]
    pub fn new<'a>(faces: impl IntoIterator<Item = &'a [u32]>) -> Self {
        let faces = faces.into_iter();
        // Room for triangles; larger faces grow it. Each pair carries where it was made (its
        // face edge), which tells that face edge its run once sorted. The triple (key, face,
        // face edge) is packed in one integer, `key << 64 | face << 32 | face edge`: it sorts
        // as the triple, in fewer instructions than a tuple compared field by field.
        let mut made: Vec<u128> = Vec::with_capacity(3 * faces.size_hint().0);
        let mut firsts = Vec::with_capacity(faces.size_hint().0);
        for (f, vs) in faces.enumerate() {
            firsts.push(made.len() as u32);
            for i in 0..vs.len() {
                let key = edge_key(vs[i], vs[(i + 1) % vs.len()]);
                made.push(u128::from(key) << 64 | (f as u128) << 32 | made.len() as u128);
            }
        }
        let made = bucket_sorted(made, |&x| (x >> 96) as u32);
        let mut entries: Vec<(u64, u32)> = Vec::with_capacity(made.len());
        let mut runs = vec![0; made.len()];
        let mut run = 0;
        for &x in &made {
            let (key, f, at) = ((x >> 64) as u64, (x >> 32) as u32, x as u32);
            match entries.last() {
                Some(&(last, _)) if last == key => {}
                _ => run = entries.len() as u32,
            }
            // A face on one edge twice keeps one pair (as `dedup` would).
            if entries.last() != Some(&(key, f)) {
                entries.push((key, f));
            }
            runs[at as usize] = run;
        }
        let skip = (0..entries.len() as u32).collect();
        EdgeTable {
            entries,
            skip,
            runs,
            firsts,
        }
    }

    /// The faces on face `f`'s edge `i` (from its vertex `i` to the next) from the first one
    /// not `settled` on, in face order. `settled` must only ever grow between calls.
    pub fn unsettled(
        &mut self,
        f: usize,
        i: usize,
        settled: impl Fn(usize) -> bool,
    ) -> impl Iterator<Item = usize> + '_ {
        let start = self.runs[self.firsts[f] as usize + i] as usize;
        let key = self.entries[start].0;
        let on_edge = move |&(k, _): &(u64, u32)| k == key;
        let mut first = self.skip[start] as usize;
        while self.entries.get(first).is_some_and(on_edge)
            && settled(self.entries[first].1 as usize)
        {
            first += 1;
        }
        self.skip[start] = first as u32;
        (self.entries[first..].iter())
            .take_while(move |e| on_edge(e))
            .map(|&(_, f)| f as usize)
    }
}

/// `items` sorted, the way `sort_unstable` sorts them, when `bucket` agrees with their order
/// (`a < b` implies `bucket(a) <= bucket(b)`); otherwise each set of equal items is still one
/// run, in the order of the buckets. Counted into their buckets first, so that a large list
/// with few items per bucket (a mesh's edges by their lower vertex, its faces by their least
/// vertex) sorts in linear time plus many tiny sorts; a sparse range of buckets falls back to
/// one sort.
pub(crate) fn bucket_sorted<T: Copy + Ord + Send>(
    items: Vec<T>,
    bucket: impl Fn(&T) -> u32,
) -> Vec<T> {
    bucket_sorted_in(items, bucket, PARALLEL_ITEMS)
}

/// Items of [`bucket_sorted`] per piece of buckets sorted on another core: the buckets of a
/// large list (San Francisco's terrain: 576,000 face edges in 96,000 buckets) are sorted in
/// pieces of whole buckets of about this many items, on all cores.
const PARALLEL_ITEMS: usize = 1 << 15;

/// [`bucket_sorted`], sorting the buckets in pieces of about `piece` items on all cores (the
/// same result for any `piece`).
fn bucket_sorted_in<T: Copy + Ord + Send>(
    mut items: Vec<T>,
    bucket: impl Fn(&T) -> u32,
    piece: usize,
) -> Vec<T> {
    let Some((lo, hi)) = (items.iter().map(&bucket)).fold(None, |range, b| match range {
        None => Some((b, b)),
        Some((lo, hi)) => Some((b.min(lo), b.max(hi))),
    }) else {
        return items;
    };
    let buckets = (hi - lo) as usize + 1;
    if buckets > 2 * items.len() + 16 {
        items.sort_unstable();
        return items;
    }
    // `ends[b + 1]` counts bucket `b`, then (summed) is where it ends; `next` fills them.
    let mut ends = vec![0usize; buckets + 1];
    for t in &items {
        ends[(bucket(t) - lo) as usize + 1] += 1;
    }
    for b in 0..buckets {
        ends[b + 1] += ends[b];
    }
    let mut next = ends[..buckets].to_vec();
    let mut sorted = vec![items[0]; items.len()];
    for t in &items {
        let b = (bucket(t) - lo) as usize;
        sorted[next[b]] = *t;
        next[b] += 1;
    }
    let sort_runs = |(rest, ends): (&mut [T], &[usize])| {
        let mut rest = rest;
        for w in ends.windows(2) {
            let (run, tail) = std::mem::take(&mut rest).split_at_mut(w[1] - w[0]);
            if run.len() > 1 {
                run.sort_unstable();
            }
            rest = tail;
        }
    };
    if sorted.len() <= piece {
        sort_runs((&mut sorted, &ends));
        return sorted;
    }
    // Pieces of whole buckets: each its items and its buckets' ends (one shared with the next).
    let mut pieces = Vec::new();
    let (mut rest, mut first) = (sorted.as_mut_slice(), 0);
    while first < buckets {
        let start = ends[first];
        let last = (first + 1..=buckets)
            .find(|&b| ends[b] - start >= piece)
            .unwrap_or(buckets);
        let (items, tail) = std::mem::take(&mut rest).split_at_mut(ends[last] - start);
        pieces.push((items, &ends[first..=last]));
        (rest, first) = (tail, last);
    }
    use rayon::prelude::*;
    pieces.into_par_iter().for_each(sort_runs);
    sorted
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// With buckets that agree with the order, the bucket sort is a sort (dense and sparse
        /// ranges of buckets); with buckets that do not, equal items still form one run each.
        #[test]
        fn bucket_sorted_sorts(
            items in proptest::collection::vec((0u64..40, 0u32..5, 0u32..3), 0..200),
            spread in proptest::prop_oneof![proptest::strategy::Just(1u64), 1u64..100_000],
        ) {
            let items: Vec<(u64, u32, u32)> =
                items.into_iter().map(|(lo, f, i)| ((lo * spread) << 32 | lo, f, i)).collect();
            let mut sorted = items.clone();
            sorted.sort_unstable();
            let bucketed = bucket_sorted(items.clone(), |&(key, _, _)| (key >> 32) as u32);
            proptest::prop_assert_eq!(&bucketed, &sorted);
            for piece in [1, 2, 5, 64] {
                let pieces = bucket_sorted_in(items.clone(), |&(key, _, _)| (key >> 32) as u32, piece);
                proptest::prop_assert_eq!(&pieces, &sorted);
            }
            let by_face = bucket_sorted(items, |&(_, f, _)| f);
            let mut runs: Vec<_> = by_face.chunk_by(|a, b| a == b).map(|r| r[0]).collect();
            let count = runs.len();
            runs.sort_unstable();
            runs.dedup();
            proptest::prop_assert_eq!(runs.len(), count);
        }
    }

    #[test]
    fn a_face_edge_finds_the_faces_on_its_edge() {
        // Two triangles sharing edge 1-2, a third on edge 2-0.
        let faces: [&[u32]; 3] = [&[0, 1, 2], &[2, 1, 3], &[0, 2, 4]];
        let mut table = EdgeTable::new(faces);
        let on = |t: &mut EdgeTable, f, i| t.unsettled(f, i, |_| false).collect::<Vec<_>>();
        assert_eq!(on(&mut table, 0, 1), [0, 1]);
        assert_eq!(on(&mut table, 1, 0), [0, 1]);
        assert_eq!(on(&mut table, 0, 2), [0, 2]);
        assert_eq!(on(&mut table, 2, 1), [2]);
        let settled: Vec<usize> = table.unsettled(1, 0, |f| f == 0).collect();
        assert_eq!(settled, [1]);
    }
}
