//! The materialised levels of a large scene's tree (culled as it is built), grown in chunks:
//! each chunk of parents (of the root's children, at depth 1) builds its nodes in arenas of
//! its own, with its own scratch, and the chunks are appended in order. No parent changes
//! while its level grows (culling at build tests each node once, as it is made), so the chunks
//! are independent and run on all cores when [`TreeOptions::parallel`] says so; fixed chunk
//! bounds make the tree the same on any number of threads.

use super::join::Pairs;
use super::{
    BeamTree, Leaf, Mirrored, Node, PROGRESS_EVERY, Prepared, Probe, Progress, ROOT, Scratch,
    TreeError, TreeStats,
};
use crate::CandidateSet;
use rayon::prelude::*;

/// Parents per chunk (a few milliseconds of a city's second level).
pub(super) const CHUNK_PARENTS: usize = 32;
/// The root's children per chunk at depth 1.
const CHUNK_CHILDREN: usize = 512;
/// Rounds of chunks grown at once ([`BeamTree::in_rounds`]): 2,048 parents at depth 2 and
/// beyond, 32,768 children of the root at depth 1.
const ROUNDS_PER_BATCH: usize = 8;

/// What one chunk grows.
#[derive(Clone, Copy)]
enum Work<'w> {
    /// These children of the root.
    Root(&'w [u32]),
    /// Every child of these parents.
    Parents(&'w [u32]),
}

impl BeamTree {
    /// Grow materialised level `depth` chunk by chunk (see the module), checking the node
    /// budget and reporting progress after each round of chunks. With `probe` (RX and its
    /// mirror images), only the nodes that can end or lead to a candidate for that RX are
    /// culled and kept ([`Probe`]); with `joined` too, each parent tries only the children
    /// the RX-side join pairs it with ([`Pairs`]) (all of them still count as tested).
    pub(super) fn grow_level_chunked(
        &mut self,
        prep: &Prepared<'_>,
        depth: usize,
        (probe, joined): (Option<&(bt_geom::Vec3, Mirrored)>, Option<&Pairs>),
        progress: Progress<'_>,
    ) -> Result<(), TreeError> {
        let start = self.nodes.len();
        let parents = self.parents_of(depth);
        let work: Vec<Work<'_>> = match depth {
            1 => (prep.reflectors.chunks(CHUNK_CHILDREN).map(Work::Root)).collect(),
            _ => parents.chunks(CHUNK_PARENTS).map(Work::Parents).collect(),
        };
        self.in_rounds(
            prep,
            (depth, parents.len(), &work),
            progress,
            |tree, w| tree.grow_chunk(prep, *w, (probe, joined)),
            BeamTree::absorb,
        )?;
        self.end_level(start, true);
        Ok(())
    }

    /// The last level of a single-receiver trace ([`Leaf`]) chunk by chunk: each chunk of
    /// parents emits its candidates into a set of its own, appended to `leaf`'s in order.
    pub(super) fn grow_leaves_chunked(
        &mut self,
        prep: &Prepared<'_>,
        depth: usize,
        leaf: &mut Leaf<'_>,
        progress: Progress<'_>,
    ) -> Result<(), TreeError> {
        let start = self.nodes.len();
        let parents = self.parents_of(depth);
        let chunks: Vec<&[u32]> = parents.chunks(CHUNK_PARENTS).collect();
        let mirrored = leaf.test.mirrored.clone();
        self.in_rounds(
            prep,
            (depth, parents.len(), &chunks),
            progress,
            |tree, ps| tree.leaves_of(prep, ps, &mirrored),
            |tree, (set, tested)| {
                leaf.out.append(&set);
                tree.stats.tested += tested;
            },
        )?;
        self.end_level(start, false);
        Ok(())
    }

    /// `grow` each chunk of `work` (of level `depth`, which has `parents` parents) and `merge`
    /// its result into the tree, in order, a round of chunks at a time: the node budget is
    /// checked and progress reported each round (about [`PROGRESS_EVERY`] parents; at depth 1
    /// the root is done only when the level is). The chunks of [`ROUNDS_PER_BATCH`] rounds
    /// are grown at once before their rounds are reported, merged and checked in order: the
    /// cores wait for each other once a batch instead of once a round (a round is a few
    /// chunks, so at its end one core often idles while the other grows the last). The
    /// reports, the tree and the budget's verdict are those of growing round by round; only
    /// the chunks of the batch after a round that exceeds the budget are grown in vain.
    fn in_rounds<W: Sync, R: Send>(
        &mut self,
        prep: &Prepared<'_>,
        (depth, parents, work): (usize, usize, &[W]),
        progress: Progress<'_>,
        grow: impl Fn(&Self, &W) -> R + Sync,
        mut merge: impl FnMut(&mut Self, R),
    ) -> Result<(), TreeError> {
        let per_round = (PROGRESS_EVERY / CHUNK_PARENTS).max(2);
        let mut r = 0;
        for batch in work.chunks(per_round * ROUNDS_PER_BATCH) {
            let tree = &*self;
            let mut grown = in_order(prep, batch, |w| grow(tree, w)).into_iter();
            while grown.len() > 0 {
                let done = if depth == 1 {
                    0
                } else {
                    r * per_round * CHUNK_PARENTS
                };
                self.report(prep, depth, (done, parents), progress);
                for part in grown.by_ref().take(per_round) {
                    merge(self, part);
                }
                self.check_budget(prep, depth)?;
                r += 1;
            }
        }
        Ok(())
    }

    /// The leaf candidates of `parents`' children against the RX of `mirrored`, and the
    /// children tested.
    fn leaves_of(
        &self,
        prep: &Prepared<'_>,
        parents: &[u32],
        mirrored: &Mirrored,
    ) -> (CandidateSet, u64) {
        let mut set = CandidateSet::with_starts();
        let mut leaf = Leaf::with_mirrored(mirrored.clone(), &mut set);
        let (mut children, mut tested) = (Vec::new(), 0);
        for &p in parents {
            let parent = self.parent_ref(prep, p);
            self.child_candidates(prep, &parent, true, &mut children);
            tested += children.len() as u64;
            leaf.test.apex_distances(&parent);
            for &s in &children {
                self.leaf_child(prep, &parent, s, &mut leaf);
            }
        }
        (set, tested)
    }

    /// The nodes `work` grows, in arenas of their own (node windows and beam planes index
    /// them; parents are this tree's nodes).
    fn grow_chunk(
        &self,
        prep: &Prepared<'_>,
        work: Work<'_>,
        (probe, joined): (Option<&(bt_geom::Vec3, Mirrored)>, Option<&Pairs>),
    ) -> BeamTree {
        let mut part = self.part();
        let mut scratch = Scratch::default();
        let mut probe = probe.map(|(rx, m)| Probe::new(*rx, m.clone()));
        match work {
            Work::Root(children) => {
                let parent = self.parent_ref(prep, ROOT);
                part.stats.tested += children.len() as u64;
                for &s in children {
                    let probing = probe.as_mut().map(|p| (p, None));
                    part.child_probed(prep, &parent, s, &mut scratch, probing);
                }
            }
            Work::Parents(parents) => {
                let mut children = Vec::new();
                for &p in parents {
                    let parent = self.parent_ref(prep, p);
                    if let Some(pairs) = joined {
                        let (kept, tried) = pairs.of_parent(p);
                        part.stats.tested += tried;
                        for child in kept {
                            let probing = probe.as_mut().map(|p| (p, pairs.leaves(child)));
                            part.child_probed(prep, &parent, child.s, &mut scratch, probing);
                        }
                        continue;
                    }
                    self.child_candidates(prep, &parent, false, &mut children);
                    part.stats.tested += children.len() as u64;
                    for &s in &children {
                        let probing = probe.as_mut().map(|p| (p, None));
                        part.child_probed(prep, &parent, s, &mut scratch, probing);
                    }
                }
            }
        }
        part
    }

    /// An empty tree of the same build, to grow a chunk's nodes in.
    pub(super) fn part(&self) -> BeamTree {
        BeamTree {
            max_order: self.max_order,
            tol: self.tol,
            options: self.options,
            tx: self.tx,
            reflectors: Vec::new(),
            surfaces: self.surfaces,
            nodes: Vec::new(),
            levels: Vec::new(),
            verts: Vec::new(),
            planes: Vec::new(),
            stats: TreeStats::default(),
        }
    }

    /// Append `part`'s nodes (a chunk grown by [`BeamTree::grow_chunk`]) and its statistics.
    fn absorb(&mut self, part: BeamTree) {
        let shift = |(lo, hi): (u32, u32), by: u32| (lo + by, hi + by);
        let (verts, planes) = (self.verts.len() as u32, self.planes.len() as u32);
        self.verts.extend_from_slice(&part.verts);
        self.planes.extend_from_slice(&part.planes);
        self.nodes.extend(part.nodes.iter().map(|n| Node {
            window: shift(n.window, verts),
            planes: shift(n.planes, planes),
            ..*n
        }));
        self.stats.absorb(&part.stats);
    }
}

