//! Newton polish of a nearly converged IPC chain ([`crate::ipc::Acceleration::Newton`]).
//!
//! Why the path length: Algorithm 2 puts a point where the two-segment length
//! |s_k − s_{k−1}| + |s_{k+1} − s_k| is smallest on its plane (the reflection point when the
//! neighbours are on one side, the straight crossing when they are on both). So a Gauss-Seidel
//! round is one sweep of exact block coordinate descent on the path length
//! L = Σ_j |s_{j+1} − s_j| over the infinite planes, and the fixed point of IPC (either order)
//! is the point where ∇L vanishes in every plane: the law of reflection. L is a sum of norms of
//! affine functions of the in-plane coordinates, hence convex; its minimiser is the
//! image-method path.
//!
//! Coordinate descent converges linearly with a rate set by the conditioning of ∇²L, which is
//! poor when two surfaces of the chain nearly meet at the bounce points (near a corner the
//! rate creeps to 1). Newton's method on ∇L = 0 does not care: with 2 in-plane unknowns per
//! point the Hessian is block tridiagonal (2×2 blocks, point k couples only to k ± 1), solved
//! by block elimination in O(n). Each step is accepted only if L does not grow beyond
//! round-off; a failure (singular block, non-finite value, no decrease) restores the points
//! and hands the run back to the paper's rounds.

use bt_geom::{Plane, Real, Vec3};

/// Longest chain polished by Newton (stack buffers); longer ones run the paper's rounds only.
pub const MAX_ORDER: usize = 8;

/// Result of [`polish`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Polish {
    /// A full Newton step of mean length at most the threshold was taken (or the steps
    /// stopped shrinking at round-off level); `last_step` is its summed length, metres.
    Converged {
        /// Newton steps taken.
        steps: u32,
        /// Summed point displacement of the last step, metres.
        last_step: Real,
    },
    /// No convergence; the points are as on entry.
    Failed {
        /// Newton steps attempted.
        steps: u32,
    },
}

/// Symmetric-or-not 2×2 matrix, row-major `[[a, b], [c, d]]`.
#[derive(Debug, Clone, Copy, Default)]
struct M2 {
    a: Real,
    b: Real,
    c: Real,
    d: Real,
}

impl M2 {
    #[inline(always)]
    fn mul(self, o: M2) -> M2 {
        M2 {
            a: self.a * o.a + self.b * o.c,
            b: self.a * o.b + self.b * o.d,
            c: self.c * o.a + self.d * o.c,
            d: self.c * o.b + self.d * o.d,
        }
    }
    #[inline(always)]
    fn apply(self, x: [Real; 2]) -> [Real; 2] {
        [self.a * x[0] + self.b * x[1], self.c * x[0] + self.d * x[1]]
    }
    #[inline(always)]
    fn transpose(self) -> M2 {
        M2 {
            a: self.a,
            b: self.c,
            c: self.b,
            d: self.d,
        }
    }
    #[inline(always)]
    fn sub(self, o: M2) -> M2 {
        M2 {
            a: self.a - o.a,
            b: self.b - o.b,
            c: self.c - o.c,
            d: self.d - o.d,
        }
    }
    /// Inverse of a symmetric positive definite block, `None` when (numerically) singular.
    #[inline(always)]
    fn inverse_spd(self) -> Option<M2> {
        let det = self.a * self.d - self.b * self.c;
        let scale = self.a + self.d;
        // Relative test: the Schur complements of an SPD matrix are SPD; a determinant at
        // round-off level relative to the squared trace means a grazing or collinear chain.
        let regular = det > 1e-13 * scale * scale && det.is_finite();
        if !regular {
            return None;
        }
        let inv = 1.0 / det;
        Some(M2 {
            a: self.d * inv,
            b: -self.b * inv,
            c: -self.c * inv,
            d: self.a * inv,
        })
    }
}

/// Unit direction and inverse length of the segment `a -> b`, `None` if degenerate.
#[inline(always)]
fn segment(a: Vec3, b: Vec3) -> Option<(Vec3, Real)> {
    let r = b - a;
    let len = r.length();
    let inv = 1.0 / len;
    (len > 0.0 && inv.is_finite()).then_some((r * inv, inv))
}

/// `pᵀ (I − r rᵀ) q / ℓ` for unit `r` and inverse length `inv`.
#[inline(always)]
fn bilinear(p: Vec3, q: Vec3, r: Vec3, inv: Real) -> Real {
    (p.dot(q) - p.dot(r) * q.dot(r)) * inv
}

