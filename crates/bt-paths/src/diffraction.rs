//! Candidates with one or two edge diffractions: reflections before the first edge, the edge,
//! reflections between the edges and the second edge (with two), reflections after the last
//! edge ([`DiffractedSet`]), and their blind enumeration, the reference the beam tree's join
//! ([`crate::beamtree`]) is checked against.
//!
//! A diffracted candidate of order `k` has `k` interactions, one or two of them diffractions:
//! D, R-D, D-R, R-D-R, ..., D-D, R-D-D, D-R-D, D-D-R, ... No surface appears twice in a row
//! among the reflections of one stretch (before, between, after the edges). Two diffractions
//! in a row are on different edges (a ray from one point of an edge to another runs along it).

use bt_geom::Real;
use bt_scene::{EdgeId, Scene, SurfaceId};

/// One diffracted candidate, borrowed from its set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiffractedCandidate<'a> {
    /// Every reflection of the candidate, TX side first (the edges left out).
    pub reflections: &'a [SurfaceId],
    /// The (first) diffracting edge.
    pub edge: EdgeId,
    /// The number of reflections before the (first) edge: its index among the points.
    pub position: usize,
    /// The second diffraction, when there are two: its edge and the number of reflections
    /// between the two edges.
    pub second: Option<(EdgeId, usize)>,
}

/// What happens at one point of a diffracted candidate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Site {
    /// A reflection on the surface.
    Reflection(SurfaceId),
    /// A diffraction on the edge.
    Diffraction(EdgeId),
}

impl<'a> DiffractedCandidate<'a> {
    /// The reflections between TX and the first edge.
    pub fn before(&self) -> &'a [SurfaceId] {
        &self.reflections[..self.position]
    }
    /// The reflections between the two edges (empty with one).
    pub fn between(&self) -> &'a [SurfaceId] {
        let q = self.second.map_or(0, |(_, q)| q);
        &self.reflections[self.position..self.position + q]
    }
    /// The reflections between the last edge and RX.
    pub fn after(&self) -> &'a [SurfaceId] {
        let q = self.second.map_or(0, |(_, q)| q);
        &self.reflections[self.position + q..]
    }
    /// Number of interactions (reflections plus diffractions).
    pub fn order(&self) -> usize {
        self.reflections.len() + self.diffractions()
    }
    /// Number of diffractions (1 or 2).
    pub fn diffractions(&self) -> usize {
        1 + usize::from(self.second.is_some())
    }
    /// The points' indices of the diffractions with their edges, TX side first.
    pub fn edges(&self) -> impl Iterator<Item = (usize, EdgeId)> + 'a {
        let first = (self.position, self.edge);
        let position = self.position;
        std::iter::once(first).chain(self.second.map(|(edge, q)| (position + 1 + q, edge)))
    }
    /// What happens at point `k` (`k < order()`).
    #[inline]
    pub fn site(&self, k: usize) -> Site {
        let p = self.position;
        match self.second {
            _ if k < p => Site::Reflection(self.reflections[k]),
            _ if k == p => Site::Diffraction(self.edge),
            None => Site::Reflection(self.reflections[k - 1]),
            Some((_, q)) if k <= p + q => Site::Reflection(self.reflections[k - 1]),
            Some((edge, q)) if k == p + q + 1 => Site::Diffraction(edge),
            Some(_) => Site::Reflection(self.reflections[k - 2]),
        }
    }
}

/// Which diffracted candidates to make: paths with up to `max_diffractions` (1 or 2)
/// diffractions, on edges at least `min_edge_length` metres long.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diffracting {
    /// Shortest edge that diffracts, metres.
    pub min_edge_length: Real,
    /// Most diffractions per path (1 or 2).
    pub max_diffractions: usize,
}

/// A set of diffracted candidates, stored flat, in a canonical order: by order, position,
/// edge, then reflections, then the second diffraction (so two generators of the same
/// candidates give equal sets: equality compares the candidates, not the Keller parameters
/// a generator may carry along, [`DiffractedSet::keller`]).
#[derive(Debug, Clone)]
pub struct DiffractedSet {
    ids: Vec<SurfaceId>,
    offsets: Vec<u32>,
    edges: Vec<EdgeId>,
    positions: Vec<u8>,
    /// Per candidate: the second edge and the reflections between, `None` with one.
    seconds: Vec<Option<(EdgeId, u8)>>,
    /// Per candidate: the Keller parameters of its two diffraction points, when solved
    /// (`Some(None)`: solved, no pair).
    keller: Vec<Option<Option<(Real, Real)>>>,
}

