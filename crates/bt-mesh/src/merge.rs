//! Coplanar merge: polygon soup -> bounded planar surfaces.
//!
//! 1. Weld positions closer than `weld_tol_m` (exporters duplicate vertices per face).
//! 2. Per face: drop repeated vertices, compute the area vector (Newell), drop zero-area faces,
//!    split faces that are not planar within `dist_tol_m`, or not simple, into fan triangles.
//! 3. Drop coincident duplicates (the same welded vertices, in either winding): one copy stays.
//! 4. Region growing over the edge adjacency graph in file order: a face joins its neighbour's
//!    group when it has the same object/group name and material, its normal is within
//!    `angle_tol_deg` of the group's area-weighted normal and all its vertices are within
//!    `dist_tol_m` of the group's plane. Checking against the group (not the neighbour) keeps
//!    a finely tessellated curved surface from merging into one "plane" by drift.
//! 5. Outlines in the group's plane: the whole traced boundary when it is one or more simple
//!    loops without holes ([`crate::trace`]), otherwise simple pieces of the group's own faces
//!    ([`crate::split`]). Either way every face's area is in exactly one surface.

use bt_geom::hash::KeyMap;
use bt_geom::poly2::{self, first_contact};
use bt_geom::{Real, Vec2, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

use crate::edges::EdgeTable;
use crate::outline::{Frame, Outline};
use crate::raw::RawMesh;
use crate::tol;
use crate::{MergeOptions, MeshSurface};

/// Result of the merge: surfaces in file order and warnings.
pub(crate) struct Merged {
    pub surfaces: Vec<MeshSurface>,
    pub warnings: Vec<String>,
}

/// A planar face after welding, with its plane. Its vertices are a range of the shared id
/// list of its [`Faces`] (one allocation for all faces, not one per face).
pub(crate) struct Face {
    /// Where its welded vertex ids lie in [`Faces`]'s id list: `start..end`.
    start: usize,
    end: usize,
    /// Index of the face in the file.
    pub source: usize,
    /// Object/group name and material (interned indices).
    pub key: (Option<u32>, Option<u32>),
    /// Unit normal (right-hand rule on the vertex order).
    pub normal: Vec3,
    /// Area in m².
    pub area: Real,
    /// Vertex average, a point on the face's plane.
    pub centroid: Vec3,
}

/// The planar faces of a mesh: per face its plane and a range of one list of welded vertex
/// ids. Index it by face number for the plane, [`Faces::vertices`] for the ids.
#[derive(Default)]
pub(crate) struct Faces {
    /// Every face's welded vertex ids, one face after the other (ranges of dropped faces
    /// stay, unused).
    ids: Vec<u32>,
    list: Vec<Face>,
}

impl Faces {
    /// Room for `faces` faces of `ids` vertex ids in all.
    fn with_capacity(faces: usize, ids: usize) -> Self {
        Faces {
            ids: Vec::with_capacity(ids),
            list: Vec::with_capacity(faces),
        }
    }

    /// Number of faces.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Face `f`'s welded vertex ids: distinct, at least three, a simple polygon in its plane.
    pub fn vertices(&self, f: usize) -> &[u32] {
        let face = &self.list[f];
        &self.ids[face.start..face.end]
    }

    /// Every face's vertex ids, in face order.
    pub fn all_vertices(&self) -> impl ExactSizeIterator<Item = &[u32]> {
        self.list.iter().map(|f| &self.ids[f.start..f.end])
    }

    /// Appends the face with vertex ids `ids` and plane `plane`, from file face `source`.
    fn push(&mut self, ids: &[u32], source: usize, key: (Option<u32>, Option<u32>), plane: Plane) {
        let start = self.ids.len();
        self.ids.extend_from_slice(ids);
        self.list.push(Face {
            start,
            end: self.ids.len(),
            source,
            key,
            normal: plane.normal,
            area: plane.area,
            centroid: plane.centroid,
        });
    }
}

impl std::ops::Index<usize> for Faces {
    type Output = Face;

    fn index(&self, f: usize) -> &Face {
        &self.list[f]
    }
}

/// A face's plane as [`make_face`] computes it.
#[derive(Clone, Copy)]
struct Plane {
    /// Unit normal (right-hand rule on the vertex order).
    normal: Vec3,
    /// Area in m².
    area: Real,
    /// Vertex average, a point on the face's plane.
    centroid: Vec3,
}

/// A set of coplanar, edge-connected faces: a view of [`Groups`].
#[derive(Clone, Copy)]
pub(crate) struct Group<'a> {
    /// Indices into the face list, ascending.
    pub faces: &'a [usize],
    /// Number of distinct file faces.
    pub source_faces: usize,
}

