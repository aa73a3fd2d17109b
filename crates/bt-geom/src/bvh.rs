//! A small bounding-volume hierarchy over axis-aligned boxes, answering "does this segment hit
//! anything?" queries for path validation.
//!
//! Why our own and not parry's: occlusion here is a test against bounded *polygons* with the
//! same tolerance rule as the inside test of interaction points ([`crate::Polygon::blocks_segment`]),
//! with the surfaces the segment starts and ends on excluded, and we need any hit, not the first.
//! A BVH over polygon boxes with a caller-supplied exact test does exactly that in ~100 lines,
//! without triangulating concave polygons.

use crate::{Real, Vec3};

/// An object that can occlude a segment.
pub trait Occluder {
    /// Axis-aligned bounding box `(min, max)`, metres.
    fn bounds(&self) -> (Vec3, Vec3);
}

impl<T: Occluder> Occluder for &T {
    fn bounds(&self) -> (Vec3, Vec3) {
        (*self).bounds()
    }
}

impl Occluder for (Vec3, Vec3) {
    fn bounds(&self) -> (Vec3, Vec3) {
        *self
    }
}

impl Occluder for crate::Polygon {
    fn bounds(&self) -> (Vec3, Vec3) {
        crate::Polygon::bounds(self)
    }
}

#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: first item in `order`; inner: index of the right child (left child follows).
    start_or_right: u32,
    /// Number of items for a leaf, 0 for an inner node.
    count: u32,
}

/// A BVH over items `0..n` of some slice, built once per scene (or time step).
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Small sets ([`SCAN_UP_TO`] items or fewer): every item's box, for segment queries that
    /// test them all in index order instead of walking the tree.
    boxes: Option<Boxes>,
}

/// Items in a leaf, at most, in trees of [`SCAN_UP_TO`] items or fewer (rooms: their segment
/// queries scan every box, and their box queries run 3 % faster a living-room trace than
/// with leaves of 2).
const LEAF_SIZE: usize = 4;
/// Items in a leaf, at most, in trees of more than [`SCAN_UP_TO`] items (cities: the smaller
/// leaves spare more item tests than their extra nodes cost, Munich's whole trace −0.6 % of
/// its instructions and 3-8 % of its time).
const LARGE_LEAF_SIZE: usize = 2;

/// Up to this many items, a segment query tests every item's box in turn: in a room a walk
/// visits a third of the nodes anyway, one box at a time, while the boxes stored as arrays
/// are tested several at once by the CPU's vector units.
pub const SCAN_UP_TO: usize = 64;

/// Boxes tested at once by `Boxes::scan` (four `f64` in an AVX register).
const LANES: usize = 4;

/// Item boxes in groups of [`LANES`], padded with zeros to whole groups.
#[derive(Debug, Clone, Default)]
struct Boxes {
    groups: Vec<Group>,
    /// Items stored (the groups hold as many, then the padding).
    len: usize,
}

/// The boxes of [`LANES`] consecutive items, by bound, coordinate and item (m): fixed-size
/// arrays, so that the scan loads them without bounds checks.
#[derive(Debug, Clone, Copy, Default)]
struct Group {
    min: [[Real; LANES]; 3],
    max: [[Real; LANES]; 3],
}

impl Bvh {
    /// Build over the bounding boxes of `items`: each node split where the surface-area
    /// heuristic expects the fewest box tests (box centres in 8 bins along their
    /// longest axis), or at the median of the node's longest axis where the centres
    /// coincide. Any split gives the same answers; the heuristic's visit fewer nodes in
    /// scenes whose surfaces differ in size (a city's ground and facades: 13 % fewer
    /// instructions a Munich trace than median splits).
    pub fn build<T: Occluder>(items: &[T]) -> Self {
        let boxes: Vec<(Vec3, Vec3)> = items.iter().map(Occluder::bounds).collect();
        let mut order: Vec<u32> = (0..items.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * items.len().max(1));
        if !items.is_empty() {
            let centres: Vec<Vec3> = boxes.iter().map(|(lo, hi)| *lo + *hi).collect();
            let built = Built {
                boxes: &boxes,
                centres: &centres,
                leaf_size: if items.len() > SCAN_UP_TO {
                    LARGE_LEAF_SIZE
                } else {
                    LEAF_SIZE
                },
            };
            build_node(&built, &mut order, 0, items.len(), &mut nodes);
        }
        // Padded to whole groups (the padding's bits are masked off in `scan`).
        let scan = (boxes.len() <= SCAN_UP_TO).then(|| {
            let mut groups = vec![Group::default(); boxes.len().div_ceil(LANES)];
            for (i, (min, max)) in boxes.iter().enumerate() {
                let group = &mut groups[i / LANES];
                for k in 0..3 {
                    group.min[k][i % LANES] = min[k];
                    group.max[k][i % LANES] = max[k];
                }
            }
            Boxes {
                groups,
                len: boxes.len(),
            }
        });
        Self {
            nodes,
            order,
            boxes: scan,
        }
    }