impl PartialEq for DiffractedSet {
    fn eq(&self, other: &Self) -> bool {
        (
            &self.ids,
            &self.offsets,
            &self.edges,
            &self.positions,
            &self.seconds,
        ) == (
            &other.ids,
            &other.offsets,
            &other.edges,
            &other.positions,
            &other.seconds,
        )
    }
}

impl Eq for DiffractedSet {}

impl Default for DiffractedSet {
    fn default() -> Self {
        DiffractedSet {
            ids: Vec::new(),
            offsets: vec![0],
            edges: Vec::new(),
            positions: Vec::new(),
            seconds: Vec::new(),
            keller: Vec::new(),
        }
    }
}

impl DiffractedSet {
    /// An empty set with room for `candidates` candidates of `reflections` reflections in
    /// all (a generator that knows its last set's size grows none of its arrays).
    pub(crate) fn with_capacity(candidates: usize, reflections: usize) -> Self {
        let mut offsets = Vec::with_capacity(candidates + 1);
        offsets.push(0);
        DiffractedSet {
            ids: Vec::with_capacity(reflections),
            offsets,
            edges: Vec::with_capacity(candidates),
            positions: Vec::with_capacity(candidates),
            seconds: Vec::with_capacity(candidates),
            keller: Vec::with_capacity(candidates),
        }
    }
    /// The number of reflections of all candidates together.
    pub(crate) fn reflection_count(&self) -> usize {
        self.ids.len()
    }
    /// Number of candidates.
    pub fn len(&self) -> usize {
        self.edges.len()
    }
    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
    /// The `i`-th candidate.
    #[inline]
    pub fn get(&self, i: usize) -> DiffractedCandidate<'_> {
        DiffractedCandidate {
            reflections: &self.ids[self.offsets[i] as usize..self.offsets[i + 1] as usize],
            edge: self.edges[i],
            position: self.positions[i] as usize,
            second: self.seconds[i].map(|(e, q)| (e, q as usize)),
        }
    }
    /// The parameters (t1 along the first edge, t2 along the second, metres from each edge's
    /// start) of the `i`-th candidate's two diffraction points, when its generator solved
    /// them ([`bt_scene::edges::keller_pair`]) from the very inputs the image method reads:
    /// TX mirrored through the reflections before the first edge, the first edge's line,
    /// and the second edge's line and RX (mirrored through the reflections after the second
    /// edge) both mirrored through those between, last first: `Some(None)` when that solve
    /// found no pair, `None` when it was not run.
    #[inline]
    pub fn keller(&self, i: usize) -> Option<Option<(Real, Real)>> {
        self.keller[i]
    }
    /// All candidates in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = DiffractedCandidate<'_>> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }
    /// Append a candidate: `before` the edge (TX side first), the edge, `after` it.
    pub fn push(&mut self, before: &[SurfaceId], edge: EdgeId, after: &[SurfaceId]) {
        self.push_parts(&[before, after], edge, None);
        self.keller.push(None);
    }
    /// Append a candidate with two diffractions: `before` the first edge, `edges.0`, the
    /// reflections `between`, `edges.1`, `after` it, with its diffraction points' parameters
    /// when known ([`Self::keller`]).
    pub fn push_twice(
        &mut self,
        before: &[SurfaceId],
        edges: (EdgeId, EdgeId),
        between: &[SurfaceId],
        after: &[SurfaceId],
        keller: Option<Option<(Real, Real)>>,
    ) {
        let second = Some((edges.1, between.len() as u8));
        self.push_parts(&[before, between, after], edges.0, second);
        self.keller.push(keller);
    }
    /// Append the reflections `parts` (the first before the first edge) with the edges.
    fn push_parts(&mut self, parts: &[&[SurfaceId]], edge: EdgeId, second: Option<(EdgeId, u8)>) {
        for part in parts {
            self.ids.extend_from_slice(part);
        }
        self.offsets.push(self.ids.len() as u32);
        self.edges.push(edge);
        self.positions.push(parts[0].len() as u8);
        self.seconds.push(second);
    }
    /// Put the candidates in the canonical order and drop repeats.
    pub fn canonicalise(&mut self) {
        let widths = self.key_widths();
        // One integer holds the fields (and orders as they do) when their widths fit 64 bits:
        // a smaller sort; otherwise two 128-bit integers with room for any field.
        let order = if widths.iter().sum::<u32>() <= u64::BITS {
            let packed = (0..self.len()).map(|i| {
                let key = (self.key_fields(i).iter().zip(widths))
                    .fold(0u64, |key, (&v, w)| key.checked_shl(w).unwrap_or(0) | v);
                (key, i as u32)
            });
            self.canonical_order(packed.collect())
        } else {
            // Widths: order and position 8 bits, an edge 32, a reflection 33, the second 41.
            let packed = (0..self.len()).map(|i| {
                let k = self.key_fields(i).map(u128::from);
                let first = (k[0] << 120) | (k[1] << 112) | (k[2] << 80) | (k[3] << 40) | k[4];
                let next = (k[5] << 88) | (k[6] << 48) | (k[7] << 41) | k[8];
                ((first, next), i as u32)
            });
            self.canonical_order(packed.collect())
        };
        // Each candidate copied whole (its reflections are contiguous, its position and
        // second diffraction kept), into arrays sized once.
        let mut sorted = DiffractedSet {
            ids: Vec::with_capacity(self.ids.len()),
            offsets: Vec::with_capacity(order.len() + 1),
            edges: Vec::with_capacity(order.len()),
            positions: Vec::with_capacity(order.len()),
            seconds: Vec::with_capacity(order.len()),
            keller: Vec::with_capacity(order.len()),
        };
        sorted.offsets.push(0);
        for i in order {
            let i = i as usize;
            let (lo, hi) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
            sorted.ids.extend_from_slice(&self.ids[lo..hi]);
            sorted.offsets.push(sorted.ids.len() as u32);
            sorted.edges.push(self.edges[i]);
            sorted.positions.push(self.positions[i]);
            sorted.seconds.push(self.seconds[i]);
            sorted.keller.push(self.keller[i]);
        }
        *self = sorted;
    }

    /// Bits enough for each of [`Self::key_fields`]' fields of every candidate, from the
    /// largest ids, positions and lengths in the arrays (no key made). Any widths that hold
    /// the fields pack them into integers ordering as the fields do (in one integer or, past
    /// 64 bits, in two), so the order and the repeats dropped are those exact widths give.
    fn key_widths(&self) -> [u32; KEY_FIELDS] {
        fn most(values: impl Iterator<Item = u64>) -> u64 {
            values.max().unwrap_or(0)
        }
        let bits = |m: u64| u64::BITS - m.leading_zeros();
        let ids = most(self.ids.iter().map(|s| u64::from(s.0) + 1));
        let longest = most(self.offsets.windows(2).map(|w| u64::from(w[1] - w[0])));
        let edges = most(self.edges.iter().map(|e| u64::from(e.0)));
        let positions = most(self.positions.iter().map(|&p| u64::from(p)));
        let seconds = most((self.seconds.iter().flatten()).map(|(e, q)| {
            // The field [`Self::key_fields`] makes (or 0, for a long candidate).
            1 + ((u64::from(e.0) << 8) | u64::from(*q))
        }));
        let id = bits(ids);
        [
            bits(longest + 2),
            bits(positions),
            bits(edges),
            id,
            id,
            id,
            id,
            1,
            bits(seconds),
        ]
    }

    /// The sort key of candidate `i`, field by field, most significant first: its order,
    /// position and edge, its first four reflections (each id + 1, 0 when absent), whether
    /// more follow, and its second diffraction (0 with none or with more than four
    /// reflections, else 1 + (edge << 8 | reflections between)). Together they decide alone
    /// up to four reflections; longer lists only on ties ([`Self::canonical_order`]).
    #[inline(always)]
    fn key_fields(&self, i: usize) -> [u64; KEY_FIELDS] {
        // Read from the arrays (what [`Self::get`] gives, without making the candidate).
        let reflections = &self.ids[self.offsets[i] as usize..self.offsets[i + 1] as usize];
        let id = |k: usize| reflections.get(k).map_or(0, |s| u64::from(s.0) + 1);
        let long = reflections.len() > 4;
        let diffractions = 1 + usize::from(self.seconds[i].is_some());
        let second = match self.seconds[i] {
            Some((edge, q)) if !long => 1 + ((u64::from(edge.0) << 8) | u64::from(q)),
            _ => 0,
        };
        [
            (reflections.len() + diffractions) as u64,
            u64::from(self.positions[i]),
            u64::from(self.edges[i].0),
            id(0),
            id(1),
            id(2),
            id(3),
            u64::from(long),
            second,
        ]
    }

    /// The candidates' indices in canonical order, repeats dropped, from their packed keys
    /// (any integers ordering as [`Self::key_fields`] do): the keys sort almost everything;
    /// only runs of equal keys (more than four reflections) are ordered by the candidates
    /// themselves.
    fn canonical_order<K: Ord + Copy>(&self, mut keyed: Vec<(K, u32)>) -> Vec<u32> {
        let ties = |a: &(K, u32), b: &(K, u32)| {
            let (x, y) = (self.get(a.1 as usize), self.get(b.1 as usize));
            x.reflections
                .cmp(y.reflections)
                .then_with(|| x.second.cmp(&y.second))
        };
        keyed.sort_unstable_by_key(|k| k.0);
        for run in keyed.chunk_by_mut(|a, b| a.0 == b.0) {
            if run.len() > 1 {
                run.sort_unstable_by(ties);
            }
        }
        keyed.dedup_by(|a, b| a.0 == b.0 && ties(a, b).is_eq());
        keyed.into_iter().map(|(_, i)| i).collect()
    }
}

