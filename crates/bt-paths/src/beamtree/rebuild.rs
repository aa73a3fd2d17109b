//! Time steps: a tree rebuilt after some surfaces moved reuses every subtree the motion cannot
//! have changed ([`BeamTree::rebuild`]).
//!
//! A node depends on its prefix's planes and hulls (its image source and window), on TX, and on
//! the occluders that culled or shrank it. A child exists where a reflector's hull meets the
//! parent's beam. So, while TX, the tolerance and every recorded occluder stay, a node whose
//! prefix holds no moved surface is the same node: it is copied, and so are its children
//! except those on a moved reflector, which are tested afresh (as every child of a node whose
//! prefix holds a moved surface is). Occlusion culling by a moved surface in its new place is
//! not applied to copied nodes: culling only removes work, never paths, so the rebuilt tree
//! holds every node of a fresh build and may keep a few it would have culled.

use super::{BeamTree, Prepared, ROOT, Scratch, TreeCache, TreeError};
use crate::beamtree::Progress;
use bt_geom::Plane;
use bt_geom::bvh::box_meets_halfspaces;
use bt_scene::{Scene, SurfaceId};
use serde::Serialize;

/// What [`BeamTree::rebuild`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct RebuildStats {
    /// The tree was built from scratch (TX, tolerance, surfaces or an occluder changed).
    pub full: bool,
    /// Nodes copied from the previous tree.
    pub reused: u64,
    /// Nodes built anew.
    pub built: u64,
}

/// Per-rebuild lookup tables.
struct Moved {
    /// Whether each surface moved.
    is_moved: Vec<bool>,
    /// The moved reflectors, ascending.
    reflectors: Vec<u32>,
}

impl BeamTree {
    /// The tree of `scene` (the same surfaces as the tree's scene, `moved` of them moved),
    /// reusing every node the motion cannot have changed (their windows and beam planes stay
    /// where they are: the new tree takes this tree's storage). Equal to
    /// [`BeamTree::build`]`(scene, options)` but for nodes a moved occluder would now cull.
    pub fn rebuild(
        self,
        scene: &Scene,
        moved: &[SurfaceId],
    ) -> Result<(BeamTree, RebuildStats), TreeError> {
        self.rebuild_with_progress(scene, moved, &mut |_| {})
    }

    /// [`BeamTree::rebuild`], reporting to `progress`.
    pub fn rebuild_with_progress(
        mut self,
        scene: &Scene,
        moved: &[SurfaceId],
        progress: Progress<'_>,
    ) -> Result<(BeamTree, RebuildStats), TreeError> {
        if !self.reusable(scene, moved) {
            let tree = BeamTree::build_with_progress(scene, self.options, progress)?;
            let built = tree.len() as u64;
            let stats = RebuildStats {
                full: true,
                reused: 0,
                built,
            };
            return Ok((tree, stats));
        }
        // The moved surfaces make this another geometry: no kept shapes would match.
        let prep = Prepared::new(scene, self.options, &mut TreeCache::default())?;
        let mut is_moved = vec![false; self.surfaces];
        moved.iter().for_each(|id| is_moved[id.index()] = true);
        let mut reflectors: Vec<u32> = moved
            .iter()
            .map(|id| id.0)
            .filter(|&s| prep.is_reflector[s as usize])
            .collect();
        reflectors.sort_unstable();
        reflectors.dedup();
        let moved = Moved {
            is_moved,
            reflectors,
        };
        let mut tree = BeamTree::empty(&prep);
        tree.stats.occluders = self.stats.occluders.clone();
        // Copied nodes keep their ranges in the arenas, which the new tree takes over.
        tree.verts = std::mem::take(&mut self.verts);
        tree.planes = std::mem::take(&mut self.planes);
        // Per node of `tree`: its twin in `self` when copied.
        let mut origin: Vec<Option<u32>> = Vec::new();
        let children = self.child_ranges();
        let ctx = Regrow {
            old: &self,
            children: &children,
            moved: &moved,
        };
        let mut scratch = Scratch::default();
        for depth in 1..=self.options.max_order {
            tree.regrow_level(&prep, &ctx, depth, &mut origin, &mut scratch, progress)?;
        }
        tree.compact();
        let reused = origin.iter().filter(|o| o.is_some()).count() as u64;
        let stats = RebuildStats {
            full: false,
            reused,
            built: tree.len() as u64 - reused,
        };
        Ok((tree, stats))
    }

    /// Whether nodes of this tree can serve `scene` after `moved` moved: same options (they
    /// are this tree's), TX, surfaces and reflectors, a tolerance no larger (copied nodes keep
    /// their wider margins), and no moved surface culled or shrank a node.
    fn reusable(&self, scene: &Scene, moved: &[SurfaceId]) -> bool {
        scene.surfaces().len() == self.surfaces
            && scene.tx() == Some(self.tx)
            && scene.length_tolerance() <= self.tol
            && scene
                .reflectors()
                .map(|id| id.0)
                .eq(self.reflectors.iter().copied())
            && moved.iter().all(|id| {
                id.index() < self.surfaces && self.stats.occluders.binary_search(&id.0).is_err()
            })
    }

    /// Per node, the range of its children in `nodes` (children of one parent are contiguous:
    /// a level is built parent by parent).
    fn child_ranges(&self) -> Vec<(u32, u32)> {
        let mut ranges = vec![(0u32, 0u32); self.nodes.len()];
        for (i, node) in self.nodes.iter().enumerate() {
            if node.parent == ROOT {
                continue;
            }
            let r = &mut ranges[node.parent as usize];
            if r.1 == 0 {
                *r = (i as u32, i as u32 + 1);
            } else {
                r.1 = i as u32 + 1;
            }
        }
        ranges
    }