/// The groups of a mesh: their members one group after the other in one list.
#[derive(Default)]
pub(crate) struct Groups {
    members: Vec<usize>,
    /// Per group: the end of its members in `members` and its number of distinct file faces.
    ends: Vec<(usize, usize)>,
}

impl Groups {
    /// Number of groups.
    fn len(&self) -> usize {
        self.ends.len()
    }

    /// The groups in order.
    fn iter(&self) -> impl ExactSizeIterator<Item = Group<'_>> + '_ {
        (0..self.ends.len()).map(|g| self.get(g))
    }

    /// Group `g`.
    fn get(&self, g: usize) -> Group<'_> {
        let start = g.checked_sub(1).map_or(0, |p| self.ends[p].0);
        let (end, source_faces) = self.ends[g];
        Group {
            faces: &self.members[start..end],
            source_faces,
        }
    }
}

/// What became of the file's faces on the way to [`Face`]s, for the warnings.
#[derive(Default)]
struct FaceCounts {
    /// Zero-area faces dropped.
    degenerate: usize,
    /// Polygon faces not planar within `dist_tol_m`, split into fan triangles.
    non_planar: usize,
    /// Polygon faces that touch or cross themselves, split into fan triangles.
    non_simple: usize,
    /// Faces coincident with an earlier one, dropped.
    duplicates: usize,
    /// Faces that are no valid polygon even alone (thinner than the tolerances), dropped.
    unusable: usize,
}

/// Groups of one mesh from which they are outlined in parallel: below, the work is too small
/// to pay for handing it to other threads (most meshes of a city hold a few groups).
const PARALLEL_GROUPS: usize = 64;

/// Where a large mesh's merge is cut into work for all cores. The pieces are joined in order,
/// so the result is that of one piece whatever the sizes (a test merges with tiny ones).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Parallel {
    /// Faces per run of [`drop_duplicates`]' cycle heads, and the least faces of a run of
    /// grown groups outlined apart ([`grow_and_outline`], for meshes of more faces).
    pub faces: usize,
}

impl Parallel {
    /// The sizes a merge uses: a run is large enough that handing it to another thread pays
    /// (most meshes of a city are one run; San Francisco's terrain of 192,000 triangles is 47).
    pub const DEFAULT: Parallel = Parallel { faces: 4096 };
}

/// Runs the whole merge. `opts` must be validated.
pub(crate) fn merge(mesh: &RawMesh, opts: &MergeOptions, file: &str) -> Merged {
    merge_with(mesh, opts, file, Parallel::DEFAULT)
}