    /// Calls `hit(item)` for every item whose box, grown by `margin` metres on every side, the
    /// segment `a -> b` touches, stopping at and returning the first item for which `hit`
    /// returns true. Exact tests that accept points within a tolerance of a polygon (such as
    /// [`crate::Polygon::blocks_segment`]) need a margin of at least that tolerance: their
    /// hits may lie outside the polygon's box. (The growth is folded into the segment's start,
    /// so it costs nothing per box; it is exact up to one rounding of `a ± margin`, so pass
    /// some slack, e.g. twice the tolerance.)
    #[inline(always)]
    pub fn any_hit(
        &self,
        a: Vec3,
        b: Vec3,
        margin: Real,
        hit: impl FnMut(u32) -> bool,
    ) -> Option<u32> {
        let slab = Slab::new(a, b, margin);
        match &self.boxes {
            Some(boxes) => boxes.scan(&slab, hit),
            None => self.walk(|min, max| slab.hits_box(min, max), hit),
        }
    }

    /// The items [`Bvh::any_hit`] would offer its `hit` for the segment `a -> b` and `margin`,
    /// as bits (bit `i` for item `i`: lowest first is `any_hit`'s order), when the BVH scans
    /// every box (at most [`SCAN_UP_TO`] items); `None` for a tree. For a caller that tests
    /// the items in its own loop (a closure's body is compiled apart from a caller's target
    /// features).
    #[inline(always)]
    pub fn touched_by(&self, a: Vec3, b: Vec3, margin: Real) -> Option<u64> {
        let boxes = self.boxes.as_ref()?;
        Some(boxes.touched(&Slab::new(a, b, margin)))
    }

    /// The one traversal: descend into nodes whose box passes `box_test`, call `hit` on the
    /// items of the leaves reached, stop at (and return) the first item `hit` accepts.
    #[inline(always)]
    fn walk(
        &self,
        mut box_test: impl FnMut(Vec3, Vec3) -> bool,
        mut hit: impl FnMut(u32) -> bool,
    ) -> Option<u32> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let index = stack[top];
            let node = self.nodes[index as usize];
            if !box_test(node.min, node.max) {
                continue;
            }
            if node.count > 0 {
                let start = node.start_or_right as usize;
                for &item in &self.order[start..start + node.count as usize] {
                    if hit(item) {
                        return Some(item);
                    }
                }
            } else if top + 2 <= stack.len() {
                // The left child is stored right after its parent.
                stack[top] = node.start_or_right;
                stack[top + 1] = index + 1;
                top += 2;
            }
        }
        None
    }
}

impl Bvh {
    /// The box `(min, max)` around every item (the root's, metres), `None` without items:
    /// the bits of folding `min` and `max` over the items' boxes in any order.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.nodes.first().map(|root| (root.min, root.max))
    }

    /// Calls `visit(item)` for every item of the leaves whose box passes `box_test(min, max)`,
    /// descending only into nodes whose box passes it: every item whose own box passes, and
    /// others of the same leaves (the caller's exact test refuses those). `box_test` must be
    /// conservative (a node's box contains its items' boxes): answering `false` for a box
    /// prunes everything inside it.
    #[inline]
    pub fn visit(&self, box_test: impl FnMut(Vec3, Vec3) -> bool, mut visit: impl FnMut(u32)) {
        self.walk(box_test, |item| {
            visit(item);
            false
        });
    }

    /// The first item (in walk order) whose box passes `box_test` and that `hit` accepts,
    /// descending only into nodes whose box passes `box_test` (conservative, as for
    /// [`Bvh::visit`]); the walk stops there.
    #[inline]
    pub fn find(
        &self,
        box_test: impl FnMut(Vec3, Vec3) -> bool,
        hit: impl FnMut(u32) -> bool,
    ) -> Option<u32> {
        self.walk(box_test, hit)
    }

    /// Calls `visit(item)` for every item whose box meets the cube of half-side `radius`
    /// (metres) around `p`.
    #[inline]
    pub fn visit_near(&self, p: Vec3, radius: Real, visit: impl FnMut(u32)) {
        let (lo, hi) = (p - Vec3::splat(radius), p + Vec3::splat(radius));
        self.visit(|min, max| min.cmple(hi).all() && max.cmpge(lo).all(), visit);
    }

    /// Calls `visit(item)` for every item whose box, grown by `margin` metres, the segment
    /// `a -> b` touches (see [`Bvh::any_hit`]).
    #[inline]
    pub fn visit_segment(&self, a: Vec3, b: Vec3, margin: Real, visit: impl FnMut(u32)) {
        let slab = Slab::new(a, b, margin);
        self.visit(|min, max| slab.hits_box(min, max), visit);
    }
}

