//! Candidates with one edge diffraction: reflections before the edge, the edge, reflections
//! after it ([`DiffractedSet`]), and their blind enumeration, the reference the beam tree's
//! join ([`crate::beamtree`]) is checked against.
//!
//! A diffracted candidate of order `k` has `k` interactions, one of them the diffraction at
//! position `p` (the number of reflections before it): D, R-D, D-R, R-D-R, ... No surface
//! appears twice in a row among the reflections on either side of the edge.

use bt_geom::Real;
use bt_scene::{EdgeId, Scene, SurfaceId};

/// One diffracted candidate, borrowed from its set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiffractedCandidate<'a> {
    /// Every reflection of the candidate, TX side first (the edge left out).
    pub reflections: &'a [SurfaceId],
    /// The diffracting edge.
    pub edge: EdgeId,
    /// The number of reflections before the edge (the diffraction's index among the points).
    pub position: usize,
}

impl<'a> DiffractedCandidate<'a> {
    /// The reflections between TX and the edge.
    pub fn before(&self) -> &'a [SurfaceId] {
        &self.reflections[..self.position]
    }
    /// The reflections between the edge and RX.
    pub fn after(&self) -> &'a [SurfaceId] {
        &self.reflections[self.position..]
    }
    /// Number of interactions (reflections plus the diffraction).
    pub fn order(&self) -> usize {
        self.reflections.len() + 1
    }
}

/// A set of diffracted candidates, stored flat, in a canonical order: by order, position,
/// edge, then reflections (so two generators of the same candidates give equal sets).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiffractedSet {
    ids: Vec<SurfaceId>,
    offsets: Vec<u32>,
    edges: Vec<EdgeId>,
    positions: Vec<u8>,
}

impl Default for DiffractedSet {
    fn default() -> Self {
        DiffractedSet {
            ids: Vec::new(),
            offsets: vec![0],
            edges: Vec::new(),
            positions: Vec::new(),
        }
    }
}

impl DiffractedSet {
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
        }
    }
    /// All candidates in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = DiffractedCandidate<'_>> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }
    /// Append a candidate: `before` the edge (TX side first), the edge, `after` it.
    pub fn push(&mut self, before: &[SurfaceId], edge: EdgeId, after: &[SurfaceId]) {
        self.ids.extend_from_slice(before);
        self.ids.extend_from_slice(after);
        self.offsets.push(self.ids.len() as u32);
        self.edges.push(edge);
        self.positions.push(before.len() as u8);
    }
    /// Put the candidates in the canonical order and drop repeats.
    pub fn canonicalise(&mut self) {
        // (order, position, edge, first two reflections) packed into one integer, which
        // decides alone up to order 3; longer reflection lists only on ties.
        let mut keyed: Vec<(u128, u32)> = (0..self.len())
            .map(|i| {
                let c = self.get(i);
                let id = |k: usize| c.reflections.get(k).map_or(0, |s| u128::from(s.0) + 1);
                let key = ((c.order() as u128) << 120)
                    | ((c.position as u128) << 112)
                    | (u128::from(c.edge.0) << 80)
                    | (id(0) << 40)
                    | id(1);
                (key, i as u32)
            })
            .collect();
        let compare = |a: &(u128, u32), b: &(u128, u32)| {
            a.0.cmp(&b.0).then_with(|| {
                let (x, y) = (self.get(a.1 as usize), self.get(b.1 as usize));
                x.reflections.cmp(y.reflections)
            })
        };
        keyed.sort_unstable_by(compare);
        keyed.dedup_by(|a, b| compare(a, b).is_eq());
        let mut sorted = DiffractedSet::default();
        for (_, i) in keyed {
            let c = self.get(i as usize);
            sorted.push(c.before(), c.edge, c.after());
        }
        *self = sorted;
    }
}

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

/// Number of diffracted sequences up to `max_order` over `n` reflectors and `m` edges
/// (saturating): Σ_k Σ_p m·c(p)·c(k−1−p), with c(0) = 1, c(j) = n(n−1)^(j−1).
pub fn diffracted_count(n: u64, m: u64, max_order: usize) -> u64 {
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
    }
    total
}

/// Every diffracted sequence up to `max_order` over the scene's reflectors and usable edges,
/// unpruned: the reference enumeration (its count is [`diffracted_count`]; callers check
/// their budget first).
pub fn enumerate_diffracted(
    scene: &Scene,
    max_order: usize,
    min_edge_length: Real,
) -> DiffractedSet {
    let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
    let edges: Vec<EdgeId> = usable_edges(scene, min_edge_length).collect();
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
    }
    set.canonicalise();
    set
}

/// Every sequence of `len` surfaces from `reflectors` with none twice in a row.
fn sequences(reflectors: &[SurfaceId], len: usize) -> Vec<Vec<SurfaceId>> {
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
            let set = enumerate_diffracted(&scene, order, 0.0);
            assert_eq!(
                set.len() as u64,
                diffracted_count(6, m, order),
                "order {order}"
            );
        }
        // D: 12; RD, DR: 2·6·12; RRD, RDR, DRR: 6·5·12 + 6·6·12 + 6·5·12.
        assert_eq!(diffracted_count(6, 12, 3), 12 + 144 + 360 + 432 + 360);
    }
}
