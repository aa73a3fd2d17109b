//! Coplanar merge: polygon soup -> bounded planar surfaces.
//!
//! 1. Weld positions closer than `weld_tol_m` (exporters duplicate vertices per face).
//! 2. Per face: drop repeated vertices, compute the area vector (Newell), drop zero-area faces,
//!    split faces that are not planar within `dist_tol_m` into fan triangles.
//! 3. Region growing over the edge adjacency graph in file order: a face joins its neighbour's
//!    group when it has the same object/group name and material, its normal is within
//!    `angle_tol_deg` of the group's area-weighted normal and all its vertices are within
//!    `dist_tol_m` of the group's plane. Checking against the group (not the neighbour) keeps
//!    a finely tessellated curved surface from merging into one "plane" by drift.
//! 4. Boundary: the group's edges used by exactly one of its faces, traced into loops keeping
//!    the group's interior on the left (the sharpest right turn at vertices where several
//!    boundary edges meet, so pinched regions give separate simple loops).
//! 5. Loops are projected onto the group's plane, cleaned of collinear vertices; counter-
//!    clockwise loops (seen from the normal) become surfaces, clockwise loops are holes, which
//!    are filled with a warning.

use bt_geom::poly2::{self, contains, signed_area};
use bt_geom::{Real, Vec2, Vec3};
use std::collections::HashMap;

use crate::raw::RawMesh;
use crate::tol;
use crate::{MergeOptions, MeshSurface};

/// Result of the merge: surfaces in file order and warnings.
pub(crate) struct Merged {
    pub surfaces: Vec<MeshSurface>,
    pub warnings: Vec<String>,
}

/// A planar face after welding, with its plane.
struct Face {
    /// Welded vertex ids, no two consecutive equal, at least three.
    vertices: Vec<u32>,
    /// Index of the face in the file.
    source: usize,
    /// Object/group name and material (interned indices).
    key: (Option<u32>, Option<u32>),
    /// Unit normal (right-hand rule on the vertex order).
    normal: Vec3,
    /// Area in m².
    area: Real,
    /// Vertex average, a point on the face's plane.
    centroid: Vec3,
}

/// Runs the whole merge. `opts` must be validated.
pub(crate) fn merge(mesh: &RawMesh, opts: &MergeOptions, file: &str) -> Merged {
    let extent = bounding_diagonal(&mesh.positions);
    let zero_length = opts.weld_tol_m.max(tol::REL_ZERO_LENGTH * extent.max(1.0));
    let (weld_map, points) = weld(&mesh.positions, opts.weld_tol_m);
    let mut warnings = Vec::new();

    let (faces, degenerate, split) = planar_faces(mesh, &weld_map, &points, opts, zero_length);
    if degenerate > 0 {
        warnings.push(format!(
            "{file}: {degenerate} degenerate (zero-area) faces dropped"
        ));
    }
    if split > 0 {
        warnings.push(format!(
            "{file}: {split} non-planar polygon faces split into fan triangles"
        ));
    }

    let edges = edge_table(&faces);
    let groups = grow_regions(&faces, &edges, &points, opts);

    let mut surfaces = Vec::new();
    let mut name_counts: HashMap<String, usize> = HashMap::new();
    let mut open_chains = 0usize;
    let mut zero_loops = 0usize;
    for group in &groups {
        let traced = trace_group(&faces, group, &points, zero_length);
        open_chains += traced.open_chains;
        zero_loops += traced.zero_loops;
        let first = &faces[group.faces[0]];
        if traced.outer.is_empty() {
            warnings.push(format!(
                "{file}: faces starting at face {} gave no closed boundary and were skipped",
                first.source
            ));
            continue;
        }
        let base = first
            .key
            .0
            .map_or("face", |n| mesh.names[n as usize].as_str());
        let material = first.key.1.map(|m| mesh.materials[m as usize].clone());
        // Holes belong to the outer loop that contains their first vertex.
        let mut holes_of = vec![(0usize, 0.0f64); traced.outer.len()];
        for hole in &traced.holes {
            let owner = traced
                .outer
                .iter()
                .position(|outer| contains(&outer.points, hole.points[0]))
                .unwrap_or(0);
            holes_of[owner].0 += 1;
            holes_of[owner].1 += -hole.area;
        }
        for (outer, (hole_count, hole_area)) in traced.outer.iter().zip(holes_of) {
            let counter = name_counts.entry(base.to_owned()).or_insert(0);
            let name = format!("{base}_{counter}");
            *counter += 1;
            if hole_count > 0 {
                warnings.push(format!(
                    "{file}: surface {name}: {hole_count} hole(s) of {hole_area:.4} m² in total \
                     filled (holes are not supported yet; area_m2 includes them)"
                ));
            }
            let vertices = outer
                .points
                .iter()
                .map(|p| traced.origin + traced.u * p.x + traced.v * p.y)
                .collect();
            surfaces.push(MeshSurface {
                name,
                material: material.clone(),
                vertices,
                normal: traced.normal,
                area_m2: outer.area,
                source_faces: group.source_faces,
            });
        }
    }
    if open_chains > 0 {
        warnings.push(format!(
            "{file}: {open_chains} open boundary chains ignored (non-manifold or \
             inconsistently oriented faces)"
        ));
    }
    if zero_loops > 0 {
        warnings.push(format!(
            "{file}: {zero_loops} zero-area boundary loops ignored"
        ));
    }
    Merged { surfaces, warnings }
}