/// Whether the box `min..max` may reach the convex region `{x : p.signed_distance(x) >= -eps}`
/// for every plane `p` (false only when the whole box lies beyond one plane).
#[inline]
pub fn box_meets_halfspaces(min: Vec3, max: Vec3, planes: &[crate::Plane], eps: Real) -> bool {
    planes.iter().all(|p| {
        // The distance of the box corner furthest along the normal, without branching on the
        // normal's signs: per axis the larger of the two products is the far corner's (a
        // product with a non-negative factor is monotone under rounding), summed in
        // `dot`'s order, so the value is exactly `signed_distance_unfused(far)`.
        let far = (p.normal * min).max(p.normal * max);
        far.x + far.y + far.z - p.offset >= -eps
    })
}

/// The items' boxes and their centres (doubled: `min + max`), for the build.
struct Built<'a> {
    boxes: &'a [(Vec3, Vec3)],
    centres: &'a [Vec3],
    /// Items in a leaf, at most.
    leaf_size: usize,
}

fn build_node(
    built: &Built<'_>,
    order: &mut [u32],
    start: usize,
    end: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in &order[start..end] {
        min = min.min(built.boxes[i as usize].0);
        max = max.max(built.boxes[i as usize].1);
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        min,
        max,
        start_or_right: start as u32,
        count: (end - start) as u32,
    });
    if end - start <= built.leaf_size {
        return index;
    }
    let mid = start
        + sah_split(built, &mut order[start..end])
            .unwrap_or_else(|| median_split(built.centres, &mut order[start..end], max - min));
    build_node(built, order, start, mid, nodes);
    let right = build_node(built, order, mid, end, nodes);
    nodes[index as usize].start_or_right = right;
    nodes[index as usize].count = 0;
    index
}

/// Bins of [`sah_split`].
const BINS: usize = 8;

/// Half the surface area of the box `min..max` (m²; zero for an empty box).
fn half_area(min: Vec3, max: Vec3) -> Real {
    let d = (max - min).max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The axis (0, 1, 2) along which `extent` is longest, x before y before z on ties.
fn longest_axis(extent: Vec3) -> usize {
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// The surface-area heuristic's best split of `order` along the longest axis of its items'
/// centres, the centres binned: reorders `order` so that the first `k` items go left and
/// returns `k`, or `None` when the centres coincide along that axis.
fn sah_split(built: &Built<'_>, order: &mut [u32]) -> Option<usize> {
    let (boxes, centres) = (built.boxes, built.centres);
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in order.iter() {
        lo = lo.min(centres[i as usize]);
        hi = hi.max(centres[i as usize]);
    }
    let axis = longest_axis(hi - lo);
    // Coinciding centres (or a NaN) leave no cut.
    if hi[axis].partial_cmp(&lo[axis]) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let scale = BINS as Real / (hi[axis] - lo[axis]);
    let bin_of = |i: u32| (((centres[i as usize][axis] - lo[axis]) * scale) as usize).min(BINS - 1);
    let mut bins = [(Vec3::INFINITY, Vec3::NEG_INFINITY, 0usize); BINS];
    for &i in order.iter() {
        let b = &mut bins[bin_of(i)];
        b.0 = b.0.min(boxes[i as usize].0);
        b.1 = b.1.max(boxes[i as usize].1);
        b.2 += 1;
    }
    // The right side's cost of each cut by a sweep from the end, then the left sweep's best.
    let mut right = [0.0; BINS];
    let (mut rmin, mut rmax, mut rn) = (Vec3::INFINITY, Vec3::NEG_INFINITY, 0);
    for b in (1..BINS).rev() {
        rmin = rmin.min(bins[b].0);
        rmax = rmax.max(bins[b].1);
        rn += bins[b].2;
        right[b] = half_area(rmin, rmax) * rn as Real;
    }
    let mut best: Option<(Real, usize)> = None;
    let (mut lmin, mut lmax, mut ln) = (Vec3::INFINITY, Vec3::NEG_INFINITY, 0);
    for cut in 1..BINS {
        lmin = lmin.min(bins[cut - 1].0);
        lmax = lmax.max(bins[cut - 1].1);
        ln += bins[cut - 1].2;
        let cost = half_area(lmin, lmax) * ln as Real + right[cut];
        if ln > 0 && ln < order.len() && best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, cut));
        }
    }
    let (_, cut) = best?;
    // In place and deterministic: the items of the bins below the cut to the front.
    let mut k = 0;
    for j in 0..order.len() {
        if bin_of(order[j]) < cut {
            order.swap(k, j);
            k += 1;
        }
    }
    Some(k)
}