/// The fields of a candidate's sort key ([`DiffractedSet::key_fields`]).
const KEY_FIELDS: usize = 9;

/// The edges candidates may diffract on: those at least `min_edge_length` metres long, and
/// only when `max_order` leaves room for a diffraction.
pub fn usable_edges(scene: &Scene, min_edge_length: Real) -> impl Iterator<Item = EdgeId> + '_ {
    scene
        .edges()
        .all()
        .iter()
        .enumerate()
        .filter(move |(_, e)| e.length >= min_edge_length)
        .map(|(i, _)| EdgeId(i as u32))
}

/// Number of diffracted sequences up to `max_order` over `n` reflectors and `m` edges with
/// at most `max_diffractions` (1 or 2) diffractions (saturating): with one,
/// Σ_k Σ_p m·c(p)·c(k−1−p); with two also Σ_k Σ_(p+q+r = k−2) m·m'·c(p)·c(q)·c(r), m' = m − 1
/// when q = 0 (two edges in a row differ), else m; c(0) = 1, c(j) = n(n−1)^(j−1).
pub fn diffracted_count(n: u64, m: u64, max_order: usize, max_diffractions: usize) -> u64 {
    let c = |j: usize| -> u64 {
        match j {
            0 => 1,
            _ => n.saturating_mul(n.saturating_sub(1).saturating_pow(j as u32 - 1)),
        }
    };
    let mut total = 0u64;
    for k in 1..=max_order {
        for p in 0..k {
            total = total.saturating_add(m.saturating_mul(c(p)).saturating_mul(c(k - 1 - p)));
        }
        if max_diffractions < 2 || k < 2 {
            continue;
        }
        for p in 0..=k - 2 {
            for q in 0..=k - 2 - p {
                let pairs = m.saturating_mul(if q == 0 { m.saturating_sub(1) } else { m });
                let reflections = c(p).saturating_mul(c(q)).saturating_mul(c(k - 2 - p - q));
                total = total.saturating_add(pairs.saturating_mul(reflections));
            }
        }
    }
    total
}