fn bounding_diagonal(points: &[Vec3]) -> Real {
    let Some(&first) = points.first() else {
        return 0.0;
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// Maps every position to a welded vertex id; returns the map and the welded positions (the
/// first position of each cluster). A position joins the nearest earlier welded vertex within
/// `tol`, found through a hash grid of cell size `tol`; `tol == 0` welds exact duplicates only.
fn weld(positions: &[Vec3], tol: Real) -> (Vec<u32>, Vec<Vec3>) {
    let mut map = Vec::with_capacity(positions.len());
    let mut welded: Vec<Vec3> = Vec::new();
    if tol <= 0.0 {
        let mut exact: HashMap<[u64; 3], u32> = HashMap::new();
        for &p in positions {
            // `+ 0.0` turns -0.0 into 0.0 so both weld.
            let key = (p + Vec3::ZERO).to_array().map(Real::to_bits);
            let id = *exact.entry(key).or_insert_with(|| {
                welded.push(p);
                (welded.len() - 1) as u32
            });
            map.push(id);
        }
        return (map, welded);
    }
    let cell_of = |p: Vec3| (p / tol).floor().to_array().map(|c| c as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for &p in positions {
        let cell = cell_of(p);
        let mut best: Option<(Real, u32)> = None;
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                for dz in -1..=1i64 {
                    let neighbour = [
                        cell[0].saturating_add(dx),
                        cell[1].saturating_add(dy),
                        cell[2].saturating_add(dz),
                    ];
                    for &id in grid.get(&neighbour).into_iter().flatten() {
                        let d = welded[id as usize].distance(p);
                        if d <= tol && best.is_none_or(|(bd, bid)| (d, id) < (bd, bid)) {
                            best = Some((d, id));
                        }
                    }
                }
            }
        }
        let id = match best {
            Some((_, id)) => id,
            None => {
                welded.push(p);
                let id = (welded.len() - 1) as u32;
                grid.entry(cell).or_default().push(id);
                id
            }
        };
        map.push(id);
    }
    (map, welded)
}

/// Builds the planar faces; returns them with the counts of dropped degenerate faces and of
/// non-planar faces split into triangles.
fn planar_faces(
    mesh: &RawMesh,
    weld_map: &[u32],
    points: &[Vec3],
    opts: &MergeOptions,
    zero_length: Real,
) -> (Vec<Face>, usize, usize) {
    let mut faces = Vec::with_capacity(mesh.face_count());
    let mut degenerate = 0usize;
    let mut split = 0usize;
    let mut ids: Vec<u32> = Vec::new();
    for f in 0..mesh.face_count() {
        ids.clear();
        for &i in mesh.face(f) {
            let id = weld_map[i as usize];
            if ids.last() != Some(&id) {
                ids.push(id);
            }
        }
        while ids.len() > 1 && ids.first() == ids.last() {
            ids.pop();
        }
        let key = (mesh.face_name[f], mesh.face_material[f]);
        match make_face(&ids, f, key, points, zero_length) {
            None => degenerate += 1,
            Some(face) => {
                let off_plane = face
                    .vertices
                    .iter()
                    .map(|&v| (points[v as usize] - face.centroid).dot(face.normal).abs())
                    .fold(0.0, Real::max);
                if off_plane <= opts.dist_tol_m {
                    faces.push(face);
                } else {
                    split += 1;
                    for k in 1..ids.len() - 1 {
                        let tri = [ids[0], ids[k], ids[k + 1]];
                        match make_face(&tri, f, key, points, zero_length) {
                            Some(t) => faces.push(t),
                            None => degenerate += 1,
                        }
                    }
                }
            }
        }
    }
    (faces, degenerate, split)
}

/// A face from welded ids, or `None` when it is degenerate: fewer than three distinct vertices,
/// or an area so small that the face's height over its longest edge is within `zero_length`.
fn make_face(
    ids: &[u32],
    source: usize,
    key: (Option<u32>, Option<u32>),
    points: &[Vec3],
    zero_length: Real,
) -> Option<Face> {
    if ids.len() < 3 {
        return None;
    }
    let pts: Vec<Vec3> = ids.iter().map(|&i| points[i as usize]).collect();
    let area_vec = 0.5 * poly2::newell(&pts);
    let area = area_vec.length();
    let longest = (0..pts.len())
        .map(|i| pts[i].distance(pts[(i + 1) % pts.len()]))
        .fold(0.0, Real::max);
    if !area.is_finite() || area <= 0.5 * zero_length * longest {
        return None;
    }
    let centroid = pts.iter().sum::<Vec3>() / pts.len() as Real;
    Some(Face {
        vertices: ids.to_vec(),
        source,
        key,
        normal: area_vec / area,
        area,
        centroid,
    })
}

fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// Every (undirected edge, face) pair, sorted by edge then face: the adjacency graph without a
/// hash map per edge.
fn edge_table(faces: &[Face]) -> Vec<(u64, u32)> {
    let mut table: Vec<(u64, u32)> = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let n = face.vertices.len();
        for i in 0..n {
            table.push((
                edge_key(face.vertices[i], face.vertices[(i + 1) % n]),
                f as u32,
            ));
        }
    }
    table.sort_unstable();
    table.dedup();
    table
}