/// The object-median split on the longest axis of the node's box (`extent`), for items
/// whose centres coincide: returns the left half's length.
fn median_split(centres: &[Vec3], order: &mut [u32], extent: Vec3) -> usize {
    let axis = longest_axis(extent);
    let centre = |i: &u32| centres[*i as usize][axis];
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |a, b| centre(a).total_cmp(&centre(b)));
    mid
}

impl Boxes {
    /// [`Bvh::any_hit`] by testing every box: `hit` on the items whose box `slab` touches, in
    /// index order, up to the first it accepts.
    #[inline(always)]
    fn scan(&self, slab: &Slab, mut hit: impl FnMut(u32) -> bool) -> Option<u32> {
        let mut touched = self.touched(slab);
        while touched != 0 {
            let j = touched.trailing_zeros();
            if hit(j) {
                return Some(j);
            }
            touched &= touched - 1;
        }
        None
    }
}

impl Boxes {
    /// The items whose box `slab` touches, as bits (bit `i` for item `i`).
    #[inline(always)]
    fn touched(&self, slab: &Slab) -> u64 {
        let mut touched = 0u64;
        // At most SCAN_UP_TO / LANES groups (`Bvh::build`); the bound, known to the compiler,
        // also makes it lay the loop out well (without it the diffracted trace costs 23 %
        // more instructions).
        for (g, group) in self.groups.iter().take(SCAN_UP_TO / LANES).enumerate() {
            touched |= u64::from(group.hit_by(slab)) << (g * LANES);
        }
        let n = self.len;
        touched & if n >= 64 { u64::MAX } else { (1 << n) - 1 }
    }
}

impl Group {
    /// The group's boxes against `slab` ([`Slab::hits_box`], lane by lane, written so that
    /// the compiler keeps the lanes in one vector register): bit `l` for box `l`.
    #[inline(always)]
    fn hit_by(&self, slab: &Slab) -> u8 {
        let (from_min, from_max, inv) = (
            slab.from_min.to_array(),
            slab.from_max.to_array(),
            slab.inv.to_array(),
        );
        let mut enter = [0.0 as Real; LANES];
        let mut exit = [1.0 as Real; LANES];
        for k in 0..3 {
            let (lo, hi) = (self.min[k], self.max[k]);
            for l in 0..LANES {
                let t0 = (lo[l] - from_min[k]) * inv[k];
                let t1 = (hi[l] - from_max[k]) * inv[k];
                // As `Vec3::min`/`max` (the first if strictly less/greater, else the
                // second), then `f64::max`/`min` (NaN dropped): `Slab::hits_box` exactly.
                let (near, far) = (if t0 < t1 { t0 } else { t1 }, if t0 > t1 { t0 } else { t1 });
                enter[l] = enter[l].max(near);
                exit[l] = exit[l].min(far);
            }
        }
        let mut bits = 0u8;
        for l in 0..LANES {
            bits |= u8::from(enter[l] <= exit[l]) << l;
        }
        bits
    }
}

