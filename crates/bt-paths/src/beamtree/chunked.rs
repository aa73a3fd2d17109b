//! The materialised levels of a large scene's tree (culled as it is built), grown in chunks:
//! each chunk of parents (of the root's children, at depth 1) builds its nodes in arenas of
//! its own, with its own scratch, and the chunks are appended in order. No parent changes
//! while its level grows (culling at build tests each node once, as it is made), so the chunks
//! are independent and run on all cores when [`TreeOptions::parallel`] says so; fixed chunk
//! bounds make the tree the same on any number of threads.

use super::{
    BeamTree, BuildProgress, Leaf, Node, PROGRESS_EVERY, Prepared, Progress, ROOT, Scratch,
    TreeError, TreeStats,
};
use crate::CandidateSet;
use rayon::prelude::*;

/// Parents per chunk (a few milliseconds of a city's second level).
const CHUNK_PARENTS: usize = 32;
/// The root's children per chunk at depth 1.
const CHUNK_CHILDREN: usize = 512;

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
    /// budget and reporting progress after each round of chunks.
    pub(super) fn grow_level_chunked(
        &mut self,
        prep: &Prepared<'_>,
        depth: usize,
        progress: Progress<'_>,
    ) -> Result<(), TreeError> {
        let start = self.nodes.len();
        let parents = self.parents_of(depth);
        let work: Vec<Work<'_>> = match depth {
            1 => (prep.reflectors.chunks(CHUNK_CHILDREN).map(Work::Root)).collect(),
            _ => parents.chunks(CHUNK_PARENTS).map(Work::Parents).collect(),
        };
        // A round covers PROGRESS_EVERY parents (at depth 1, chunks of the root's children:
        // the root is done only when the level is).
        let per_round = (PROGRESS_EVERY / CHUNK_PARENTS).max(2);
        for (r, round) in work.chunks(per_round).enumerate() {
            let done = if depth == 1 {
                0
            } else {
                r * per_round * CHUNK_PARENTS
            };
            self.report(prep, depth, (done, parents.len()), progress);
            let grow = |w: &Work<'_>| self.grow_chunk(prep, *w);
            let parts: Vec<BeamTree> = match prep.options.parallel && round.len() > 1 {
                true => round.par_iter().map(grow).collect(),
                false => round.iter().map(grow).collect(),
            };
            for part in parts {
                self.absorb(part);
            }
            self.check_budget(prep, depth)?;
        }
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
        let per_round = (PROGRESS_EVERY / CHUNK_PARENTS).max(2);
        for (r, round) in chunks.chunks(per_round).enumerate() {
            self.report(
                prep,
                depth,
                (r * per_round * CHUNK_PARENTS, parents.len()),
                progress,
            );
            let grow = |ps: &&[u32]| self.leaves_of(prep, ps, &leaf.mirrored);
            let parts: Vec<(CandidateSet, u64)> = match prep.options.parallel && round.len() > 1 {
                true => round.par_iter().map(grow).collect(),
                false => round.iter().map(grow).collect(),
            };
            for (set, tested) in parts {
                leaf.out.append(&set);
                self.stats.tested += tested;
            }
        }
        self.end_level(start, false);
        Ok(())
    }

    /// The leaf candidates of `parents`' children against the RX of `mirrored`, and the
    /// children tested.
    fn leaves_of(
        &self,
        prep: &Prepared<'_>,
        parents: &[u32],
        mirrored: &std::sync::Arc<[(bt_geom::Real, bt_geom::Vec3)]>,
    ) -> (CandidateSet, u64) {
        let mut set = CandidateSet::with_starts();
        let mut leaf = Leaf::with_mirrored(mirrored.clone(), &mut set);
        let (mut children, mut tested) = (Vec::new(), 0);
        for &p in parents {
            let parent = self.parent_ref(prep, p);
            self.child_candidates(prep, &parent, true, &mut children);
            tested += children.len() as u64;
            leaf.apex_distances(&parent);
            for &s in &children {
                self.leaf_child(prep, &parent, s, &mut leaf);
            }
        }
        (set, tested)
    }

    /// The parents of level `depth`: the root, or the nodes of the level above.
    fn parents_of(&self, depth: usize) -> Vec<u32> {
        match depth {
            1 => vec![ROOT],
            _ => {
                let (lo, hi) = self.levels[depth - 2];
                (lo as u32..hi as u32).collect()
            }
        }
    }

    /// Report `done` of `parents` parents of level `depth` to `progress`.
    fn report(
        &self,
        prep: &Prepared<'_>,
        depth: usize,
        (done, parents): (usize, usize),
        progress: Progress<'_>,
    ) {
        progress(BuildProgress {
            depth,
            max_order: prep.options.max_order,
            parents_done: done.min(parents),
            parents,
            nodes: self.nodes.len() as u64,
        });
    }

    /// The nodes `work` grows, in arenas of their own (node windows and beam planes index
    /// them; parents are this tree's nodes).
    fn grow_chunk(&self, prep: &Prepared<'_>, work: Work<'_>) -> BeamTree {
        let mut part = self.part();
        let mut scratch = Scratch::default();
        match work {
            Work::Root(children) => {
                let parent = self.parent_ref(prep, ROOT);
                part.stats.tested += children.len() as u64;
                for &s in children {
                    part.child(prep, &parent, s, &mut scratch);
                }
            }
            Work::Parents(parents) => {
                let mut children = Vec::new();
                for &p in parents {
                    let parent = self.parent_ref(prep, p);
                    self.child_candidates(prep, &parent, false, &mut children);
                    part.stats.tested += children.len() as u64;
                    for &s in &children {
                        part.child(prep, &parent, s, &mut scratch);
                    }
                }
            }
        }
        part
    }

    /// An empty tree of the same build, to grow a chunk's nodes in.
    fn part(&self) -> BeamTree {
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

/// `f` of each chunk of [`CHUNK_CHILDREN`] `items`, in order; on all cores when the build's
/// options say so (fixed chunks: the same results on any number of threads).
pub(super) fn map_chunks<R: Send>(
    prep: &Prepared<'_>,
    items: &[u32],
    f: impl Fn(&[u32]) -> R + Sync,
) -> Vec<R> {
    match prep.options.parallel && items.len() > CHUNK_CHILDREN {
        true => items.par_chunks(CHUNK_CHILDREN).map(&f).collect(),
        false => items.chunks(CHUNK_CHILDREN).map(f).collect(),
    }
}