/// [`merge`], cut into parallel work as `parallel` says.
pub(crate) fn merge_with(
    mesh: &RawMesh,
    opts: &MergeOptions,
    file: &str,
    parallel: Parallel,
) -> Merged {
    // The stages are never inlined (each runs once a mesh), so that a profile shows each.
    let extent = bounding_diagonal(&mesh.positions);
    let zero_length = opts.weld_tol_m.max(tol::REL_ZERO_LENGTH * extent.max(1.0));
    let (weld_map, points) = weld(&mesh.positions, opts.weld_tol_m);
    let mut counts = FaceCounts::default();
    let welded = (weld_map.as_slice(), points.as_slice());
    let faces = planar_faces(mesh, welded, opts, zero_length, &mut counts);
    let faces = drop_duplicates(faces, &mut counts, parallel);
    let (groups, outlined) = if faces.len() > parallel.faces {
        grow_and_outline(&faces, &points, opts, zero_length, parallel)
    } else {
        let groups = grow_regions(&faces, &points, opts, |_| {});
        let outlined = outline_groups(&faces, &groups, &points, zero_length);
        (groups, outlined)
    };
    let mut surfaces = Vec::with_capacity(outlined.iter().map(|(_, o, _)| o.len()).sum());
    let mut name_counts: HashMap<String, usize> = HashMap::new();
    for (group, (frame, outlines, unusable)) in groups.iter().zip(outlined) {
        counts.unusable += unusable;
        let first = &faces[group.faces[0]];
        let base = first
            .key
            .0
            .map_or("face", |n| mesh.names[n as usize].as_str());
        let material = first.key.1.map(|m| mesh.materials[m as usize].clone());
        let region_area: Real = outlines.iter().map(|o| o.area).sum();
        for Outline {
            points: outline,
            area,
            source_faces,
        } in outlines
        {
            // A name is copied once, when first counted (not for every surface).
            let counter = match name_counts.get_mut(base) {
                Some(counter) => {
                    *counter += 1;
                    *counter - 1
                }
                None => {
                    name_counts.insert(base.to_owned(), 1);
                    0
                }
            };
            surfaces.push(MeshSurface {
                name: numbered(base, counter),
                material: material.clone(),
                vertices: outline.into_iter().map(|p| frame.lift(p)).collect(),
                normal: frame.normal,
                area_m2: area,
                region_area_m2: region_area,
                source_faces,
            });
        }
    }
    Merged {
        surfaces,
        warnings: warnings(file, &counts),
    }
}

/// A group's outlines as [`merge_with`] makes them: its frame, its outlines and the number
/// of its faces too thin to be a polygon (dropped).
type Outlined = (Frame, Vec<Outline>, usize);

/// Outlines `group` in its own plane: the whole traced boundary, else simple pieces.
fn outline_group(
    faces: &Faces,
    group: Group<'_>,
    points: &[Vec3],
    zero_length: Real,
    scratch: &mut crate::trace::Scratch,
) -> Outlined {
    let frame = Frame::of_faces(faces, group.faces);
    let whole = crate::trace::whole_outlines(faces, group, &frame, points, zero_length, scratch);
    match whole {
        Some(outlines) => (frame, outlines, 0),
        None => {
            let split = crate::split::split_group(faces, group, &frame, points, zero_length);
            (frame, split.outlines, split.unusable)
        }
    }
}

/// Every group outlined on its own, in order: on all cores when there are many (a large
/// mesh, say a church of 12,000 faces, would otherwise keep one core busy while the other
/// waits).
fn outline_groups(
    faces: &Faces,
    groups: &Groups,
    points: &[Vec3],
    zero_length: Real,
) -> Vec<Outlined> {
    let outline = |scratch: &mut crate::trace::Scratch, g: usize| {
        outline_group(faces, groups.get(g), points, zero_length, scratch)
    };
    if groups.len() >= PARALLEL_GROUPS {
        (0..groups.len())
            .into_par_iter()
            .map_init(crate::trace::Scratch::default, outline)
            .collect()
    } else {
        let mut scratch = crate::trace::Scratch::default();
        (0..groups.len())
            .map(|g| outline(&mut scratch, g))
            .collect()
    }
}