/// A set of coplanar, edge-connected faces.
struct Group {
    /// Indices into the face list, the first is the lowest.
    faces: Vec<usize>,
    /// Number of distinct file faces.
    source_faces: usize,
}

fn grow_regions(
    faces: &[Face],
    edges: &[(u64, u32)],
    points: &[Vec3],
    opts: &MergeOptions,
) -> Vec<Group> {
    let cos_tol = opts.angle_tol_deg.to_radians().cos();
    let mut group_of: Vec<Option<u32>> = vec![None; faces.len()];
    let mut groups = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    // skip[i], for i the first index of an edge's run in `edges`: where its ungrouped faces begin.
    let mut skip = vec![0u32; edges.len()];
    for seed in 0..faces.len() {
        if group_of[seed].is_some() {
            continue;
        }
        let id = groups.len() as u32;
        group_of[seed] = Some(id);
        let mut members = vec![seed];
        let mut normal_sum = faces[seed].normal * faces[seed].area;
        let mut centroid_sum = faces[seed].centroid * faces[seed].area;
        let mut area_sum = faces[seed].area;
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            let face = &faces[f];
            let n = face.vertices.len();
            for i in 0..n {
                let key = edge_key(face.vertices[i], face.vertices[(i + 1) % n]);
                let start = edges.partition_point(|&(k, _)| k < key);
                // Skip the leading run of faces on this edge that already have a group, so
                // many faces on one edge (duplicated triangles) cost linear, not quadratic, time.
                let mut first = skip[start].max(start as u32) as usize;
                while first < edges.len()
                    && edges[first].0 == key
                    && group_of[edges[first].1 as usize].is_some()
                {
                    first += 1;
                }
                skip[start] = first as u32;
                for &(k, other) in &edges[first..] {
                    if k != key {
                        break;
                    }
                    let other = other as usize;
                    if group_of[other].is_some() || faces[other].key != face.key {
                        continue;
                    }
                    let normal = normal_sum.normalize();
                    let origin = centroid_sum / area_sum;
                    let candidate = &faces[other];
                    let coplanar = candidate.normal.dot(normal) >= cos_tol
                        && candidate.vertices.iter().all(|&v| {
                            (points[v as usize] - origin).dot(normal).abs() <= opts.dist_tol_m
                        });
                    if coplanar {
                        group_of[other] = Some(id);
                        members.push(other);
                        normal_sum += candidate.normal * candidate.area;
                        centroid_sum += candidate.centroid * candidate.area;
                        area_sum += candidate.area;
                        queue.push_back(other);
                    }
                }
            }
        }
        members.sort_unstable();
        let mut source_faces = 0;
        let mut last = usize::MAX;
        for &m in &members {
            if faces[m].source != last {
                source_faces += 1;
                last = faces[m].source;
            }
        }
        groups.push(Group {
            faces: members,
            source_faces,
        });
    }
    groups
}