    /// Copy node `i` of `old` under `parent` (its window and beam planes are in the arenas
    /// this tree took over).
    fn copy_node(&mut self, old: &BeamTree, i: u32, parent: u32) {
        self.nodes.push(super::Node {
            parent,
            ..old.nodes[i as usize]
        });
    }

    /// Drop the windows and planes of nodes a rebuild left behind once they outweigh the
    /// ones in use.
    fn compact(&mut self) {
        let len = |r: (u32, u32)| (r.1 - r.0) as usize;
        let used: usize = self.nodes.iter().map(|n| len(n.window)).sum();
        if self.verts.len() <= 2 * used + 1024 {
            return;
        }
        let (verts, planes) = (
            std::mem::take(&mut self.verts),
            std::mem::take(&mut self.planes),
        );
        for n in &mut self.nodes {
            n.window = super::push_range(
                &mut self.verts,
                &verts[n.window.0 as usize..n.window.1 as usize],
            );
            n.planes = super::push_range(
                &mut self.planes,
                &planes[n.planes.0 as usize..n.planes.1 as usize],
            );
        }
    }

    /// Build depth `depth` of a rebuild: copied parents keep their unmoved children and test
    /// the moved reflectors; other parents grow all their children.
    fn regrow_level(
        &mut self,
        prep: &Prepared<'_>,
        ctx: &Regrow<'_>,
        depth: usize,
        origin: &mut Vec<Option<u32>>,
        scratch: &mut Scratch,
        progress: Progress<'_>,
    ) -> Result<(), TreeError> {
        self.for_each_parent(prep, (depth, true), progress, |tree, p, bufs| {
            let twin = match p {
                ROOT => Some(ROOT),
                _ => origin[p as usize],
            };
            match twin {
                Some(twin) => tree.merge_children(prep, ctx, (p, twin), origin, scratch, bufs.0),
                None => {
                    tree.grow_children(prep, p, depth, scratch, None, bufs);
                    origin.resize(tree.nodes.len(), None);
                }
            }
            debug_assert_eq!(origin.len(), tree.nodes.len());
        })
    }

    /// The children of parent `p`, whose twin in the old tree is `twin`: the twin's children
    /// off the moved reflectors (copied, in order), merged by surface index with the moved
    /// reflectors that meet the beam (tested afresh).
    fn merge_children(
        &mut self,
        prep: &Prepared<'_>,
        ctx: &Regrow<'_>,
        (p, twin): (u32, u32),
        origin: &mut Vec<Option<u32>>,
        scratch: &mut Scratch,
        plane_copy: &mut Vec<Plane>,
    ) {
        let parent = self.parent_view(prep, p, plane_copy);
        if p != ROOT && !self.nodes[p as usize].live {
            return;
        }
        let (lo, hi) = match twin {
            ROOT => {
                let (lo, hi) = ctx.old.levels.first().copied().unwrap_or((0, 0));
                (lo as u32, hi as u32)
            }
            _ => ctx.children[twin as usize],
        };
        let eps = super::EPS * prep.tol;
        let fresh = ctx.moved.reflectors.iter().copied().filter(|&m| {
            Some(m) != parent.surface
                && (p == ROOT || {
                    let (blo, bhi) = prep.scene.surface(SurfaceId(m)).polygon.bounds();
                    box_meets_halfspaces(blo, bhi, parent.planes, eps)
                })
        });
        let kept = (lo..hi).filter(|&i| {
            let s = ctx.old.nodes[i as usize].surface;
            !ctx.moved.is_moved[s as usize]
        });
        let (mut fresh, mut kept) = (fresh.peekable(), kept.peekable());
        loop {
            // Copied and fresh children never share a surface (fresh ones moved).
            let next_kept = kept.peek().map(|&i| ctx.old.nodes[i as usize].surface);
            let copy = match (next_kept, fresh.peek()) {
                (None, None) => break,
                (Some(s), Some(&m)) => s < m,
                (Some(_), None) => true,
                (None, Some(_)) => false,
            };
            if copy {
                if let Some(i) = kept.next() {
                    self.stats.tested += 1;
                    self.copy_node(ctx.old, i, p);
                    origin.push(Some(i));
                }
            } else if let Some(m) = fresh.next() {
                self.stats.tested += 1;
                self.child(prep, &parent, m, scratch);
                origin.resize(self.nodes.len(), None);
            }
        }
    }
}

/// The old tree, its child ranges and the motion, for one rebuild.
struct Regrow<'a> {
    old: &'a BeamTree,
    children: &'a [(u32, u32)],
    moved: &'a Moved,
}

impl BeamTree {
    /// Whether this tree still serves `scene` (its scene's next state, `moved` surfaces moved)
    /// as it is: it could be rebuilt ([`BeamTree::rebuild`] would reuse nodes) and no moved
    /// surface is a reflector. A moving blocker that culled nothing (a person walking)
    /// changes validation only.
    pub fn unchanged_by(&self, scene: &Scene, moved: &[SurfaceId]) -> bool {
        self.reusable(scene, moved)
            && moved
                .iter()
                .all(|id| scene.surface(*id).kind != bt_scene::SurfaceKind::Reflector)
    }
}
