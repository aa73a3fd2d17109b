//! Closed shells (watertight groups of surfaces: a box without omitted faces, a closed mesh
//! solid) and whether a terminal is enclosed by one: a TX inside a closed cabinet with the RX
//! outside it has no path at all, which deserves a warning rather than an empty result.
//!
//! Both tests are conservative: a shell is closed only when every edge of its surfaces is shared,
//! vertex for vertex (exact coordinates), by exactly two of them; a point's side is decided by
//! the parity of crossings of a ray, and a ray passing within the scene's tolerance of an edge,
//! a vertex or along a plane is discarded for the next direction. When no direction is clear the
//! answer is "unknown" and nothing is warned about.

use crate::surface::{Surface, SurfaceId};
use bt_geom::hash::KeyMap;
use bt_geom::{Real, Vec3};

/// Surfaces (by id) of each closed shell of at least 4 surfaces, in order of their first id.
pub(crate) fn closed_shells(surfaces: &[Surface]) -> Vec<Vec<SurfaceId>> {
    // The point map and the edge list sized once for every corner (distinct points are
    // fewer): grown by doubling, they touched fresh memory at each step (Munich's trace: 624
    // page faults of 11,931, docs/performance.md).
    let corners: usize = surfaces.iter().map(|s| s.polygon.vertices().len()).sum();
    // Each distinct point (exact coordinates, -0.0 as +0.0) numbered as first met; keyed by
    // a tuple, hashed as three integers (an array is hashed byte by byte).
    let mut ids: KeyMap<(u64, u64, u64), u32> = KeyMap::default();
    ids.reserve(corners);
    let mut id = |p: Vec3| {
        let next = ids.len() as u32;
        let [x, y, z] = (p + Vec3::ZERO).to_array().map(Real::to_bits);
        *ids.entry((x, y, z)).or_insert(next)
    };
    // Every edge as (its ends' numbers in order, its surface), sorted: the owners of one edge
    // are then neighbours, in surface order (a sort, not a map: a city has 100,000 edges). The
    // edges' order between them does not matter: what follows groups and counts owners.
    let mut edges: Vec<(u64, u32)> = Vec::with_capacity(corners);
    for (i, s) in surfaces.iter().enumerate() {
        let v = s.polygon.vertices();
        for k in 0..v.len() {
            let (a, b) = (id(v[k]), id(v[(k + 1) % v.len()]));
            edges.push(((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), i as u32));
        }
    }
    edges.sort_unstable();
    let owners = || edges.chunk_by(|x, y| x.0 == y.0);
    let mut parent: Vec<usize> = (0..surfaces.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for owners in owners() {
        for w in owners.windows(2) {
            let (a, b) = (
                root(&mut parent, w[0].1 as usize),
                root(&mut parent, w[1].1 as usize),
            );
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut open = vec![false; surfaces.len()];
    for owners in owners() {
        let r = root(&mut parent, owners[0].1 as usize);
        // an edge used once (a border) or by more than two faces (a fin) breaks watertightness
        let two_distinct = owners.len() == 2 && owners[0].1 != owners[1].1;
        open[r] |= !two_distinct;
    }
    // By root, the smallest id of its group (unions keep the smaller root): groups in order
    // of their first id, only the closed ones collected.
    let mut shells: Vec<Vec<SurfaceId>> = vec![Vec::new(); surfaces.len()];
    for i in 0..surfaces.len() {
        let r = root(&mut parent, i);
        if !open[r] {
            shells[r].push(SurfaceId(i as u32));
        }
    }
    shells.retain(|members| members.len() >= 4);
    shells
}

/// Ray directions tried in turn: none parallel to an axis or to a diagonal, so axis-aligned
/// walls and boxes are never grazed by the first one.
const DIRECTIONS: [[Real; 3]; 4] = [
    [0.5377, 0.3119, 0.7834],
    [-0.4271, 0.6673, 0.2917],
    [0.2249, -0.7517, -0.4302],
    [-0.6911, -0.1813, 0.5539],
];

/// Whether the box around `shell`'s surfaces, grown by `eps` (metres), holds one of `points`:
/// a point outside it lies outside the shell, so [`encloses`] need not be asked.
pub(crate) fn box_holds_either(
    surfaces: &[Surface],
    shell: &[SurfaceId],
    points: [Vec3; 2],
    eps: Real,
) -> bool {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for id in shell {
        let (a, b) = surfaces[id.index()].polygon.bounds();
        (lo, hi) = (lo.min(a), hi.max(b));
    }
    let (lo, hi) = (lo - Vec3::splat(eps), hi + Vec3::splat(eps));
    (points.iter()).any(|p| p.cmpge(lo).all() && p.cmple(hi).all())
}

/// Whether `p` lies inside the closed `shell` (`Some(true)`), outside (`Some(false)`), or too
/// near its surfaces along every direction tried to tell (`None`). `eps`: the scene's length
/// tolerance, metres.
pub(crate) fn encloses(
    surfaces: &[Surface],
    shell: &[SurfaceId],
    p: Vec3,
    eps: Real,
) -> Option<bool> {
    let (mut lo, mut hi) = (p, p);
    for id in shell {
        let (a, b) = surfaces[id.index()].polygon.bounds();
        (lo, hi) = (lo.min(a), hi.max(b));
    }
    let reach = 2.0 * (hi - lo).length() + 1.0;
    DIRECTIONS.iter().find_map(|d| {
        let q = p + Vec3::from_array(*d).normalize() * reach;
        let mut crossings = 0usize;
        for id in shell {
            crossings += usize::from(crosses(&surfaces[id.index()], p, q, eps)?);
        }
        Some(crossings % 2 == 1)
    })
}

/// Whether the segment `p`–`q` crosses the surface's interior clearly (`Some`), or passes
/// within `eps` of its plane at an end, of its boundary, or along its plane (`None`).
fn crosses(surface: &Surface, p: Vec3, q: Vec3, eps: Real) -> Option<bool> {
    let plane = surface.polygon.plane();
    let (dp, dq) = (plane.signed_distance(p), plane.signed_distance(q));
    if dp.abs() <= eps {
        // starts in the plane: a crossing at p, which lies off the polygon (validated terminal)
        // unless near its boundary
        return (surface.polygon.signed_boundary_distance(p) < -eps).then_some(false);
    }
    if dq.abs() <= eps {
        return None;
    }
    if (dp > 0.0) == (dq > 0.0) {
        return Some(false);
    }
    let x = p + (q - p) * (dp / (dp - dq));
    let inside = surface.polygon.signed_boundary_distance(x);
    (inside.abs() > eps).then_some(inside > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Scene, SceneDescription, Terminals};

    fn scene(json: &str) -> Scene {
        let d: SceneDescription = serde_json::from_str(json).unwrap();
        Scene::from_description(&d, "t", Terminals::default()).unwrap()
    }

    #[test]
    fn boxes_are_closed_unless_a_face_is_omitted_and_open_walls_never() {
        let s = scene(
            r#"{ "tx": [1, 1, 1], "rx": [3, 2, 1],
            "boxes": [ { "name": "room", "min": [0, 0, 0], "max": [6, 4, 3] },
                       { "name": "crate", "min": [4, 1, 0.5], "max": [5, 2, 1.5] },
                       { "name": "shelf", "min": [1, 3, 0.5], "max": [2, 3.5, 1], "omit": ["top"] } ],
            "surfaces": [ { "name": "wall", "vertices": [[0.5, 2, 0], [2, 2, 0], [2, 2, 2], [0.5, 2, 2]] } ] }"#,
        );
        let shells = closed_shells(s.surfaces());
        let names: Vec<Vec<&str>> = (shells.iter())
            .map(|m| m.iter().map(|id| s.surface(*id).name.as_str()).collect())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        assert!(names[0].iter().all(|n| n.starts_with("room.")) && names[0].len() == 6);
        assert!(names[1].iter().all(|n| n.starts_with("crate.")) && names[1].len() == 6);
        let eps = s.length_tolerance();
        let crate_shell = &shells[1];
        let inside = |p: [Real; 3]| encloses(s.surfaces(), crate_shell, Vec3::from_array(p), eps);
        assert_eq!(inside([4.5, 1.5, 1.0]), Some(true));
        assert_eq!(inside([4.5, 1.5, 2.0]), Some(false));
        assert_eq!(inside([3.0, 1.5, 1.0]), Some(false));
        // in the plane of a face but outside the face: still decided
        assert_eq!(inside([4.0, 3.0, 1.0]), Some(false));
        assert_eq!(
            encloses(s.surfaces(), &shells[0], s.tx().unwrap(), eps),
            Some(true)
        );
    }
}
