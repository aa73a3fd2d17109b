//! The RX side of the probes of a deferred level ([`super::Probe`]): per reflector `s`, the
//! reflectors RX sees whose mirror beam can reach `s`, so that a probe tries those instead of
//! walking the BVH of every reflector RX sees.
//!
//! A leaf `c` of a node `(.., s)` ends a candidate when the image-method point `x` (on `c`,
//! within the leaf test's margins) lies in the node's beam. Then the point `p` where the line
//! from the node's apex through `x` meets `s`'s plane lies near the node's window (the beam's
//! side planes relaxed by one tolerance, traced on `s`'s plane), and `x` lies on the segment
//! from `p` to RX's mirror image `J` in `c`. So `p` lies in `c`'s *mirror beam*: the rays from
//! `J` through `c`'s grown hull, beyond `c`'s plane. A reflector `s` whose box or grown hull
//! lies beyond one plane of `c`'s mirror beam by more than [`Reach::margin`] can therefore end
//! no candidate through `c`, whatever the node. Nor can a `c` whose grown hull lies, by more
//! than the margin, on the other side of `s`'s plane than the node's beam (each reflector
//! has one list per side). The relaxed window stays within a quarter of the
//! margin of the window only in a well-conditioned node ([`Reach::answers`]); any other node
//! walks the BVH as before.

use super::{EPS, Mirrored, Prepared, beam_planes, box_meets_halfspaces, chunked};
use bt_geom::{Plane, Real, Vec3};
use bt_scene::SurfaceId;

/// Visible reflectors per parallel task of [`Reach::of`]: a city's few hundred (Munich: 723)
/// in as many tasks as fit, not in one of 512 and one of the rest (the lists are the same
/// for any chunking: each chunk's pairs are appended in order and the counting sort keeps it).
const CHUNK: usize = 32;

/// [`Reach::margin`] in length tolerances: about a millimetre in a city of a kilometre.
const MARGIN_TOLS: Real = 1024.0;

/// Per reflector, the reflectors RX sees whose mirror beam reaches its box (module docs).
pub(super) struct Reach {
    /// Reflector `s`'s lists, `k = 2·s + side`, are `items[offsets[k]..offsets[k + 1]]`
    /// (ascending): side 0 holds the `c` whose grown hull reaches `s`'s plane's positive side
    /// within the margin, side 1 its negative side ([`Reach::of_surface`]).
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Reflectors RX sees within [`Reach::margin`] of their plane: tried by every probe (their
    /// mirror beam is too flat to bound).
    always: Vec<u32>,
    /// How far (m) a box must lie beyond a plane of a mirror beam to be left out of its list.
    margin: Real,
}

/// From this many reflectors seen by RX, a large scene's probes read the lists: below it, the
/// walk over the few visible reflectors costs less than the lists' longer runs of leaf tests
/// and their build (Florence at order 3, RX seeing 172 reflectors: +1.1 % of the candidates'
/// instructions with the lists; Munich, 723: −26.5 %).
const LISTS_FROM: usize = 256;

impl Reach {
    /// Whether to build the lists for the reflectors `visible` that RX sees: in large scenes
    /// when RX sees at least [`LISTS_FROM`] reflectors, always in small ones (whose probes
    /// would otherwise scan every visible reflector: the property tests exercise the lists
    /// there).
    pub(super) fn pays(prep: &Prepared<'_>, visible: &[u32]) -> bool {
        prep.reflectors.len() <= super::LINEAR_SCAN || visible.len() >= LISTS_FROM
    }

