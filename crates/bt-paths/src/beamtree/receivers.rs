//! Many receivers of one kept tree (a coverage sweep, `trace_many`): which nodes' beams may
//! hold each receiver, found for boxes of nearby receivers at a time instead of testing every
//! node against every receiver. A node is dropped for a box only when one of its beam's planes
//! has the whole box (grown for rounding) beyond the margin [`BeamTree::holds`] keeps, so no
//! node that holds a receiver in the box is lost: [`BeamTree::candidates_among`] then gives
//! each receiver exactly the set of [`BeamTree::candidates`], in the same order.

use super::{BeamTree, EPS};
use bt_geom::{Real, Vec3};

/// Receivers per box below which a box is not halved again.
const LEAF_RECEIVERS: usize = 4;

/// Receivers per half from which the two halves of a box are narrowed in parallel.
const PARALLEL_RECEIVERS: usize = 32;

/// For each receiver, the tree's live nodes whose beams may hold it, in node order
/// ([`BeamTree::receiver_nodes`]).
#[derive(Debug, Clone, Default)]
pub struct ReceiverNodes {
    /// Node lists, one per box of receivers.
    lists: Vec<Vec<u32>>,
    /// Per receiver: its box's list.
    list_of: Vec<u32>,
}

impl ReceiverNodes {
    /// The nodes (ascending indices) that may hold receiver `k` (an index into the receivers
    /// given to [`BeamTree::receiver_nodes`]).
    pub fn of(&self, k: usize) -> &[u32] {
        &self.lists[self.list_of[k] as usize]
    }
}

impl BeamTree {
    /// The live nodes whose beams may hold each of `receivers` (metres, the tree's frame): a
    /// superset of the nodes that hold it, in node order. Receivers with a non-finite
    /// coordinate get every live node. The halves of a large box are narrowed side by side
    /// on rayon's pool when `parallel`; the answer is the same.
    pub fn receiver_nodes(&self, receivers: &[Vec3], parallel: bool) -> ReceiverNodes {
        let live: Vec<u32> = (self.levels.iter().flat_map(|&(lo, hi)| lo..hi))
            .filter(|&i| self.nodes[i].live)
            .map(|i| i as u32)
            .collect();
        // List 0, every live node, for receivers with a non-finite coordinate (no box).
        let mut out = ReceiverNodes {
            lists: vec![live.clone()],
            list_of: vec![0; receivers.len()],
        };
        let mut ids: Vec<u32> = (0..receivers.len() as u32)
            .filter(|&k| receivers[k as usize].is_finite())
            .collect();
        let mut boxes = Vec::new();
        self.split_box(receivers, &mut ids, live, parallel, &mut boxes);
        // The boxes cover `ids` in order, each a run of them.
        let mut at = 0;
        for (count, nodes) in boxes {
            let list = out.lists.len() as u32;
            for &k in &ids[at..at + count] {
                out.list_of[k as usize] = list;
            }
            out.lists.push(nodes);
            at += count;
        }
        out
    }

    /// Narrows `nodes` to those whose beams may meet the box of the receivers `ids` (finite),
    /// then halves the box along its longest side, down to [`LEAF_RECEIVERS`]; appends each
    /// final box to `boxes`, in the order of `ids` (reordered in place): how many receivers
    /// it has and its nodes.
    fn split_box(
        &self,
        receivers: &[Vec3],
        ids: &mut [u32],
        nodes: Vec<u32>,
        parallel: bool,
        boxes: &mut Vec<(usize, Vec<u32>)>,
    ) {
        let Some((lo, hi)) = (ids.iter().map(|&k| receivers[k as usize]))
            .map(|p| (p, p))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        else {
            return;
        };
        let nodes: Vec<u32> = (nodes.into_iter())
            .filter(|&i| self.may_hold_box(i as usize, lo, hi))
            .collect();
        if ids.len() <= LEAF_RECEIVERS || nodes.is_empty() {
            boxes.push((ids.len(), nodes));
            return;
        }
        let axis = (hi - lo).max_position();
        let half = ids.len() / 2;
        ids.select_nth_unstable_by(half, |&a, &b| {
            receivers[a as usize][axis].total_cmp(&receivers[b as usize][axis])
        });
        let (first, second) = ids.split_at_mut(half);
        if parallel && first.len() >= PARALLEL_RECEIVERS {
            let copy = nodes.clone();
            let mut later = Vec::new();
            rayon::join(
                || self.split_box(receivers, first, copy, parallel, boxes),
                || self.split_box(receivers, second, nodes, parallel, &mut later),
            );
            boxes.append(&mut later);
        } else {
            self.split_box(receivers, first, nodes.clone(), parallel, boxes);
            self.split_box(receivers, second, nodes, parallel, boxes);
        }
    }

    /// Whether some point of the box `lo..hi` may lie in node `i`'s beam as
    /// [`BeamTree::holds`] tests it: no plane has the whole box beyond its margin. Each plane's
    /// largest value over the box is computed at the box's centre plus the half-extent along
    /// the normal, with slack for the rounding of both this bound and the point test.
    fn may_hold_box(&self, i: usize, lo: Vec3, hi: Vec3) -> bool {
        let (first, last) = self.nodes[i].planes;
        let eps = EPS * self.tol;
        let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let size = centre.abs() + half;
        self.planes[first as usize..last as usize].iter().all(|pl| {
            let most = pl.normal.dot(centre) + pl.normal.abs().dot(half) - pl.offset;
            let slack = 16.0 * Real::EPSILON * (pl.normal.abs().dot(size) + pl.offset.abs());
            most >= -eps - slack
        })
    }
}
