//! Candidates with two diffractions from the two trees' reaches (issue 28).
//!
//! A path `s1..sp → D1 on E1 → m1..mq → D2 on E2 → s(p+q+1)..sk → RX` unfolds, through its
//! reflections, into a broken line `I → D1 → D2' → J'`: `I` the TX image of the TX tree's node
//! `s1..sp`, `J` the RX image of the RX tree's node, and `E2'`, `D2'`, `J'` the second edge,
//! its point and `J` mirrored through the middle reflections `mq..m1`. So
//! - `D1` lies in the TX node's reach on `E1`, `D2` in the RX node's reach on `E2` (the
//!   parameter along `E2'` is the one along `E2`);
//! - `(D1, D2')` is the two-point Keller solution of `I`, `E1`, `E2'`, `J'`
//!   ([`bt_scene::edges::keller_pair`]): the one stationary point of a convex length.
//!
//! The join keeps `(TX node, middle, RX node)` when that solution lies in both reaches, within
//! the tree's margin, or when it cannot be computed (validation decides): a superset of the
//! valid paths, which property tests check against blind enumeration.

use super::{Pairing, Reach};
use crate::beamtree::TreeError;
use crate::diffraction::DiffractedSet;
use bt_scene::edges::{EdgeLine, keller_pair};
use bt_scene::{EdgeId, Scene, SurfaceId};

impl Pairing<'_> {
    /// The candidates with two diffractions: every TX reach, RX reach and middle sequence
    /// whose depths fit the order (two edges in a row differ) and whose Keller pair lies in
    /// both reaches.
    pub(super) fn twice(&self, scene: &Scene, set: &mut DiffractedSet) -> Result<(), TreeError> {
        let deepest = self.side.max_order - 2;
        let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
        let middles: Vec<Vec<Vec<SurfaceId>>> = (0..=deepest)
            .map(|q| crate::diffraction::sequences(&reflectors, q))
            .collect();
        let shallow = |reaches: &[Vec<Reach>]| -> Vec<(usize, Reach)> {
            let mut out = Vec::new();
            for (e, on_edge) in reaches.iter().enumerate() {
                out.extend(
                    on_edge
                        .iter()
                        .filter(|r| r.depth <= deepest)
                        .map(|r| (e, *r)),
                );
            }
            out
        };
        let (tx, rx) = (shallow(&self.side.reaches), shallow(self.from_rx));
        let edges = scene.edges().all();
        let (mut before, mut after) = (Vec::new(), Vec::new());
        for (e1, a) in &tx {
            let first = EdgeLine::of(&edges[*e1]);
            for (e2, b) in rx.iter().filter(|(_, b)| a.depth + b.depth <= deepest) {
                for middle in middles[..=deepest - a.depth - b.depth].iter().flatten() {
                    if (middle.is_empty() && e1 == e2)
                        || !self.may_join(scene, (a, first), middle, (b, *e2))
                    {
                        continue;
                    }
                    self.surfaces((a.node, b.node), (&mut before, &mut after));
                    let pair = (EdgeId(*e1 as u32), EdgeId(*e2 as u32));
                    set.push_twice(&before, pair, middle, &after);
                    self.check_budget(set)?;
                }
            }
        }
        Ok(())
    }

    /// Whether TX reach `a` (on the line `first`), the `middle` reflections and RX reach `b`
    /// (on edge `e2`) may make a path: the Keller pair lies in both reaches, or cannot be
    /// computed.
    fn may_join(
        &self,
        scene: &Scene,
        (a, first): (&Reach, EdgeLine),
        middle: &[SurfaceId],
        (b, e2): (&Reach, usize),
    ) -> bool {
        let mut second = EdgeLine::of(&scene.edges().all()[e2]);
        let mut j = b.image;
        for id in middle.iter().rev() {
            let plane = scene.surface(*id).polygon.plane();
            second = second.mirrored(plane);
            j = plane.mirror(j);
        }
        let Some((t1, t2)) = keller_pair(a.image, first, second, j) else {
            return true;
        };
        let m = self.margin;
        t1 >= a.lo - m && t1 <= a.hi + m && t2 >= b.lo - m && t2 <= b.hi + m
    }
}