    /// The lists for the reflectors `visible` (ascending) that RX sees, with RX's mirror
    /// images `mirrored`.
    pub(super) fn of(prep: &Prepared<'_>, visible: &[u32], mirrored: &Mirrored) -> Reach {
        let margin = MARGIN_TOLS * prep.tol;
        let (mut pairs, mut always) = (Vec::new(), Vec::new());
        for (part, flat) in chunked::map_chunks(prep, (visible, Some(CHUNK)), |chunk| {
            reached(prep, chunk, mirrored, margin)
        }) {
            pairs.extend(part);
            always.extend(flat);
        }
        // A counting sort by reached reflector and side: each list keeps `c` ascending.
        let (offsets, items) = super::by_key(2 * prep.planes.len(), || pairs.iter().copied());
        Reach {
            offsets,
            items,
            always,
            margin,
        }
    }

    /// The reflectors a probe of a node on surface `s` with apex `apex` must try (the node's
    /// own `s` may be among them: the caller skips it). The leaf's point lies beyond the
    /// node's near plane (`s`'s plane oriented away from the apex) within one tolerance, so
    /// in the part of the leaf's grown hull on that side.
    pub(super) fn of_surface(
        &self,
        prep: &Prepared<'_>,
        s: u32,
        apex: Vec3,
    ) -> impl Iterator<Item = u32> + '_ {
        let side = usize::from(prep.plane(s).signed_distance_unfused(apex) > 0.0);
        let k = 2 * s as usize + side;
        let (lo, hi) = (self.offsets[k], self.offsets[k + 1]);
        self.always
            .iter()
            .chain(&self.items[lo as usize..hi as usize])
            .copied()
    }

    /// The reflectors of `s`'s list `side` (0: those whose grown hull reaches the positive
    /// side of `s`'s plane, used by a node whose apex lies on its negative side; 1: the
    /// reverse) and those tried by every probe.
    pub(super) fn list(&self, s: u32, side: usize) -> impl Iterator<Item = u32> + '_ {
        let k = 2 * s as usize + side;
        let (lo, hi) = (self.offsets[k], self.offsets[k + 1]);
        (self.always.iter())
            .chain(&self.items[lo as usize..hi as usize])
            .copied()
    }

    /// The length of both of surface `s`'s lists ([`Reach::list`]).
    pub(super) fn lists_len(&self, s: u32) -> usize {
        let k = 2 * s as usize;
        2 * self.always.len() + (self.offsets[k + 2] - self.offsets[k]) as usize
    }

    /// How far (m) a box may lie beyond a plane of a mirror beam and still be in its list.
    pub(super) fn margin(&self) -> Real {
        self.margin
    }

    /// Whether the lists answer for the node on surface `s` with apex `apex` (m), window
    /// `window` and beam `planes` (its near plane first): whether the point `p` of any passing
    /// leaf test (module docs) surely lies within half the margin of `s`'s box and within a
    /// quarter of it of `s`'s grown hull. It does when
    /// - every window edge has its side plane (none degenerate and left out);
    /// - `p` on `s`'s plane violates a side plane by at most 2 tolerances (the leaf test's
    ///   one, times at most 2 when `x` lies up to one tolerance before `s`'s plane: the
    ///   apex lies ≥ 8 tolerances off it), so it lies within `2·eps / (sin θ · sin(ψ/2))` of
    ///   the window, θ the smallest angle between a side plane and `s`'s plane and ψ the
    ///   window's smallest interior angle: required ≤ margin / 4;
    /// - when `x` lies before `s`'s plane, `p` lies beyond `x` by at most
    ///   `|p − apex|·eps / h`, h the apex's distance to the plane: required ≤ margin / 8;
    /// - the window lies in `s`'s grown hull, which must lie within margin / 4 of `s`'s box
    ///   (the lists are found by a walk over the surfaces' boxes).
    ///
    /// `x` lies in `c`'s grown hull, so every plane of `c`'s mirror beam holds `p` up to that
    /// and rounding; `p` lies within margin / 4 of `s`'s grown hull, so some vertex of the hull
    /// (and a point of `s`'s box) passes the plane within the margin, and `c` is in `s`'s list.
    pub(super) fn answers(
        &self,
        prep: &Prepared<'_>,
        (s, apex): (u32, Vec3),
        window: &[Vec3],
        planes: &[Plane],
    ) -> bool {
        let n = window.len();
        if planes.len() != n + 1 || n < 3 {
            return false;
        }
        let eps = EPS * prep.tol;
        let plane = prep.plane(s);
        let h = plane.signed_distance_unfused(apex).abs();
        let far = window
            .iter()
            .map(|&v| (v - apex).length_squared())
            .fold(0.0, Real::max)
            .sqrt();
        if 8.0 * eps * (far + 2.0 * self.margin) > self.margin * h {
            return false;
        }
        let cos_theta = planes[1..]
            .iter()
            .map(|p| p.normal.dot(plane.normal).abs())
            .fold(0.0, Real::max);
        let sin2_theta = 1.0 - cos_theta * cos_theta;
        let sin2_half_psi = smallest_half_angle_sin2(window);
        // 2·eps / (sin θ · sin(ψ/2)) ≤ margin / 4, squared.
        let limit = 8.0 * eps / self.margin;
        let conditioning = sin2_theta * sin2_half_psi;
        if conditioning.is_nan() || conditioning < limit * limit {
            return false;
        }
        let (lo, hi) = prep.scene.surface(SurfaceId(s)).polygon.bounds();
        let slack = Vec3::splat(0.25 * self.margin);
        let (lo, hi) = (lo - slack, hi + slack);
        prep.hull(s)
            .iter()
            .all(|&v| v.cmpge(lo).all() && v.cmple(hi).all())
    }
}