/// Every diffracted sequence up to `max_order` with up to `max_diffractions` (1 or 2)
/// diffractions over the scene's reflectors and usable edges, unpruned: the reference
/// enumeration (its count is [`diffracted_count`]; callers check their budget first).
pub fn enumerate_diffracted(
    scene: &Scene,
    max_order: usize,
    diffracting: Diffracting,
) -> DiffractedSet {
    let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
    let edges: Vec<EdgeId> = usable_edges(scene, diffracting.min_edge_length).collect();
    let mut set = DiffractedSet::default();
    for k in 1..=max_order {
        for p in 0..k {
            let befores = sequences(&reflectors, p);
            let afters = sequences(&reflectors, k - 1 - p);
            for &edge in &edges {
                for before in &befores {
                    for after in &afters {
                        set.push(before, edge, after);
                    }
                }
            }
        }
        if diffracting.max_diffractions >= 2 && k >= 2 {
            enumerate_twice(&mut set, (&reflectors, &edges), k);
        }
    }
    set.canonicalise();
    set
}

/// Every sequence of order `k` with two diffractions into `set`.
fn enumerate_twice(
    set: &mut DiffractedSet,
    (reflectors, edges): (&[SurfaceId], &[EdgeId]),
    k: usize,
) {
    for p in 0..=k - 2 {
        for q in 0..=k - 2 - p {
            let befores = sequences(reflectors, p);
            let betweens = sequences(reflectors, q);
            let afters = sequences(reflectors, k - 2 - p - q);
            for &e1 in edges {
                for &e2 in edges.iter().filter(|&&e2| q > 0 || e2 != e1) {
                    for before in &befores {
                        for between in &betweens {
                            for after in &afters {
                                set.push_twice(before, (e1, e2), between, after, None);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Every sequence of `len` surfaces from `reflectors` with none twice in a row.
pub(crate) fn sequences(reflectors: &[SurfaceId], len: usize) -> Vec<Vec<SurfaceId>> {
    let mut out = vec![Vec::new()];
    for _ in 0..len {
        out = out
            .into_iter()
            .flat_map(|seq: Vec<SurfaceId>| {
                reflectors
                    .iter()
                    .filter(|s| seq.last() != Some(s))
                    .map(|s| {
                        let mut longer = seq.clone();
                        longer.push(*s);
                        longer
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_count_matches_the_enumeration() {
        let scene = bt_testkit::box_room([4.0, 3.0, 2.5], [1.0, 1.0, 1.0], [3.0, 2.0, 1.5]);
        let m = scene.edges().len() as u64;
        assert_eq!(m, 12);
        for order in 0..=3 {
            for max_diffractions in [1, 2] {
                let diffracting = Diffracting {
                    min_edge_length: 0.0,
                    max_diffractions,
                };
                let set = enumerate_diffracted(&scene, order, diffracting);
                assert_eq!(
                    set.len() as u64,
                    diffracted_count(6, m, order, max_diffractions),
                    "order {order}, {max_diffractions} diffractions"
                );
            }
        }
        // D: 12; RD, DR: 2·6·12; RRD, RDR, DRR: 6·5·12 + 6·6·12 + 6·5·12.
        assert_eq!(diffracted_count(6, 12, 3, 1), 12 + 144 + 360 + 432 + 360);
        // DD: 12·11; RDD, DDR: 6·12·11 each; DRD: 12·6·12.
        let twice = 132 + 2 * 792 + 864;
        assert_eq!(diffracted_count(6, 12, 3, 2), 1308 + twice);
    }

    /// The canonical order is the order of the candidates' key fields, then reflections, then
    /// second diffraction, with repeats dropped: on sets whose keys pack into one integer
    /// (small ids) and on sets that need two (ids up to `u32::MAX`), with long candidates
    /// that tie on the keys and repeats pushed in a shuffled order.
    #[test]
    fn canonical_order_sorts_by_the_key_fields_with_either_packing() {
        let mut state = 0x5eed_u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        for big in [false, true] {
            let id = |v: u64| if big { u32::MAX - v as u32 } else { v as u32 };
            let mut set = DiffractedSet::default();
            for _ in 0..3000 {
                let surfaces = |len: u64, next: &mut dyn FnMut(u64) -> u64| -> Vec<SurfaceId> {
                    (0..len).map(|_| SurfaceId(id(next(3)))).collect()
                };
                let before = surfaces(next(3), &mut next);
                let after = surfaces(next(4), &mut next);
                let edge = EdgeId(id(next(3)));
                if next(2) == 0 {
                    set.push(&before, edge, &after);
                } else {
                    let between = surfaces(next(2), &mut next);
                    let second = EdgeId(id(next(3)));
                    set.push_twice(&before, (edge, second), &between, &after, None);
                }
            }
            let mut expected: Vec<_> = (0..set.len())
                .map(|i| {
                    let c = set.get(i);
                    (set.key_fields(i), c.reflections.to_vec(), c.second)
                })
                .collect();
            expected.sort();
            expected.dedup();
            set.canonicalise();
            let got: Vec<_> = (0..set.len())
                .map(|i| {
                    let c = set.get(i);
                    (set.key_fields(i), c.reflections.to_vec(), c.second)
                })
                .collect();
            assert!(got.len() < 3000, "repeats were drawn");
            assert_eq!(got, expected, "big ids: {big}");
        }
    }
}