/// A closed boundary loop in the group's plane coordinates (metres).
struct Loop {
    points: Vec<Vec2>,
    /// Signed area in m²: positive counter-clockwise seen from the group normal.
    area: Real,
}

/// The traced boundary of one group, with the plane frame its 2-D coordinates live in.
struct Traced {
    normal: Vec3,
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    outer: Vec<Loop>,
    holes: Vec<Loop>,
    open_chains: usize,
    zero_loops: usize,
}

/// The area-weighted normal and centroid of a group's faces.
fn group_plane(faces: &[Face], group: &Group) -> (Vec3, Vec3) {
    let mut normal_sum = Vec3::ZERO;
    let mut centroid_sum = Vec3::ZERO;
    let mut area_sum = 0.0;
    for &f in &group.faces {
        normal_sum += faces[f].normal * faces[f].area;
        centroid_sum += faces[f].centroid * faces[f].area;
        area_sum += faces[f].area;
    }
    (normal_sum.normalize(), centroid_sum / area_sum)
}

/// The group's boundary as directed edges `(from, to)` in face order: the half-edges whose
/// undirected edge the group uses once.
fn boundary_edges(faces: &[Face], group: &Group) -> Vec<(u32, u32)> {
    let mut half: Vec<(u64, u32, u32)> = Vec::new();
    for &f in &group.faces {
        let vs = &faces[f].vertices;
        for i in 0..vs.len() {
            let (a, b) = (vs[i], vs[(i + 1) % vs.len()]);
            half.push((edge_key(a, b), a, b));
        }
    }
    let mut by_key: Vec<usize> = (0..half.len()).collect();
    by_key.sort_by_key(|&h| half[h].0);
    let mut is_boundary = vec![false; half.len()];
    for run in by_key.chunk_by(|&x, &y| half[x].0 == half[y].0) {
        if run.len() == 1 {
            is_boundary[run[0]] = true;
        }
    }
    half.iter()
        .zip(&is_boundary)
        .filter(|(_, b)| **b)
        .map(|(&(_, a, b), _)| (a, b))
        .collect()
}