/// The (list `2·s + side` of a reached reflector `s`, `c`) pairs of the reflectors `chunk` RX
/// sees ([`Reach::offsets`]), and those of them tried by every probe ([`Reach::always`]).
fn reached(
    prep: &Prepared<'_>,
    chunk: &[u32],
    mirrored: &Mirrored,
    margin: Real,
) -> (Vec<(u32, u32)>, Vec<u32>) {
    let (mut pairs, mut always, mut planes) = (Vec::new(), Vec::new(), Vec::new());
    let scene = prep.scene;
    for &c in chunk {
        let (d_rx, image) = mirrored[c as usize];
        if d_rx.abs() <= margin {
            always.push(c);
            continue;
        }
        planes.clear();
        beam_planes(prep.plane(c), image, prep.hull(c), &mut planes);
        scene.bvh().visit(
            |lo, hi| box_meets_halfspaces(lo, hi, &planes, margin),
            |s| {
                if s != c && prep.is_reflector[s as usize] {
                    let (lo, hi) = prep.shapes.boxes[s as usize];
                    let hull = prep.hull(s);
                    let near = |p: &Plane| {
                        hull.iter()
                            .any(|&v| p.signed_distance_unfused(v) >= -margin)
                    };
                    if box_meets_halfspaces(lo, hi, &planes, margin) && planes.iter().all(near) {
                        let plane = prep.plane(s);
                        let d = prep
                            .hull(c)
                            .iter()
                            .map(|&v| plane.signed_distance_unfused(v));
                        let (least, most) = d
                            .fold((Real::INFINITY, Real::NEG_INFINITY), |(l, m), d| {
                                (l.min(d), m.max(d))
                            });
                        if most >= -margin {
                            pairs.push((2 * s, c));
                        }
                        if least <= margin {
                            pairs.push((2 * s + 1, c));
                        }
                    }
                }
            },
        );
    }
    (pairs, always)
}

