//! Groups that are not one plain polygon (holes, open or non-manifold boundaries, overlapping
//! faces) split into simple pieces made of their own faces, so that nothing is lost or filled.
//!
//! Greedy growth: a piece starts at the group's first face not yet used and takes neighbouring
//! faces in breadth-first order while the union stays a disk. A face joins when the edges it
//! shares with the piece's boundary (used the other way round by the piece) form one run and
//! its other vertices are not yet in the piece; then the union of two disks glued along one
//! arc is a disk. A face that would close a ring around a hole, pinch the piece at a vertex or
//! overlap it that way is left for a later piece. A piece's boundary is checked in the plane
//! ([`outline`]); where the mesh's geometry disagrees with its connectivity (a vertex lying on
//! another face's edge, faces overlapping), the longest prefix of the growth order that gives
//! an outline is kept and the rest goes back to the pool. Every face ends in exactly one piece,
//! so the pieces' areas add up to the faces'. Seams between pieces are coplanar.

use bt_geom::{Real, Vec3};
use std::collections::{HashMap, HashSet, VecDeque};

use crate::edges::EdgeTable;
use crate::merge::{Faces, Group};
use crate::outline::{Frame, Outline, area_matches, outline};

/// Most faces on one edge a growing piece looks at, counted from the first one not yet in an
/// earlier piece: a manifold mesh has two, and a bound keeps thousands of faces on one edge
/// linear, not quadratic. Faces not looked at are not lost: they seed later pieces.
const MAX_NEIGHBOURS_PER_EDGE: usize = 8;

/// Pieces of one group, and the faces that could not form a valid polygon even alone.
#[derive(Debug, Default)]
pub(crate) struct Split {
    /// Outlines in the order of their first face.
    pub outlines: Vec<Outline>,
    /// Faces dropped because, alone, they are no valid polygon (thinner than the tolerances).
    pub unusable: usize,
}

/// Splits `group` into simple pieces of its faces, in face order.
pub(crate) fn split_group(
    faces: &Faces,
    group: Group<'_>,
    frame: &Frame,
    points: &[Vec3],
    eps: Real,
) -> Split {
    let members = group.faces;
    let mut grower = Grower::new(faces, members);
    let mut done = vec![false; members.len()];
    let mut split = Split::default();
    let mut cursor = 0;
    loop {
        while cursor < members.len() && done[cursor] {
            cursor += 1;
        }
        if cursor == members.len() {
            return split;
        }
        let order = grower.grow(cursor, &done);
        let piece = |boundary: &Boundary, prefix: &[usize]| {
            let prefix: Vec<usize> = prefix.iter().map(|&f| members[f]).collect();
            piece_outline(boundary, faces, &prefix, frame, points, eps)
        };
        let (taken, outline) = match piece(&grower.boundary, &order) {
            Some(o) => (order.len(), Some(o)),
            None => longest_valid_prefix(&order, |prefix| {
                let vertices = prefix.iter().map(|&f| faces.vertices(members[f]));
                piece(&Boundary::replay(vertices), prefix)
            }),
        };
        for &f in &order[..taken] {
            done[f] = true;
        }
        match outline {
            Some(o) => split.outlines.push(o),
            None => split.unusable += taken,
        }
    }
}

/// The longest proper prefix of `order` (whose whole gives no outline) that gives an outline,
/// by binary search, and that outline; `(1, None)` when not even the first face does.
fn longest_valid_prefix(
    order: &[usize],
    outline_of: impl Fn(&[usize]) -> Option<Outline>,
) -> (usize, Option<Outline>) {
    let Some(mut best) = outline_of(&order[..1]) else {
        return (1, None);
    };
    // Valid at `lo`, invalid at `hi`.
    let (mut lo, mut hi) = (1, order.len());
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        match outline_of(&order[..mid]) {
            Some(o) => {
                lo = mid;
                best = o;
            }
            None => hi = mid,
        }
    }
    (lo, Some(best))
}

/// The outline of the piece with `boundary` made of the faces `piece` (indices into `faces`),
/// when it is a valid polygon holding the faces' area.
fn piece_outline(
    boundary: &Boundary,
    faces: &Faces,
    piece: &[usize],
    frame: &Frame,
    points: &[Vec3],
    eps: Real,
) -> Option<Outline> {
    let ring = boundary.cycle()?;
    let mut sources: Vec<usize> = piece.iter().map(|&f| faces[f].source).collect();
    sources.sort_unstable();
    sources.dedup();
    let projected = ring.iter().map(|&v| frame.project(points[v as usize]));
    let outline = outline(projected.collect(), sources.len(), eps)?;
    let expected = frame.projected_area(faces, piece);
    area_matches(std::slice::from_ref(&outline), expected, eps).then_some(outline)
}