fn path_length(tx: Vec3, rx: Vec3, points: &[Vec3]) -> Real {
    let mut prev = tx;
    let mut sum = 0.0;
    for p in points {
        sum += prev.distance(*p);
        prev = *p;
    }
    sum + prev.distance(rx)
}

/// Block tridiagonal system of one Newton step: diagonal blocks, upper blocks (k, k+1), and
/// the negative in-plane gradient.
struct System {
    diag: [M2; MAX_ORDER],
    upper: [M2; MAX_ORDER],
    rhs: [[Real; 2]; MAX_ORDER],
}

impl System {
    /// The Newton system of the path length in the points' in-plane frames (`frames[k]`),
    /// from the segments' unit directions and inverse lengths (`dirs[j]`, segment `j` ending
    /// at point `j`): block-tridiagonal Hessian and minus the gradient. Returns the Hessian's
    /// scale, its largest diagonal entry (the stiffest segment's 1/ℓ).
    fn assemble(&mut self, frames: &[(Vec3, Vec3)], dirs: &[(Vec3, Real)]) -> Real {
        let n = frames.len();
        let mut scale: Real = 0.0;
        for k in 0..n {
            let (u, v) = frames[k];
            let (r_in, inv_in) = dirs[k];
            let (r_out, inv_out) = dirs[k + 1];
            let g = r_in - r_out;
            let b = bilinear(u, v, r_in, inv_in) + bilinear(u, v, r_out, inv_out);
            self.diag[k] = M2 {
                a: bilinear(u, u, r_in, inv_in) + bilinear(u, u, r_out, inv_out),
                b,
                c: b,
                d: bilinear(v, v, r_in, inv_in) + bilinear(v, v, r_out, inv_out),
            };
            scale = scale.max(self.diag[k].a).max(self.diag[k].d);
            self.rhs[k] = [-u.dot(g), -v.dot(g)];
            if k + 1 < n {
                let (u2, v2) = frames[k + 1];
                self.upper[k] = M2 {
                    a: -bilinear(u, u2, r_out, inv_out),
                    b: -bilinear(u, v2, r_out, inv_out),
                    c: -bilinear(v, u2, r_out, inv_out),
                    d: -bilinear(v, v2, r_out, inv_out),
                };
            }
        }
        scale
    }

    /// Solve (H + mu I) δ = −g by block elimination into `step`; false when a pivot block is
    /// singular.
    fn solve(&self, n: usize, mu: Real, step: &mut [[Real; 2]; MAX_ORDER]) -> bool {
        let mut pivot_inv = [M2::default(); MAX_ORDER];
        let mut rhs = [[0.0; 2]; MAX_ORDER];
        for k in 0..n {
            let mut d = self.diag[k];
            d.a += mu;
            d.d += mu;
            let mut r = self.rhs[k];
            if k > 0 {
                // lower block (k, k-1) = upper(k-1)ᵀ
                let w = self.upper[k - 1].transpose().mul(pivot_inv[k - 1]);
                d = d.sub(w.mul(self.upper[k - 1]));
                let wy = w.apply(rhs[k - 1]);
                r = [r[0] - wy[0], r[1] - wy[1]];
            }
            let Some(inv) = d.inverse_spd() else {
                return false;
            };
            pivot_inv[k] = inv;
            rhs[k] = r;
        }
        for k in (0..n).rev() {
            let mut y = rhs[k];
            if k + 1 < n {
                let cx = self.upper[k].apply(step[k + 1]);
                y = [y[0] - cx[0], y[1] - cx[1]];
            }
            step[k] = pivot_inv[k].apply(y);
        }
        step[..n]
            .iter()
            .all(|s| s[0].is_finite() && s[1].is_finite())
    }
}

/// Damped (or halved) steps allowed in one polish. A chain whose length is smallest where two
/// of its points meet on the edge between their planes (no real double bounce there) has a
/// kink at its minimum, where Newton never takes a full step; IPC's rounds then decide.
const MAX_DAMPED_STEPS: u32 = 6;

/// Damping attempts per Newton iteration (the damping grows 100-fold per attempt).
const DAMPING_ATTEMPTS: u32 = 12;