/// `f` of each chunk of `size` `items` ([`CHUNK_CHILDREN`] when `None`), in order (see
/// [`in_order`]).
pub(super) fn map_chunks<R: Send>(
    prep: &Prepared<'_>,
    (items, size): (&[u32], Option<usize>),
    f: impl Fn(&[u32]) -> R + Sync,
) -> Vec<R> {
    let chunks: Vec<&[u32]> = items.chunks(size.unwrap_or(CHUNK_CHILDREN)).collect();
    in_order(prep, &chunks, |c| f(c))
}

/// `f` of each of `items`, in order; on all cores when the build's options say so and there
/// is more than one (each item is the same work on any number of threads).
fn in_order<T: Sync, R: Send>(
    prep: &Prepared<'_>,
    items: &[T],
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    in_order_if(prep.options.parallel, items, f)
}

/// `f` of each of `items`, in order; on all cores when `parallel` and there is more than one.
pub(super) fn in_order_if<T: Sync, R: Send>(
    parallel: bool,
    items: &[T],
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    match parallel && items.len() > 1 {
        true => items.par_iter().map(&f).collect(),
        false => items.iter().map(f).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{BeamTree, BuildProgress, Culling, TreeError, TreeOptions};
    use super::*;

    /// Parents of one batch of rounds ([`ROUNDS_PER_BATCH`]) at depth 2 and beyond.
    const BATCH_PARENTS: usize =
        (PROGRESS_EVERY / CHUNK_PARENTS) * CHUNK_PARENTS * ROUNDS_PER_BATCH;

    /// A scene whose tree at order 4 has several batches of parents at depth 3, and the
    /// options (one thread) that grow it in chunks: culled as it is built (the scene's 80
    /// surfaces are not all reflectors, so it would not be by default).
    fn batched() -> (bt_scene::Scene, TreeOptions) {
        let options = TreeOptions {
            culling: Culling::Always,
            ..TreeOptions::new(4)
        };
        (bt_testkit::random_scene(3, 80), options)
    }

    /// The kept tree of a scene, its RX's candidates, and the progress reports of its build.
    fn grown(
        scene: &bt_scene::Scene,
        options: TreeOptions,
    ) -> (BeamTree, Vec<Vec<u32>>, Vec<BuildProgress>) {
        let mut reports = Vec::new();
        let tree = BeamTree::build_with_progress(scene, options, &mut |p| reports.push(p)).unwrap();
        let set = tree.candidates(scene.rx().unwrap());
        let listing = set
            .iter()
            .map(|s| s.iter().map(|id| id.0).collect())
            .collect();
        (tree, listing, reports)
    }

    /// A level of several batches of parents grown on all cores is the level grown on one
    /// thread (the batches are appended in order), and both report progress every
    /// [`PROGRESS_EVERY`] parents, as rounds grown one at a time did.
    #[test]
    fn levels_of_several_batches_grow_as_on_one_thread() {
        let (scene, one) = batched();
        let (a, walk_a, reports_a) = grown(&scene, one);
        let (b, walk_b, reports_b) = grown(
            &scene,
            TreeOptions {
                parallel: true,
                ..one
            },
        );
        let parents = a.stats().nodes_per_depth[2] as usize;
        assert!(parents > 2 * BATCH_PARENTS, "{parents} parents at depth 3");
        assert_eq!(a.stats(), b.stats());
        assert!(walk_a == walk_b, "the walks differ");
        assert_eq!(reports_a, reports_b);
        let done: Vec<usize> = (reports_a.iter())
            .filter(|p| p.depth == 4)
            .map(|p| p.parents_done)
            .collect();
        let expected: Vec<usize> = (0..parents).step_by(PROGRESS_EVERY).collect();
        assert_eq!(done, expected);
    }

    /// A budget exceeded in the middle of a level of several batches stops the build on one
    /// thread and on all at the end of the round that exceeds it, as rounds grown one at a
    /// time did: with the nodes the next round's progress report counts.
    #[test]
    fn the_budget_stops_a_batched_level_after_the_round_that_exceeds_it() {
        let (scene, options) = batched();
        let (full, _, reports) = grown(&scene, options);
        // The nodes after each round of depth 4, the last one's being the whole tree's.
        let mut after: Vec<u64> = (reports.iter())
            .filter(|p| p.depth == 4 && p.parents_done > 0)
            .map(|p| p.nodes)
            .collect();
        after.push(full.len() as u64);
        let budget = after[after.len() / 2] - 1;
        let expected = after[after.len() / 2];
        for parallel in [false, true] {
            let options = TreeOptions {
                max_nodes: budget,
                parallel,
                ..options
            };
            match BeamTree::build(&scene, options) {
                Err(TreeError::Budget { nodes, depth, .. }) => {
                    assert_eq!((nodes, depth), (expected, 4), "parallel: {parallel}");
                }
                other => panic!("{:?}", other.map(|t| t.len())),
            }
        }
    }
}