/// The least `sin²(ψ/2)` over the interior angles ψ of the convex polygon `window` (1 for
/// a straight corner, 0 for a degenerate one).
fn smallest_half_angle_sin2(window: &[Vec3]) -> Real {
    let n = window.len();
    let mut least: Real = 1.0;
    for i in 0..n {
        let prev = window[if i == 0 { n - 1 } else { i - 1 }];
        let next = window[if i + 1 == n { 0 } else { i + 1 }];
        let (e_in, e_out) = (window[i] - prev, next - window[i]);
        let norms = (e_in.length_squared() * e_out.length_squared()).sqrt();
        if norms.is_nan() || norms <= 0.0 {
            return 0.0;
        }
        // ψ = π − (the turn between the edges): cos ψ = −cos(turn).
        let cos_psi = -e_in.dot(e_out) / norms;
        least = least.min(0.5 * (1.0 - cos_psi));
    }
    least
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reflector `c` (the square |x|, |y| ≤ 1 at z = 0) below RX (0, 0, 1): its mirror beam
    /// is the pyramid from J = (0, 0, −1) through `c`, whose side through `c`'s edge x = 1 is
    /// x = 1 + z. A small square at z = 1 touching that side at one corner (x = 2) lies in the
    /// beam only there: a node's ray through that corner reaches `c` at its edge, so `c` must
    /// be in the square's list for an apex above it. A square a metre beyond the side must not
    /// be. This pins the margin's sign, which the property tests cannot see (a
    /// corner of one surface on the beam's side through another's edge is too rare there):
    /// with the margin negated it fails.
    #[test]
    fn a_surface_touching_a_mirror_beam_at_one_corner_is_in_its_list() {
        // A 10 cm square at z = 1 from (x, 0).
        let square = |name: &str, x: Real| {
            let a = x + 0.1;
            format!(
                r#"{{ "name": "{name}", "vertices": [[{x},0,1],[{a},0,1],[{a},0.1,1],[{x},0.1,1]] }}"#
            )
        };
        let json = format!(
            r#"{{ "tx": [0.5, 0.3, 4], "rx": [0, 0, 1], "surfaces": [
                {{ "name": "c", "vertices": [[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]] }}, {}, {} ] }}"#,
            square("touching", 2.0),
            square("beyond", 3.0),
        );
        let scene = bt_testkit::scene_from_json(&json);
        let mut cache = super::super::TreeCache::default();
        let prep = Prepared::new(&scene, super::super::TreeOptions::new(3), &mut cache).unwrap();
        let mirrored = super::super::mirrored(&prep, scene.rx().unwrap());
        let reach = Reach::of(&prep, &prep.reflectors, &mirrored);
        let (c, touching, beyond) = (0, 1, 2);
        assert_eq!(scene.surface(SurfaceId(touching)).name, "touching");
        // A node on the square with its apex above it: its beam heads down, towards `c`.
        let list = |s: u32, x: Real| -> Vec<u32> {
            reach
                .of_surface(&prep, s, Vec3::new(x + 0.05, 0.05, 5.0))
                .collect()
        };
        let (touching, beyond) = (list(touching, 2.0), list(beyond, 3.0));
        assert!(touching.contains(&c), "{touching:?}");
        assert!(!beyond.contains(&c), "{beyond:?}");
    }

    #[test]
    fn the_smallest_half_angle_is_that_of_the_sharpest_corner() {
        // A square of side 2 in the plane x = 3, its corners a quarter turn apart.
        let square: Vec<Vec3> = (0..4)
            .map(|k| {
                let (sin, cos) = (std::f64::consts::FRAC_PI_2 * k as Real).sin_cos();
                Vec3::new(3.0, cos - sin, cos + sin)
            })
            .collect();
        // ψ = 90°: sin²(45°) = 1/2.
        assert!((smallest_half_angle_sin2(&square) - 0.5).abs() < 1e-15);
        // A sliver: ψ = atan(0.01 / 10) at the far corner, the least.
        let sliver = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 0.01, 0.0),
        ];
        let psi = (0.01_f64 / 10.0).atan();
        let expected = (0.5 * psi).sin().powi(2);
        assert!((smallest_half_angle_sin2(&sliver) - expected).abs() < 1e-8 * expected);
        // A repeated vertex makes the window degenerate.
        let repeated = [square[0], square[1], square[1], square[2]];
        assert_eq!(smallest_half_angle_sin2(&repeated), 0.0);
    }
}