/// The groups of a large mesh, and their outlines in order, made while they grow: growing is
/// one pass in file order, and a group is final once grown, so each run of finished groups
/// of at least `parallel.faces` faces is outlined on another core while the next grow (San
/// Francisco's terrain outlined its 2,004 groups only after growing all of them).
fn grow_and_outline(
    faces: &Faces,
    points: &[Vec3],
    opts: &MergeOptions,
    zero_length: Real,
    parallel: Parallel,
) -> (Groups, Vec<Outlined>) {
    let done: std::sync::Mutex<Vec<(usize, Vec<Outlined>)>> = Default::default();
    let groups = rayon::scope(|scope| {
        // The first group not yet handed out.
        let mut next: usize = 0;
        let mut hand_out = |groups: &Groups, last: bool| {
            let start = next.checked_sub(1).map_or(0, |p| groups.ends[p].0);
            let ready = groups.members.len() - start;
            if groups.len() == next || (!last && ready < parallel.faces) {
                return;
            }
            let run = Groups {
                members: groups.members[start..].to_vec(),
                ends: (groups.ends[next..].iter())
                    .map(|&(end, sources)| (end - start, sources))
                    .collect(),
            };
            let (first, done) = (next, &done);
            next = groups.len();
            scope.spawn(move |_| {
                let mut scratch = crate::trace::Scratch::default();
                let outlined = (run.iter())
                    .map(|group| outline_group(faces, group, points, zero_length, &mut scratch))
                    .collect();
                let mut done = done
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                done.push((first, outlined));
            });
        };
        let groups = grow_regions(faces, points, opts, |groups| hand_out(groups, false));
        hand_out(&groups, true);
        groups
    });
    let mut done = done
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    done.sort_unstable_by_key(|&(first, _)| first);
    let outlined = done.into_iter().flat_map(|(_, outlined)| outlined);
    (groups, outlined.collect())
}

/// `<base>_<counter>`, written without the formatting machinery (`format!` was a tenth of
/// the merge's own instructions on a city of small meshes).
fn numbered(base: &str, counter: usize) -> String {
    let mut digits = [0u8; 20];
    let mut at = digits.len();
    let mut rest = counter;
    loop {
        at -= 1;
        digits[at] = b'0' + (rest % 10) as u8;
        rest /= 10;
        if rest == 0 {
            break;
        }
    }
    let digits = std::str::from_utf8(&digits[at..]).unwrap_or_default();
    [base, "_", digits].concat()
}