/// The line search of one Newton iteration: its damping and the path length it must not grow.
struct Search {
    /// Path length of the accepted points, metres.
    length: Real,
    /// Relative round-off allowed on the length.
    slack: Real,
    /// Levenberg-Marquardt damping (0: pure Newton).
    mu: Real,
    /// The damping a first damped attempt starts from (scaled to this iteration's system).
    mu_min: Real,
}

impl Search {
    /// Tries an undamped full step, an undamped half step, then growing damping, from `current`
    /// into `points`; the first step that does not lengthen the path is kept. Returns the
    /// step's total point displacement (metres) and whether it was a full undamped step, or
    /// `None` when every attempt failed.
    #[inline(always)]
    fn step(
        &mut self,
        system: &System,
        frames: &[(Vec3, Vec3)],
        current: &[Vec3],
        points: &mut [Vec3],
        (tx, rx): (Vec3, Vec3),
    ) -> Option<(Real, bool)> {
        let n = points.len();
        let mut step = [[0.0; 2]; MAX_ORDER];
        for attempt in 0..DAMPING_ATTEMPTS {
            let factor = if self.mu == 0.0 && attempt == 1 {
                0.5
            } else {
                1.0
            };
            if self.mu == 0.0 && attempt >= 2 {
                self.mu = self.mu_min;
            }
            if system.solve(n, self.mu, &mut step) {
                let mut moved = 0.0;
                for k in 0..n {
                    let (u, v) = frames[k];
                    let (dx, dy) = (factor * step[k][0], factor * step[k][1]);
                    points[k] = current[k] + dx * u + dy * v;
                    moved += (dx * dx + dy * dy).sqrt();
                }
                let new_length = path_length(tx, rx, points);
                if moved.is_finite() && new_length <= self.length * (1.0 + self.slack) {
                    self.length = new_length.min(self.length);
                    return Some((moved, factor == 1.0 && self.mu == 0.0));
                }
            }
            if self.mu > 0.0 {
                self.mu *= 100.0;
            }
        }
        None
    }
}

