//! The whole-group outline: a group's boundary traced into loops, accepted when it is plain.
//!
//! Boundary edges are the half-edges whose undirected edge the group uses once; they are
//! traced into loops keeping the group's interior on the left (the sharpest right turn at a
//! vertex where several boundary edges meet, so a region that touches itself at a vertex gives
//! separate simple loops). The group is plain when every chain closes, no loop is a hole
//! (clockwise seen from the normal), each loop is an [`Outline`] and together they hold the
//! faces' area. Anything else (holes, open or non-manifold boundaries, overlapping faces) is
//! left to [`crate::split`], which loses nothing.

use bt_geom::{Real, Vec2, Vec3};

use crate::edges::edge_key;
use crate::merge::{Faces, Group};
use crate::outline::{Frame, Outline, area_matches, outline};

/// Working lists of [`whole_outlines`], kept from one group to the next (one set per worker
/// thread) so that tracing a group allocates only the loops it returns.
#[derive(Default)]
pub(crate) struct Scratch {
    /// The group's half-edges in face order: (undirected edge key, from, to).
    half: Vec<(u64, u32, u32)>,
    /// The half-edges' keys with their positions in `half`, sorted: `key << 32 | position`
    /// (one integer sorts in fewer instructions than a pair compared field by field).
    keyed: Vec<u128>,
    /// Per half-edge: on the boundary; then per boundary edge: traced.
    flags: Vec<bool>,
    /// The boundary edges (from, to) in face order.
    boundary: Vec<(u32, u32)>,
    /// The boundary edges by start vertex, sorted: `from << 32 | position in boundary`.
    outgoing: Vec<u64>,
}

/// The outlines of a plain group, in the order of their first boundary edge; `None` when the
/// group is not plain and must be split.
pub(crate) fn whole_outlines(
    faces: &Faces,
    group: Group<'_>,
    frame: &Frame,
    points: &[Vec3],
    eps: Real,
    scratch: &mut Scratch,
) -> Option<Vec<Outline>> {
    let loops = closed_loops(faces, group, frame, points, scratch)?;
    let mut outlines = Vec::with_capacity(loops.len());
    for ring in loops {
        let cleaned = crate::outline::simplify(ring, eps);
        let area = bt_geom::poly2::signed_area(&cleaned);
        if cleaned.len() < 3 || area.abs() <= 0.5 * eps * crate::outline::perimeter(&cleaned) {
            // A slit or a sliver of a loop: no area, nothing to keep (the area check below
            // notices if it mattered).
            continue;
        }
        outlines.push(outline(cleaned, group.source_faces, eps)?);
    }
    let expected = frame.projected_area(faces, group.faces);
    (!outlines.is_empty() && area_matches(&outlines, expected, eps)).then_some(outlines)
}

/// Fills `scratch.boundary` with the group's boundary as directed edges `(from, to)` in face
/// order: the half-edges whose undirected edge the group uses once.
fn boundary_edges(faces: &Faces, group: Group<'_>, scratch: &mut Scratch) {
    let Scratch {
        half,
        keyed,
        flags,
        boundary,
        ..
    } = scratch;
    half.clear();
    for &f in group.faces {
        let vs = faces.vertices(f);
        for i in 0..vs.len() {
            let (a, b) = (vs[i], vs[(i + 1) % vs.len()]);
            half.push((edge_key(a, b), a, b));
        }
    }
    keyed.clear();
    keyed.extend(
        (half.iter().enumerate()).map(|(h, &(key, _, _))| u128::from(key) << 32 | h as u128),
    );
    keyed.sort_unstable();
    flags.clear();
    flags.resize(half.len(), false);
    for run in keyed.chunk_by(|x, y| x >> 32 == y >> 32) {
        if let [h] = run {
            flags[*h as u32 as usize] = true;
        }
    }
    boundary.clear();
    boundary.extend(
        (half.iter().zip(flags.iter()))
            .filter(|(_, b)| **b)
            .map(|(&(_, a, b), _)| (a, b)),
    );
}

/// Every boundary loop of the group in frame coordinates, or `None` when a chain does not
/// close (non-manifold edges, overlapping faces).
fn closed_loops(
    faces: &Faces,
    group: Group<'_>,
    frame: &Frame,
    points: &[Vec3],
    scratch: &mut Scratch,
) -> Option<Vec<Vec<Vec2>>> {
    let project = |id: u32| frame.project(points[id as usize]);
    boundary_edges(faces, group, scratch);
    let Scratch {
        flags: used,
        boundary,
        outgoing,
        ..
    } = scratch;
    // The boundary edges by start vertex (in edge order for each): a sorted list, no
    // allocation per vertex.
    outgoing.clear();
    outgoing
        .extend((boundary.iter().enumerate()).map(|(h, &(a, _))| u64::from(a) << 32 | h as u64));
    outgoing.sort_unstable();
    let leaving = |at: u32| {
        let start = outgoing.partition_point(|&x| x >> 32 < u64::from(at));
        let end = start + outgoing[start..].partition_point(|&x| x >> 32 == u64::from(at));
        outgoing[start..end].iter().map(|&x| x as u32 as usize)
    };
    let mut loops = Vec::new();
    used.clear();
    used.resize(boundary.len(), false);
    // Boundary edges not yet in a loop: the most the next loop can take (sized once, not
    // grown vertex by vertex).
    let mut left = boundary.len();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut ring = Vec::with_capacity(left);
        ring.push(project(boundary[start].0));
        let mut current = start;
        loop {
            let (from, at) = boundary[current];
            let incoming = project(at) - project(from);
            // Where several boundary edges leave one vertex (the region touches itself
            // there), take the sharpest right turn: it follows the exterior wedge, so the
            // loops separate into simple ones (outline and hole) instead of one self-touching
            // loop that would hide the hole.
            // One edge leaving (nearly always): it is the turn, no angle needed.
            let mut open = leaving(at)
                .filter(|&h| !used[h] || h == start)
                .filter(|&h| h != current);
            let next = match (open.next(), open.next()) {
                (None, _) => None,
                (Some(h), None) => Some(h),
                (Some(a), Some(b)) => [a, b]
                    .into_iter()
                    .chain(open)
                    .map(|h| {
                        let out = project(boundary[h].1) - project(at);
                        (incoming.perp_dot(out).atan2(incoming.dot(out)), h)
                    })
                    .fold(None, |best: Option<(Real, usize)>, (turn, h)| match best {
                        Some((bt, _)) if bt <= turn => best,
                        _ => Some((turn, h)),
                    })
                    .map(|(_, h)| h),
            };
            match next {
                None => return None,
                Some(h) if h == start => break,
                Some(h) => {
                    used[h] = true;
                    ring.push(project(at));
                    current = h;
                }
            }
        }
        left -= ring.len();
        loops.push(ring);
    }
    Some(loops)
}