/// The boundary of a growing piece: the successor of each boundary vertex (a disk's boundary
/// is one cycle through each of its vertices once) and every vertex the piece holds.
#[derive(Debug, Default)]
struct Boundary {
    next: HashMap<u32, u32>,
    vertices: HashSet<u32>,
}

impl Boundary {
    /// The boundary of faces added in a growth order (each joins, as it did when grown).
    fn replay<'a>(faces: impl Iterator<Item = &'a [u32]>) -> Self {
        let mut boundary = Boundary::default();
        for vs in faces {
            let added = boundary.try_add(vs);
            debug_assert!(added, "a growth order replays");
        }
        boundary
    }

    fn clear(&mut self) {
        self.next.clear();
        self.vertices.clear();
    }

    /// Adds the face with vertex cycle `vs` (distinct ids, counter-clockwise like the piece)
    /// when the union stays a disk; returns whether it did. The first face always joins.
    fn try_add(&mut self, vs: &[u32]) -> bool {
        let k = vs.len();
        if self.next.is_empty() {
            self.glue(vs, 0, 0);
            return true;
        }
        // Edge i of the face runs vs[i] -> vs[i + 1]; it is shared when the piece's boundary
        // runs the other way.
        let shared = |i: usize| self.next.get(&vs[(i + 1) % k]) == Some(&vs[i]);
        let mut run = 0;
        let mut starts = 0;
        let mut start = 0;
        for i in 0..k {
            if shared(i) {
                run += 1;
                if !shared((i + k - 1) % k) {
                    starts += 1;
                    start = i;
                }
            }
        }
        // One run of shared edges, not the whole face (which would fill a hole the piece, a
        // disk, cannot have).
        if starts != 1 || run == k {
            return false;
        }
        // The run covers vertices start ..= start + run; the others must be new.
        if (run + 1..k).any(|t| self.vertices.contains(&vs[(start + t) % k])) {
            return false;
        }
        self.glue(vs, start, run);
        true
    }

    /// Replaces the piece's edges along the face's shared run (`run` edges from `start`) by
    /// the face's other edges.
    fn glue(&mut self, vs: &[u32], start: usize, run: usize) {
        let k = vs.len();
        for t in 0..run {
            self.next.remove(&vs[(start + t + 1) % k]);
        }
        for t in run..k {
            self.next
                .insert(vs[(start + t) % k], vs[(start + t + 1) % k]);
        }
        self.vertices.extend(vs.iter().copied());
    }

    /// The boundary cycle from its smallest vertex id (deterministic), or `None` if the
    /// successors do not form one cycle (they always should).
    fn cycle(&self) -> Option<Vec<u32>> {
        let first = *self.next.keys().min()?;
        let mut ring = vec![first];
        let mut at = self.next[&first];
        while at != first {
            if ring.len() >= self.next.len() {
                return None;
            }
            ring.push(at);
            at = *self.next.get(&at)?;
        }
        (ring.len() == self.next.len()).then_some(ring)
    }
}

/// Grows pieces over one group's faces (local indices into `members`).
struct Grower<'a> {
    faces: &'a Faces,
    members: &'a [usize],
    edges: EdgeTable,
    in_piece: Vec<bool>,
    boundary: Boundary,
    queue: VecDeque<usize>,
}

impl<'a> Grower<'a> {
    fn new(faces: &'a Faces, members: &'a [usize]) -> Self {
        Grower {
            faces,
            members,
            edges: EdgeTable::new(members.iter().map(|&f| faces.vertices(f))),
            in_piece: vec![false; members.len()],
            boundary: Boundary::default(),
            queue: VecDeque::new(),
        }
    }

    /// One piece from `seed`: the faces it took, in the order they joined.
    fn grow(&mut self, seed: usize, done: &[bool]) -> Vec<usize> {
        self.boundary.clear();
        self.queue.clear();
        self.queue.push_back(seed);
        let mut order = Vec::new();
        while let Some(f) = self.queue.pop_front() {
            if done[f] || self.in_piece[f] {
                continue;
            }
            let vs = self.faces.vertices(self.members[f]);
            if !self.boundary.try_add(vs) {
                continue;
            }
            self.in_piece[f] = true;
            order.push(f);
            for i in 0..vs.len() {
                let across = self.edges.unsettled(f, i, |g| done[g]);
                let in_piece = &self.in_piece;
                self.queue.extend(
                    across
                        .take(MAX_NEIGHBOURS_PER_EDGE)
                        .filter(|&g| !done[g] && !in_piece[g]),
                );
            }
        }
        for &f in &order {
            self.in_piece[f] = false;
        }
        order
    }
}