/// Newton steps on ∇L = 0 for the chain `tx -> points -> rx` over `planes`, until a full step's
/// mean point displacement is at most `threshold` metres. On `Failed` the points are restored.
///
/// Globalisation: a step is accepted only if the path length does not grow beyond round-off.
/// A full Newton step is tried first (then half of it); when both fail, the step is damped
/// Levenberg-Marquardt style, (H + μI) δ = −g with μ growing 100-fold per attempt, which near
/// the kink of a millimetre segment (bounces next to a corner) keeps the step from
/// overshooting along the nearly flat direction. Convergence is declared only on full,
/// undamped steps.
pub fn polish(
    planes: &[Plane],
    tx: Vec3,
    rx: Vec3,
    points: &mut [Vec3],
    threshold: Real,
) -> Polish {
    let n = points.len();
    if n == 0 || n > MAX_ORDER {
        return Polish::Failed { steps: 0 };
    }
    let mut saved = [Vec3::ZERO; MAX_ORDER];
    saved[..n].copy_from_slice(points);
    let mut frames = [(Vec3::ZERO, Vec3::ZERO); MAX_ORDER];
    for (f, plane) in frames.iter_mut().zip(planes) {
        *f = plane.normal.any_orthonormal_pair();
    }
    // Segment j joins point j - 1 and point j (TX = -1, RX = n).
    let mut dirs = [(Vec3::ZERO, 0.0); MAX_ORDER + 1];
    let mut system = System {
        diag: [M2::default(); MAX_ORDER],
        upper: [M2::default(); MAX_ORDER],
        rhs: [[0.0; 2]; MAX_ORDER],
    };
    let mut current = [Vec3::ZERO; MAX_ORDER];
    let mut search = Search {
        length: path_length(tx, rx, points),
        // Round-off of L: n + 1 square roots and sums, each within a few ulps.
        slack: 4.0 * (n + 1) as Real * Real::EPSILON,
        mu: 0.0,
        mu_min: 0.0,
    };
    let mut last_full = Real::INFINITY;
    let (mut steps, mut damped) = (0, 0);
    let fail = |points: &mut [Vec3], steps| {
        points.copy_from_slice(&saved[..n]);
        Polish::Failed { steps }
    };
    while steps < crate::ipc::NEWTON_MAX_STEPS {
        steps += 1;
        for (j, dir) in dirs.iter_mut().enumerate().take(n + 1) {
            let a = if j == 0 { tx } else { points[j - 1] };
            let b = if j == n { rx } else { points[j] };
            match segment(a, b) {
                Some(d) => *dir = d,
                None => return fail(points, steps),
            }
        }
        let scale = system.assemble(&frames[..n], &dirs[..=n]);
        search.mu_min = 1e-9 * scale;
        current[..n].copy_from_slice(points);
        let accepted = search.step(&system, &frames[..n], &current[..n], points, (tx, rx));
        let Some((moved, full)) = accepted else {
            return fail(points, steps);
        };
        if !full {
            damped += 1;
            if damped > MAX_DAMPED_STEPS {
                return fail(points, steps);
            }
        }
        if search.mu > 0.0 {
            // Success: relax the damping, back to pure Newton once it is negligible.
            let mu = search.mu / 1e4;
            search.mu = if mu < search.mu_min { 0.0 } else { mu };
            continue;
        }
        if full {
            if moved <= threshold * n as Real {
                return Polish::Converged {
                    steps,
                    last_step: moved,
                };
            }
            // Quadratic convergence stopped: the steps are round-off noise.
            if moved > 0.5 * last_full && moved <= 1e3 * threshold * n as Real {
                return Polish::Converged {
                    steps,
                    last_step: moved,
                };
            }
            last_full = moved;
        }
    }
    fail(points, steps)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(point: Vec3, normal: Vec3) -> Plane {
        Plane::from_point_normal(point, normal)
    }

    #[test]
    fn one_wall_polishes_to_the_mirror_point() {
        let walls = [plane(Vec3::ZERO, Vec3::Z)];
        let (tx, rx) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(4.0, 0.0, 3.0));
        // Exact: TX image (0, 0, -1), line to RX crosses z = 0 at x = 1.
        let mut points = [Vec3::new(1.3, 0.2, 0.0)];
        let out = polish(&walls, tx, rx, &mut points, 1e-13);
        assert!(matches!(out, Polish::Converged { .. }), "{out:?}");
        assert!(
            points[0].distance(Vec3::new(1.0, 0.0, 0.0)) < 1e-14,
            "{points:?}"
        );
    }

    #[test]
    fn corner_chain_converges_and_failures_restore_the_points() {
        // Two walls meeting at the z axis (a 90° corner), bounce points 1 mm and 2 mm from the
        // edge; TX and RX placed by the reflection law.
        let walls = [plane(Vec3::ZERO, Vec3::X), plane(Vec3::ZERO, Vec3::Y)];
        let (p1, p2) = (Vec3::new(0.0, 1e-3, 0.5), Vec3::new(2e-3, 0.0, 0.7));
        let o = (p2 - p1).normalize();
        let tx = p1 - 2.0 * (o - 2.0 * o.x * Vec3::X);
        let rx = p2 + 2.0 * (o - 2.0 * o.y * Vec3::Y);
        let mut points = [
            p1 + Vec3::new(0.0, 1e-3, -2e-3),
            p2 + Vec3::new(-1e-3, 0.0, 1e-3),
        ];
        let out = polish(&walls, tx, rx, &mut points, 1e-13);
        assert!(matches!(out, Polish::Converged { .. }), "{out:?}");
        // The problem is ill-conditioned (a 2 mm segment between 2 m ones): the round-off of
        // TX and RX alone moves the solution by ~1e-11 m. The length is well-conditioned.
        assert!(
            points[0].distance(p1) < 1e-10 && points[1].distance(p2) < 1e-10,
            "{points:?}"
        );
        let image = Plane::from_point_normal(Vec3::ZERO, Vec3::Y)
            .mirror(Plane::from_point_normal(Vec3::ZERO, Vec3::X).mirror(tx));
        assert!((path_length(tx, rx, &points) - image.distance(rx)).abs() < 1e-14);
        // Grazing: TX and RX on the first plane; the system is singular; the points must come
        // back unchanged and finite.
        let start = [Vec3::new(0.0, 1.0, 1.0), Vec3::new(1.0, 0.0, 1.0)];
        let mut points = start;
        let grazing = polish(
            &walls,
            Vec3::new(0.0, 2.0, 1.0),
            Vec3::new(0.0, 3.0, 1.0),
            &mut points,
            1e-13,
        );
        if let Polish::Failed { .. } = grazing {
            assert_eq!(points, start);
        }
        assert!(points.iter().all(|p| p.is_finite()));
    }
}