/// The slab test of a segment against boxes grown by a margin.
struct Slab {
    /// The segment's start moved by `+margin` and `-margin` on every axis: a box face at `min`
    /// grown to `min - margin` is crossed where `min - (a + margin)` is, and likewise for `max`.
    from_min: Vec3,
    from_max: Vec3,
    /// 1 / (b - a) per axis (infinite on axes the segment does not move along).
    inv: Vec3,
}

impl Slab {
    #[inline(always)]
    fn new(a: Vec3, b: Vec3, margin: Real) -> Self {
        let d = b - a;
        let m = Vec3::splat(margin);
        Slab {
            from_min: a + m,
            from_max: a - m,
            inv: Vec3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z),
        }
    }

    /// Whether the segment touches the box `min..max` grown by the margin (inclusive).
    #[inline(always)]
    fn hits_box(&self, min: Vec3, max: Vec3) -> bool {
        let t0 = (min - self.from_min) * self.inv;
        let t1 = (max - self.from_max) * self.inv;
        let lo = t0.min(t1);
        let hi = t0.max(t1);
        // NaN (0 * inf: a segment that runs exactly in the plane of a grown face) is dropped,
        // and the box is missed: the segment then lies exactly the margin away from the box,
        // beyond any tolerance the margin covers. `enter` (`exit`) is the largest (smallest)
        // of 0 (1) and the values of `lo` (`hi`) that are not NaN, as `f64::max`/`min` would
        // fold them, but each step one compare-and-select (a comparison with NaN is false, so
        // the running value, never NaN, is kept) instead of `f64::max`'s NaN handling: a
        // third of the instructions of a BVH walk's box test. Only the sign of a zero may
        // differ from the fold, which `<=` does not see.
        let (mut enter, mut exit): (Real, Real) = (0.0, 1.0);
        for k in 0..3 {
            enter = if lo[k] > enter { lo[k] } else { enter };
            exit = if hi[k] < exit { hi[k] } else { exit };
        }
        enter <= exit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Polygon;

    fn quad(x: Real) -> Polygon {
        Polygon::new(vec![
            Vec3::new(x, 0., 0.),
            Vec3::new(x, 1., 0.),
            Vec3::new(x, 1., 1.),
            Vec3::new(x, 0., 1.),
        ])
        .unwrap()
    }

    /// The walls `blocks_segment` (tolerance `tol`) accepts for `a -> b`: all of them, and
    /// those the BVH with a margin of twice the tolerance offers.
    fn brute_and_bvh(walls: &[Polygon], bvh: &Bvh, (a, b): (Vec3, Vec3)) -> (Vec<u32>, Vec<u32>) {
        let tol = 1e-9;
        let blocks = |i: u32| walls[i as usize].blocks_segment(a, b, tol, tol);
        let brute: Vec<u32> = (0..walls.len() as u32).filter(|&i| blocks(i)).collect();
        let mut seen = Vec::new();
        bvh.any_hit(a, b, 2.0 * tol, |i| {
            if blocks(i) {
                seen.push(i);
            }
            false
        });
        seen.sort();
        (brute, seen)
    }

    /// Walls at x = 0, 0.5, 1, ...: few enough to be scanned, and too many (the tree is walked).
    fn wall_sets() -> [Vec<Polygon>; 2] {
        let walls = |n: usize| (0..n).map(|i| quad(i as Real * 0.5)).collect::<Vec<_>>();
        [walls(37), walls(SCAN_UP_TO + 37)]
    }

    #[test]
    fn finds_the_same_hits_as_brute_force() {
        for walls in wall_sets() {
            let bvh = Bvh::build(&walls);
            assert_eq!(bvh.boxes.is_some(), walls.len() <= SCAN_UP_TO);
            assert_eq!(
                bvh.touched_by(Vec3::ZERO, Vec3::X, 0.0).is_some(),
                bvh.boxes.is_some()
            );
            for k in 0..50 {
                let a = Vec3::new(k as Real * 0.37 - 1.0, 0.5, 0.5);
                let b = a + Vec3::new(0.9, 0.1, 0.05);
                let (brute, seen) = brute_and_bvh(&walls, &bvh, (a, b));
                assert_eq!(brute, seen, "segment {k} among {} walls", walls.len());
            }
        }
    }

    /// `find` answers whether some item in the boxes a test accepts is accepted, as a visit
    /// of every such item would, and stops at the first (no item is offered after it).
    #[test]
    fn find_stops_at_the_first_accepted_item_of_a_visit() {
        for walls in wall_sets() {
            let bvh = Bvh::build(&walls);
            for (lo, hi) in [(3.2, 9.9), (-1.0, -0.5), (0.0, 100.0)] {
                let in_slab = |min: Vec3, max: Vec3| max.x >= lo && min.x <= hi;
                let mut visited = Vec::new();
                bvh.visit(in_slab, |i| visited.push(i));
                for wanted in [7u32, 40, 1000] {
                    let mut offered = Vec::new();
                    let found = bvh.find(in_slab, |i| {
                        offered.push(i);
                        i == wanted
                    });
                    assert_eq!(found.is_some(), visited.contains(&wanted), "{lo} {wanted}");
                    assert_eq!(offered.last() == Some(&wanted), found.is_some());
                    assert!(offered.iter().all(|i| visited.contains(i)));
                }
            }
        }
    }

    /// `Slab::hits_box` as it was written with `f64::max`/`min` (NaN dropped): the reference
    /// its compare-and-select folds must agree with.
    fn hits_box_folded(slab: &Slab, min: Vec3, max: Vec3) -> bool {
        let t0 = (min - slab.from_min) * slab.inv;
        let t1 = (max - slab.from_max) * slab.inv;
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let enter = lo.x.max(lo.y).max(lo.z).max(0.0 as Real);
        let exit = hi.x.min(hi.y).min(hi.z).min(1.0);
        enter <= exit
    }

    /// Item boxes for the build's tests: a grid of cells (so that many centres coincide
    /// across cells' copies), each a box, a flat box (a wall: zero thickness on one axis) or
    /// a point, some repeated, with a few large boxes across the others.
    fn item_boxes(cells: &[(u8, u8, u8, u8)], big: &[(u8, u8)]) -> Vec<(Vec3, Vec3)> {
        let mut boxes = Vec::new();
        for &(x, y, kind, copies) in cells {
            let lo = Vec3::new(x as Real, y as Real, 0.0);
            let hi = match kind % 4 {
                0 => lo + Vec3::new(0.8, 0.6, 3.0),
                1 => lo + Vec3::new(0.0, 0.9, 2.0),
                2 => lo + Vec3::new(0.7, 0.0, 1.0),
                _ => lo,
            };
            boxes.extend(std::iter::repeat_n((lo, hi), 1 + copies as usize % 3));
        }
        for &(a, b) in big {
            let (a, b) = (a as Real, b as Real);
            boxes.push((
                Vec3::new(a.min(b), 0.0, -1.0),
                Vec3::new(a.max(b) + 1.0, 40.0, 0.0),
            ));
        }
        boxes
    }

    proptest::proptest! {
        /// Whatever the split (surface-area heuristic, or the median where centres coincide),
        /// every item is in exactly one leaf, every leaf's box holds its items' boxes, and a
        /// box query offers every item a test of every box finds (and others of the same
        /// leaves, which the callers' exact tests then refuse).
        #[test]
        fn the_tree_holds_every_item_once_and_queries_find_all(
            cells in proptest::collection::vec((0u8..12, 0u8..12, 0u8..4, 0u8..3), 20..160),
            big in proptest::collection::vec((0u8..12, 0u8..12), 0..4),
            query in (0u8..12, 0u8..12, 1u8..6, 1u8..6),
        ) {
            let boxes = item_boxes(&cells, &big);
            let bvh = Bvh::build(&boxes);
            let mut leaves = Vec::new();
            bvh.visit(|_, _| true, |i| leaves.push(i));
            leaves.sort_unstable();
            proptest::prop_assert_eq!(leaves, (0..boxes.len() as u32).collect::<Vec<_>>());
            for node in &bvh.nodes {
                if node.count > 0 {
                    let start = node.start_or_right as usize;
                    for &i in &bvh.order[start..start + node.count as usize] {
                        let (lo, hi) = boxes[i as usize];
                        proptest::prop_assert!(node.min.cmple(lo).all() && hi.cmple(node.max).all());
                    }
                }
            }
            let lo = Vec3::new(query.0 as Real, query.1 as Real, 0.5);
            let hi = lo + Vec3::new(query.2 as Real, query.3 as Real, 1.0);
            let meets = |min: Vec3, max: Vec3| min.cmple(hi).all() && max.cmpge(lo).all();
            let brute: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| meets(boxes[i as usize].0, boxes[i as usize].1))
                .collect();
            let mut found = vec![false; boxes.len()];
            bvh.visit(meets, |i| found[i as usize] = true);
            proptest::prop_assert!(brute.iter().all(|&i| found[i as usize]));
        }
    }

    proptest::proptest! {
        /// The slab test's compare-and-select folds answer as `f64::max`/`min`'s, on a coarse
        /// grid (segments along axes and in the planes of grown faces: NaN), with margins
        /// 0 and 1, on inverted boxes too, and with infinite or NaN ends.
        #[test]
        fn the_slab_test_folds_as_f64_max_and_min(
            corners in proptest::array::uniform6(-2i8..3),
            ends in proptest::array::uniform6(-3i8..4),
            margin in 0i8..2,
            odd in 0usize..8,
        ) {
            let v = |c: &[i8]| Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real);
            let (lo, hi) = (v(&corners[..3]), v(&corners[3..]));
            let (mut a, b) = (v(&ends[..3]), v(&ends[3..]));
            // Odd ends: one coordinate infinite or NaN (odd = 6, 7: none).
            if odd < 6 {
                a[odd % 3] = [Real::INFINITY, Real::NEG_INFINITY][odd / 3 % 2];
                if odd == 5 {
                    a[0] = Real::NAN;
                }
            }
            let slab = Slab::new(a, b, margin as Real);
            for (min, max) in [(lo.min(hi), lo.max(hi)), (lo, hi)] {
                proptest::prop_assert_eq!(slab.hits_box(min, max), hits_box_folded(&slab, min, max));
            }
        }
    }

    proptest::proptest! {
        /// The scan (four boxes per step) touches exactly the boxes the one-box slab test
        /// touches, on a coarse grid where segments run along axes and
        /// in the planes of grown faces (the NaN cases).
        #[test]
        fn the_scans_touch_what_the_slab_test_touches(
            corners in proptest::collection::vec(proptest::array::uniform6(-2i8..3), 1..40),
            ends in proptest::array::uniform6(-3i8..4),
        ) {
            let margin = 1.0;
            let v = |c: &[i8]| Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real);
            let boxes: Vec<(Vec3, Vec3)> = corners
                .iter()
                .map(|c| (v(&c[..3]).min(v(&c[3..])), v(&c[..3]).max(v(&c[3..]))))
                .collect();
            let bvh = Bvh::build(&boxes);
            let (a, b) = (v(&ends[..3]), v(&ends[3..]));
            let slab = Slab::new(a, b, margin);
            let expected: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| slab.hits_box(boxes[i as usize].0, boxes[i as usize].1))
                .collect();
            let mut seen = Vec::new();
            proptest::prop_assert_eq!(bvh.any_hit(a, b, margin, |i| { seen.push(i); false }), None);
            proptest::prop_assert_eq!(&seen, &expected);
            // `touched_by`'s bits are the items `any_hit` offers, lowest first.
            let bits = bvh.touched_by(a, b, margin);
            let from_bits: Option<Vec<u32>> =
                bits.map(|t| (0..64).filter(|i| t >> i & 1 == 1).collect());
            proptest::prop_assert_eq!(from_bits, Some(expected));
        }
    }

    #[test]
    fn finds_hits_within_the_tolerance_outside_the_boxes() {
        // Segments that pass just outside the walls' edges (inside the tolerance, so
        // `blocks_segment` accepts them), along an edge and obliquely, and ones just beyond it.
        for walls in wall_sets() {
            hits_within_the_tolerance(&walls);
        }
    }

    fn hits_within_the_tolerance(walls: &[Polygon]) {
        let bvh = Bvh::build(walls);
        for off in [0.0, 0.5e-9, 0.99e-9, 1.5e-9, 3e-9] {
            let along = (
                Vec3::new(0.1, 1.0 + off, 0.5),
                Vec3::new(17.9, 1.0 + off, 0.5),
            );
            let oblique = (
                Vec3::new(0.2, 0.9 + off, -0.2),
                Vec3::new(0.8, 1.1 + off, 1.0 + off),
            );
            for (what, seg) in [("along", along), ("oblique", oblique)] {
                let (brute, seen) = brute_and_bvh(walls, &bvh, seg);
                assert_eq!(brute, seen, "{what} segment at {off} m beyond the edge");
                assert_eq!(brute.is_empty(), off > 1e-9, "{what} segment at {off} m");
            }
        }
    }
}