/// The notes about faces dropped or split on the way.
fn warnings(file: &str, counts: &FaceCounts) -> Vec<String> {
    let mut warnings = Vec::new();
    let mut note = |count: usize, what: &str| {
        if count > 0 {
            warnings.push(format!("{file}: {count} {what}"));
        }
    };
    note(counts.degenerate, "degenerate (zero-area) faces dropped");
    note(
        counts.non_planar,
        "non-planar polygon faces split into fan triangles",
    );
    note(
        counts.non_simple,
        "self-touching polygon faces split into fan triangles",
    );
    note(
        counts.duplicates,
        "duplicate faces (the same vertices as an earlier face) merged into one copy",
    );
    note(
        counts.unusable,
        "faces too thin to form a valid polygon on their own dropped",
    );
    warnings
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
/// `tol` (the lowest id among equally near ones); `tol == 0` welds exact duplicates only.
#[inline(never)]
fn weld(positions: &[Vec3], tol: Real) -> (Vec<u32>, Vec<Vec3>) {
    let mut map = Vec::with_capacity(positions.len());
    let mut welded: Vec<Vec3> = Vec::new();
    if tol <= 0.0 {
        let mut exact: KeyMap<[u64; 3], u32> = KeyMap::default();
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
    let mut grid = WeldGrid::new(tol, positions.len());
    for &p in positions {
        let id = match grid.nearest(p, &welded) {
            Some(id) => id,
            None => {
                welded.push(p);
                let id = (welded.len() - 1) as u32;
                grid.insert(p, id);
                id
            }
        };
        map.push(id);
    }
    (map, welded)
}

/// The welded vertices by cell, for [`weld`]: cubes of edge `10 tol`, so that the ball of
/// radius `tol` around a point, widened to `1.2 tol` for rounding, meets at most two cells
/// per axis, and on average fewer than two in all (with cubes of `2.5 tol` it met eight
/// almost always: the look-ups were most of welding). Each cell holds a chain of ids through
/// `next` (no allocation per cell); welded vertices are more than `tol` apart, so in the
/// meshes of cities and rooms a cell holds one or two.
struct WeldGrid {
    tol: Real,
    cell: Real,
    /// The last id inserted into each cell.
    head: KeyMap<Cell, u32>,
    /// Per welded id: the id inserted before it into its cell, or `u32::MAX`.
    next: Vec<u32>,
}

/// A [`WeldGrid`] cell: a tuple, hashed as three integers (an `[i64; 3]` is hashed as 24
/// single bytes, each a round of the hasher).
type Cell = (i64, i64, i64);

impl WeldGrid {
    fn new(tol: Real, capacity: usize) -> Self {
        let mut head = KeyMap::default();
        head.reserve(capacity);
        WeldGrid {
            tol,
            cell: 10.0 * tol,
            head,
            next: Vec::with_capacity(capacity),
        }
    }

    /// The cell of `p` (`as` saturates, so absurd coordinates land in the outermost cell).
    fn cell_of(&self, p: Vec3) -> Cell {
        let [x, y, z] = (p / self.cell).to_array().map(floor_i64);
        (x, y, z)
    }

    fn insert(&mut self, p: Vec3, id: u32) {
        let cell = self.cell_of(p);
        let before = self.head.insert(cell, id).unwrap_or(u32::MAX);
        self.next.push(before);
    }

    /// The nearest welded vertex within `tol` of `p`, the lowest id among equally near ones.
    fn nearest(&self, p: Vec3, welded: &[Vec3]) -> Option<u32> {
        // A distance computed within `tol` holds a true offset within `tol (1 + 4 eps)` on
        // every axis; the margin of `0.2 tol` also covers the rounding of `p ± reach` up to
        // coordinates of `0.2 tol / eps` (9e10 m at the default 0.1 mm).
        let reach = Vec3::splat(1.2 * self.tol);
        let (lo, hi) = (self.cell_of(p - reach), self.cell_of(p + reach));
        let mut best: Option<(Real, u32)> = None;
        for x in [lo.0, hi.0].into_iter().take(1 + usize::from(hi.0 != lo.0)) {
            for y in [lo.1, hi.1].into_iter().take(1 + usize::from(hi.1 != lo.1)) {
                for z in [lo.2, hi.2].into_iter().take(1 + usize::from(hi.2 != lo.2)) {
                    let mut id = self.head.get(&(x, y, z)).copied().unwrap_or(u32::MAX);
                    while id != u32::MAX {
                        let d = welded[id as usize].distance(p);
                        if d <= self.tol && best.is_none_or(|(bd, bid)| (d, id) < (bd, bid)) {
                            best = Some((d, id));
                        }
                        id = self.next[id as usize];
                    }
                }
            }
        }
        best.map(|(_, id)| id)
    }
}

/// `x.floor() as i64` (saturating, NaN to 0) without the call to the C library's `floor`
/// that `f64::floor` is on a target without SSE4.1 (a tenth of welding): the truncation,
/// less one when it rounded up. Exact: a truncation above `x` is at most one too high, and
/// it is the integer `x` itself from 2^52 on.
fn floor_i64(x: Real) -> i64 {
    let t = x as i64;
    if t as Real > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Builds the planar, simple faces, counting in `counts` the faces dropped as degenerate and
/// the polygon faces split into fan triangles (not planar, or not simple). One pass on one
/// core: made in runs on all cores and joined, the faces cost more than they saved (the runs'
/// lists are a second copy of every face, fresh pages included).
#[inline(never)]
fn planar_faces(
    mesh: &RawMesh,
    (weld_map, points): (&[u32], &[Vec3]),
    opts: &MergeOptions,
    zero_length: Real,
    counts: &mut FaceCounts,
) -> Faces {
    let mut faces = Faces::with_capacity(mesh.face_count(), mesh.indices.len());
    let mut ids: Vec<u32> = Vec::new();
    let mut scratch: Vec<Vec3> = Vec::new();
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
        let Some(plane) = make_face(&ids, points, zero_length, &mut scratch) else {
            counts.degenerate += 1;
            continue;
        };
        let planar = ids.iter().all(|&v| {
            (points[v as usize] - plane.centroid)
                .dot(plane.normal)
                .abs()
                <= opts.dist_tol_m
        });
        let simple =
            ids.len() == 3 || (planar && is_simple_face(&ids, &plane, points, zero_length));
        if planar && simple {
            faces.push(&ids, f, key, plane);
            continue;
        }
        if planar {
            counts.non_simple += 1;
        } else {
            counts.non_planar += 1;
        }
        for k in 1..ids.len() - 1 {
            let tri = [ids[0], ids[k], ids[k + 1]];
            match make_face(&tri, points, zero_length, &mut scratch) {
                Some(t) => faces.push(&tri, f, key, t),
                None => counts.degenerate += 1,
            }
        }
    }
    faces
}

/// Whether a planar polygon face (welded `ids`, its `plane`) is simple in its plane by a
/// margin of `eps` metres (no vertex used twice, no edges touching).
fn is_simple_face(ids: &[u32], plane: &Plane, points: &[Vec3], eps: Real) -> bool {
    let u = plane.normal.any_orthonormal_vector();
    let v = plane.normal.cross(u);
    let local: Vec<Vec2> = ids
        .iter()
        .map(|&i| {
            let d = points[i as usize] - plane.centroid;
            Vec2::new(d.dot(u), d.dot(v))
        })
        .collect();
    first_contact(&local, eps).is_none()
}

/// The plane of a face of welded `ids`, or `None` when it is degenerate: fewer than three
/// distinct vertices, or an area so small that the face's height over its longest edge is
/// within `zero_length`. `pts` is scratch space (its contents are replaced).
fn make_face(
    ids: &[u32],
    points: &[Vec3],
    zero_length: Real,
    pts: &mut Vec<Vec3>,
) -> Option<Plane> {
    if ids.len() < 3 {
        return None;
    }
    pts.clear();
    pts.extend(ids.iter().map(|&i| points[i as usize]));
    let pts = pts.as_slice();
    let area_vec = 0.5 * poly2::newell(pts);
    let area = area_vec.length();
    let longest = (0..pts.len())
        .map(|i| pts[i].distance(pts[(i + 1) % pts.len()]))
        .fold(0.0, Real::max);
    if !area.is_finite() || area <= 0.5 * zero_length * longest {
        return None;
    }
    let centroid = pts.iter().sum::<Vec3>() / pts.len() as Real;
    Some(Plane {
        normal: area_vec / area,
        area,
        centroid,
    })
}

/// The faces without coincident duplicates: a face whose welded vertices are those of an
/// earlier face, in the same cyclic order either way round, is dropped (counted in `counts`).
/// Faces are sorted by the start of their canonical cycle and length, then index (no hashing,
/// no allocation per face); only faces agreeing there are compared in full, so each set of
/// copies is one run led by its first face. A large mesh's heads are taken on all cores, in
/// runs of `parallel.faces`.
#[inline(never)]
fn drop_duplicates(mut faces: Faces, counts: &mut FaceCounts, parallel: Parallel) -> Faces {
    let cycle = |i: usize| {
        let vs = faces.vertices(i);
        (0..vs.len()).map(canonical_cycle(vs))
    };
    let head = |i: usize| {
        let mut head = cycle(i);
        let mut next = || head.next().unwrap_or(u32::MAX);
        ((faces.vertices(i).len(), [next(), next(), next()]), i)
    };
    let order: Vec<((usize, [u32; 3]), usize)> = match faces.len() > parallel.faces {
        true => (0..faces.len())
            .into_par_iter()
            .with_min_len(parallel.faces)
            .map(head)
            .collect(),
        false => (0..faces.len()).map(head).collect(),
    };
    // By least vertex first: each set of copies is still one run, in index order.
    let order = crate::edges::bucket_sorted(order, |&((_, head), _)| head[0]);
    let mut duplicate = vec![false; faces.len()];
    for run in order
        .chunk_by(|a, b| a.0 == b.0)
        .filter(|run| run.len() > 1)
    {
        let mut copies: Vec<usize> = run.iter().map(|&(_, i)| i).collect();
        if run[0].0.0 > 3 {
            // Polygons agreeing in their first three vertices: order by the whole cycle.
            copies.sort_by(|&a, &b| cycle(a).cmp(cycle(b)).then(a.cmp(&b)));
        }
        for same in copies.chunk_by(|&a, &b| cycle(a).eq(cycle(b))) {
            for &i in &same[1..] {
                duplicate[i] = true;
            }
        }
    }
    let dropped = duplicate.iter().filter(|&&d| d).count();
    counts.duplicates += dropped;
    if dropped > 0 {
        let mut d = duplicate.into_iter();
        faces.list.retain(|_| !d.next().unwrap_or(false));
    }
    faces
}

/// The vertex cycle as a function of position: from its smallest id, continuing towards the
/// smaller of that id's two neighbours; the same for every rotation and both windings.
fn canonical_cycle(vs: &[u32]) -> impl Fn(usize) -> u32 + '_ {
    let n = vs.len();
    let low = (0..n).min_by_key(|&i| vs[i]).unwrap_or(0);
    let forward = vs[(low + 1) % n] <= vs[(low + n - 1) % n];
    move |k| {
        if forward {
            vs[(low + k) % n]
        } else {
            vs[(low + n - k % n) % n]
        }
    }
}

/// The groups of coplanar, edge-connected faces with the same name and material, in the
/// order of their first face; `grown` sees the groups so far each time one is complete.
#[inline(never)]
fn grow_regions(
    faces: &Faces,
    points: &[Vec3],
    opts: &MergeOptions,
    mut grown: impl FnMut(&Groups),
) -> Groups {
    let cos_tol = opts.angle_tol_deg.to_radians().cos();
    let mut edges = EdgeTable::new(faces.all_vertices());
    let mut group_of: Vec<Option<u32>> = vec![None; faces.len()];
    let mut groups = Groups {
        members: Vec::with_capacity(faces.len()),
        ends: Vec::new(),
    };
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..faces.len() {
        if group_of[seed].is_some() {
            continue;
        }
        let id = groups.len() as u32;
        group_of[seed] = Some(id);
        let start = groups.members.len();
        groups.members.push(seed);
        let mut normal_sum = faces[seed].normal * faces[seed].area;
        let mut centroid_sum = faces[seed].centroid * faces[seed].area;
        let mut area_sum = faces[seed].area;
        // The group's plane (normal, origin) as it stands, until a face joins.
        let mut plane: Option<(Vec3, Vec3)> = None;
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            let vs = faces.vertices(f);
            let n = vs.len();
            for i in 0..n {
                for other in edges.unsettled(f, i, |g| group_of[g].is_some()) {
                    if group_of[other].is_some() || faces[other].key != faces[f].key {
                        continue;
                    }
                    let (normal, origin) = *plane
                        .get_or_insert_with(|| (normal_sum.normalize(), centroid_sum / area_sum));
                    let candidate = &faces[other];
                    let coplanar = candidate.normal.dot(normal) >= cos_tol
                        && faces.vertices(other).iter().all(|&v| {
                            (points[v as usize] - origin).dot(normal).abs() <= opts.dist_tol_m
                        });
                    if coplanar {
                        group_of[other] = Some(id);
                        groups.members.push(other);
                        normal_sum += candidate.normal * candidate.area;
                        centroid_sum += candidate.centroid * candidate.area;
                        area_sum += candidate.area;
                        plane = None;
                        queue.push_back(other);
                    }
                }
            }
        }
        let members = &mut groups.members[start..];
        members.sort_unstable();
        // Distinct file faces: the runs of equal sources (as `dedup` would leave them).
        let source_faces = 1
            + (members.windows(2))
                .filter(|w| faces[w[0]].source != faces[w[1]].source)
                .count();
        groups.ends.push((groups.members.len(), source_faces));
        grown(&groups);
    }
    groups
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

    /// [`weld`] by a scan of every welded vertex: the nearest earlier one within `tol`, the
    /// lowest id among equally near ones.
    fn weld_by_scan(positions: &[Vec3], tol: Real) -> (Vec<u32>, Vec<Vec3>) {
        let mut welded: Vec<Vec3> = Vec::new();
        let map = positions
            .iter()
            .map(|&p| {
                let near = (0..welded.len() as u32)
                    .map(|id| (welded[id as usize].distance(p), id))
                    .filter(|&(d, _)| d <= tol)
                    .min_by(|a, b| a.partial_cmp(b).expect("finite"));
                near.map_or_else(
                    || {
                        welded.push(p);
                        (welded.len() - 1) as u32
                    },
                    |(_, id)| id,
                )
            })
            .collect();
        (map, welded)
    }

    proptest::proptest! {
        /// The grid of cells finds what a scan of every welded vertex finds, for points packed
        /// within a few tolerances of each other (many on and across cell boundaries), far
        /// from the origin too.
        #[test]
        fn weld_finds_what_a_scan_finds(
            steps in proptest::collection::vec((-12i32..12, -12i32..12, -3i32..3), 1..120),
            jitter in 0.0f64..0.5,
            offset in proptest::prop_oneof![proptest::strategy::Just(0.0), -5e3f64..5e3],
        ) {
            let tol = 1e-4;
            let positions: Vec<Vec3> = (steps.iter().enumerate())
                .map(|(i, &(x, y, z))| {
                    let wobble = jitter * ((i * 7 % 5) as Real - 2.0) * 0.25;
                    let grid = Vec3::new(x as Real, y as Real, z as Real) * 0.45 * tol;
                    Vec3::splat(offset) + grid + Vec3::splat(wobble * tol)
                })
                .collect();
            proptest::prop_assert_eq!(weld(&positions, tol), weld_by_scan(&positions, tol));
        }
    }

    #[test]
    fn floor_i64_is_floor_then_as() {
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            -1.0,
            1.0 - Real::EPSILON / 2.0,
            -1.0 + Real::EPSILON / 2.0,
            4503599627370495.5,
            -4503599627370495.5,
            9007199254740993.0,
            9.223372036854775e18,
            -9.223372036854775e18,
            9.3e18,
            -9.3e18,
            Real::MAX,
            Real::MIN,
            Real::INFINITY,
            Real::NEG_INFINITY,
            Real::NAN,
            Real::MIN_POSITIVE,
            -Real::MIN_POSITIVE,
        ];
        for x in edges {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }

    proptest::proptest! {
        /// Any bits at all: the cheap floor is `floor` then `as`.
        #[test]
        fn floor_i64_agrees_on_any_bits(bits in proptest::num::u64::ANY, scale in -70i32..70) {
            let x = Real::from_bits(bits);
            proptest::prop_assert_eq!(floor_i64(x), x.floor() as i64);
            let y = (bits as i64 as Real) * (2.0 as Real).powi(scale) / 3.0;
            proptest::prop_assert_eq!(floor_i64(y), y.floor() as i64);
        }
    }

    #[test]
    fn numbered_names_match_format() {
        for counter in [0, 7, 10, 99, 12345, usize::MAX] {
            assert_eq!(numbered("face", counter), format!("face_{counter}"));
        }
        assert_eq!(numbered("", 3), "_3");
    }

    #[test]
    fn canonical_cycle_ignores_rotation_and_winding() {
        let canonical = |vs: &[u32]| {
            let c = canonical_cycle(vs);
            (0..vs.len()).map(c).collect::<Vec<u32>>()
        };
        let expected = vec![1, 5, 9, 7];
        for cycle in [[1, 5, 9, 7], [9, 7, 1, 5], [7, 9, 5, 1], [5, 1, 7, 9]] {
            assert_eq!(canonical(&cycle), expected, "{cycle:?}");
        }
        assert_ne!(canonical(&[1, 9, 5, 7]), expected);
    }
}