fn trace_group(faces: &[Face], group: &Group, points: &[Vec3], zero_length: Real) -> Traced {
    let (normal, origin) = group_plane(faces, group);
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let project = |id: u32| {
        let d = points[id as usize] - origin;
        Vec2::new(d.dot(u), d.dot(v))
    };
    let boundary = boundary_edges(faces, group);
    let mut outgoing: HashMap<u32, Vec<usize>> = HashMap::new();
    for (h, &(a, _)) in boundary.iter().enumerate() {
        outgoing.entry(a).or_default().push(h);
    }

    let mut traced = Traced {
        normal,
        origin,
        u,
        v,
        outer: Vec::new(),
        holes: Vec::new(),
        open_chains: 0,
        zero_loops: 0,
    };
    let mut used = vec![false; boundary.len()];
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        let mut ids = vec![boundary[start].0];
        let mut current = start;
        let closed = loop {
            let (from, at) = boundary[current];
            let incoming = project(at) - project(from);
            // Where several boundary edges leave one vertex (the region touches itself
            // there), take the sharpest right turn: it follows the exterior wedge, so the
            // loops separate into simple ones (outline and hole) instead of one self-touching
            // loop that would hide the hole.
            let next = outgoing
                .get(&at)
                .into_iter()
                .flatten()
                .copied()
                .filter(|&h| !used[h] && h != current)
                .map(|h| {
                    let out = project(boundary[h].1) - project(at);
                    (incoming.perp_dot(out).atan2(incoming.dot(out)), h)
                })
                .fold(None, |best: Option<(Real, usize)>, (turn, h)| match best {
                    Some((bt, _)) if bt <= turn => best,
                    _ => Some((turn, h)),
                });
            match next {
                None => break false,
                Some((_, h)) if h == start => break true,
                Some((_, h)) => {
                    used[h] = true;
                    ids.push(at);
                    current = h;
                }
            }
        };
        used[start] = true;
        if !closed {
            traced.open_chains += 1;
            continue;
        }
        let pts = simplify(ids.into_iter().map(project).collect(), zero_length);
        let area = signed_area(&pts);
        let perimeter: Real = (0..pts.len())
            .map(|i| pts[i].distance(pts[(i + 1) % pts.len()]))
            .sum();
        if pts.len() < 3 || area.abs() <= 0.5 * zero_length * perimeter {
            traced.zero_loops += 1;
        } else if area > 0.0 {
            traced.outer.push(Loop { points: pts, area });
        } else {
            traced.holes.push(Loop { points: pts, area });
        }
    }
    traced
}

/// Whether `p` is redundant between `a` and `b`: within `eps` of the line through them, or `a`
/// and `b` coincide (a spike).
fn redundant(a: Vec2, p: Vec2, b: Vec2, eps: Real) -> bool {
    let ab = b - a;
    let len = ab.length();
    len <= eps || ab.perp_dot(p - a).abs() <= eps * len
}

/// Removes repeated, collinear and spike vertices of a closed loop until none is left.
fn simplify(mut pts: Vec<Vec2>, eps: Real) -> Vec<Vec2> {
    loop {
        let before = pts.len();
        let mut out: Vec<Vec2> = Vec::with_capacity(before);
        for &p in &pts {
            if out.last().is_some_and(|q| q.distance(p) <= eps) {
                continue;
            }
            out.push(p);
            while out.len() >= 3 {
                let n = out.len();
                if redundant(out[n - 3], out[n - 2], out[n - 1], eps) {
                    out.remove(n - 2);
                } else {
                    break;
                }
            }
        }
        // Close the loop: the seam between the last and the first vertex.
        while out.len() >= 2 && out[0].distance(out[out.len() - 1]) <= eps {
            out.pop();
        }
        while out.len() >= 3 {
            let n = out.len();
            if redundant(out[n - 2], out[n - 1], out[0], eps) {
                out.pop();
            } else if redundant(out[n - 1], out[0], out[1], eps) {
                out.remove(0);
            } else {
                break;
            }
        }
        if out.len() == before || out.len() < 3 {
            return out;
        }
        pts = out;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_joins_nearby_positions_and_keeps_far_ones() {
        let pts = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.00005, 0.0, 0.0),
            Vec3::new(1.0, 0.0, -0.00009),
            Vec3::new(0.0, 0.0, 0.001),
        ];
        let (map, welded) = weld(&pts, 1e-4);
        assert_eq!(map, [0, 1, 0, 1, 2]);
        assert_eq!(welded.len(), 3);
        let (map, _) = weld(&[Vec3::ZERO, Vec3::new(-0.0, 0.0, 0.0)], 0.0);
        assert_eq!(map, [0, 0]);
    }

    #[test]
    fn simplify_removes_collinear_and_spikes() {
        let square = [
            (0.0, 0.0),
            (0.5, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.0, 0.5),
        ]
        .map(|(x, y)| Vec2::new(x, y));
        let out = simplify(square.to_vec(), 1e-9);
        assert_eq!(out.len(), 4, "{out:?}");
        assert!((signed_area(&out) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn point_in_polygon() {
        let square = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)].map(|(x, y)| Vec2::new(x, y));
        assert!(contains(&square, Vec2::new(1.0, 1.0)));
        assert!(!contains(&square, Vec2::new(3.0, 1.0)));
    }
}
