//! IPC four runs at a time: the rounds of up to [`LANES`] candidates of the same order run
//! side by side, their points and planes stored as structures of arrays so that each
//! operation of Algorithm 2 is one vector instruction over the lanes.
//!
//! A Gauss-Seidel round is a chain of dependent divisions and square roots, so one run keeps
//! the CPU waiting; four independent runs fill the vector units instead. Each lane performs
//! exactly the operations of [`crate::ipc::intersection_point`] and of the scalar round, in
//! the same order, so its outcome and points are bit for bit those of [`crate::ipc::solve`]
//! (tested). The checks after a round stay scalar, per lane ([`IpcRun`]); the lane's points
//! are copied out only for the rounds whose checks look at them.

use crate::ipc::{Acceleration, IpcOptions, IpcOutcome, IpcRun, UpdateOrder};
use bt_geom::{Plane, Real, Vec3};
use bt_scene::{Endpoints, Scene, SurfaceId};

/// Runs advanced together.
pub(crate) const LANES: usize = 4;

/// Longest chain run in lanes (the scalar run's stack copy of its planes); longer ones take
/// the scalar path.
pub(crate) const MAX_ORDER: usize = crate::ipc::LOCAL_PLANES;

type Lanes = [Real; LANES];

/// One point per lane, by coordinate.
#[derive(Clone, Copy, Default)]
struct Points {
    x: Lanes,
    y: Lanes,
    z: Lanes,
}

impl Points {
    fn splat(v: Vec3) -> Self {
        Points {
            x: [v.x; LANES],
            y: [v.y; LANES],
            z: [v.z; LANES],
        }
    }

    fn get(&self, l: usize) -> Vec3 {
        Vec3::new(self.x[l], self.y[l], self.z[l])
    }

    fn set(&mut self, l: usize, v: Vec3) {
        (self.x[l], self.y[l], self.z[l]) = (v.x, v.y, v.z);
    }
}

/// One plane per lane: unit normal by coordinate and offset (m).
#[derive(Clone, Copy, Default)]
struct Planes {
    x: Lanes,
    y: Lanes,
    z: Lanes,
    offset: Lanes,
}

/// Whether [`solve_group`] runs `options`: both update orders, without Newton acceleration
/// (whose steps need the points every round).
pub(crate) fn handles(options: &IpcOptions) -> bool {
    options.acceleration == Acceleration::None
}

/// A candidate in a lane: its position `k` in the caller's list, its sequence, its planes
/// (for the scalar checks) and its run.
struct Job<'s> {
    k: usize,
    seq: &'s [SurfaceId],
    planes: [Plane; MAX_ORDER],
    run: IpcRun<'s>,
}

/// The lanes of one chain length `n`.
struct Group<'s> {
    n: usize,
    points: [Points; MAX_ORDER],
    planes: [Planes; MAX_ORDER],
    jobs: [Option<Job<'s>>; LANES],
}

/// Run IPC with `options` (see [`handles`]) on every candidate of `items`, all of the same
/// order `n` ≤ [`MAX_ORDER`]: `(k, seq, start)` with IPC's start points (`None`: the
/// centroids). `done(k, seq, outcome, points)` receives each run's end, in the order the runs
/// end.
#[inline(always)]
pub(crate) fn solve_group<'s>(
    (scene, ends): (&'s Scene, Endpoints),
    options: &'s IpcOptions,
    n: usize,
    mut items: impl Iterator<Item = (usize, &'s [SurfaceId], Option<&'s [Vec3]>)>,
    mut done: impl FnMut(usize, &[SurfaceId], IpcOutcome, &[Vec3]),
) {
    debug_assert!(n <= MAX_ORDER && handles(options));
    let mut group = Group {
        n,
        points: [Points::default(); MAX_ORDER],
        planes: [Planes::default(); MAX_ORDER],
        jobs: std::array::from_fn(|_| None),
    };
    let Endpoints { tx, rx } = ends;
    let min_sum = crate::ipc::min_sum(scene);
    let mut out = [Vec3::ZERO; MAX_ORDER];
    loop {
        for l in 0..LANES {
            if group.jobs[l].is_none()
                && let Some((k, seq, start)) = items.next()
            {
                group.load((scene, ends), options, l, (k, seq, start));
            }
        }
        if group.jobs.iter().all(Option::is_none) {
            return;
        }
        group.open_rounds(&mut out, &mut done);
        let rounds = match options.order {
            UpdateOrder::GaussSeidel => group.round_of::<false>((tx, rx), min_sum),
            UpdateOrder::Jacobi => group.round_of::<true>((tx, rx), min_sum),
        };
        group.close_rounds(rounds, &mut out, &mut done);
    }
}

impl<'s> Group<'s> {
    /// Put candidate `(k, seq, start)` into lane `l`.
    fn load(
        &mut self,
        (scene, ends): (&'s Scene, Endpoints),
        options: &'s IpcOptions,
        l: usize,
        (k, seq, start): (usize, &'s [SurfaceId], Option<&'s [Vec3]>),
    ) {
        let n = self.n;
        let planes = crate::ipc::local_planes(scene, seq);
        let mut points = [Vec3::ZERO; MAX_ORDER];
        crate::ipc_start(scene, seq, start, &mut points[..n]);
        for (i, plane) in planes[..n].iter().enumerate() {
            let lane = &mut self.planes[i];
            (lane.x[l], lane.y[l], lane.z[l]) = (plane.normal.x, plane.normal.y, plane.normal.z);
            lane.offset[l] = plane.offset;
            self.points[i].set(l, points[i]);
        }
        let run = IpcRun::new(scene, seq, (ends.tx, ends.rx), options);
        self.jobs[l] = Some(Job {
            k,
            seq,
            planes,
            run,
        });
    }

    /// Lane `l`'s points, copied into `out`.
    fn copy_out(&self, l: usize, out: &mut [Vec3; MAX_ORDER]) {
        for (i, p) in out[..self.n].iter_mut().enumerate() {
            *p = self.points[i].get(l);
        }
    }

    /// Open a round in every lane; a run at its round cap ends and frees its lane.
    #[inline(always)]
    fn open_rounds(
        &mut self,
        out: &mut [Vec3; MAX_ORDER],
        done: &mut impl FnMut(usize, &[SurfaceId], IpcOutcome, &[Vec3]),
    ) {
        let n = self.n;
        for l in 0..LANES {
            let Some(job) = self.jobs[l].as_mut() else {
                continue;
            };
            if !job.run.at_cap() {
                job.run.count_round();
                continue;
            }
            self.copy_out(l, out);
            if let Some(job) = self.jobs[l].take() {
                let end = job.run.not_settled(&job.planes[..n], &out[..n]);
                done(job.k, job.seq, end, &out[..n]);
            }
        }
    }

    /// The checks after each lane's round (`rounds[l]`: the summed displacement, or the point
    /// whose neighbours both lie on its plane); an ended run frees its lane.
    #[inline(always)]
    fn close_rounds(
        &mut self,
        rounds: [Result<Real, usize>; LANES],
        out: &mut [Vec3; MAX_ORDER],
        done: &mut impl FnMut(usize, &[SurfaceId], IpcOutcome, &[Vec3]),
    ) {
        let n = self.n;
        for (l, round) in rounds.into_iter().enumerate() {
            let Some(job) = self.jobs[l].as_mut() else {
                continue;
            };
            if let Ok(moved) = round
                && job.run.quiet_round(moved)
            {
                continue;
            }
            self.copy_out(l, out);
            if let Some(job) = self.jobs[l].as_mut()
                && let Some(end) = job.run.end_round(&job.planes[..n], &mut out[..n], round)
            {
                done(job.k, job.seq, end, &out[..n]);
                self.jobs[l] = None;
            }
        }
    }

    /// One round in every lane, the chain length made a constant for the common orders (the
    /// round's loop then unrolls and its points stay in registers).
    #[inline(always)]
    fn round_of<const JACOBI: bool>(
        &mut self,
        ends: (Vec3, Vec3),
        min_sum: Real,
    ) -> [Result<Real, usize>; LANES] {
        match self.n {
            1 => self.round::<1, JACOBI>(ends, min_sum),
            2 => self.round::<2, JACOBI>(ends, min_sum),
            3 => self.round::<3, JACOBI>(ends, min_sum),
            _ => self.round::<MAX_ORDER, JACOBI>(ends, min_sum),
        }
    }

    /// One round in every lane (free lanes compute on stale values, never read) of a chain of
    /// `self.n` ≤ `N` points: the summed displacement per lane, or for a lane where some point's
    /// neighbours both lie on its plane, that point's index. Such a lane (rare) is rerun by the
    /// scalar round from its points before the round, which leaves them exactly as the scalar
    /// run would: the new points are written back only after the round, so the lanes still
    /// hold them.
    #[inline(always)]
    fn round<const N: usize, const JACOBI: bool>(
        &mut self,
        (tx, rx): (Vec3, Vec3),
        min_sum: Real,
    ) -> [Result<Real, usize>; LANES] {
        // The common orders run with `N` = the chain length, a constant: the loop unrolls and
        // the points are written back without a call to `memcpy`.
        let n = if N < MAX_ORDER { N } else { self.n };
        debug_assert_eq!(n, self.n);
        let mut moved = [0.0; LANES];
        let mut flat = [false; LANES];
        let mut new = [Points::default(); N];
        let mut prev = Points::splat(tx);
        // `k` indexes the points, their successors and the planes alike.
        #[allow(clippy::needless_range_loop)]
        for k in 0..n {
            let next = if k + 1 == n {
                Points::splat(rx)
            } else {
                self.points[k + 1]
            };
            let old = self.points[k];
            new[k] = update(
                &self.planes[k],
                (&prev, &next, &old),
                min_sum,
                (&mut flat, &mut moved),
            );
            prev = if JACOBI { old } else { new[k] };
        }
        if flat.iter().any(|&f| f) {
            return self.rerun_flat::<JACOBI>(&new[..n], flat, moved, (tx, rx), min_sum);
        }
        for (k, points) in new[..n].iter().enumerate() {
            self.points[k] = *points;
        }
        moved.map(Ok)
    }

    /// The end of a round in which some lanes were `flat`: those are rerun by the scalar round
    /// from their points before it (still in the lanes), the others take their `new` points.
    #[cold]
    fn rerun_flat<const JACOBI: bool>(
        &mut self,
        new: &[Points],
        flat: [bool; LANES],
        moved: Lanes,
        ends: (Vec3, Vec3),
        min_sum: Real,
    ) -> [Result<Real, usize>; LANES] {
        let rounds = std::array::from_fn(|l| match flat[l] {
            false => Ok(moved[l]),
            true => self.rerun::<JACOBI>(l, ends, min_sum),
        });
        for (k, points) in new.iter().enumerate() {
            for l in (0..LANES).filter(|&l| !flat[l]) {
                self.points[k].set(l, points.get(l));
            }
        }
        rounds
    }

    /// Lane `l`'s round rerun by the scalar round from its points before it (still in the
    /// lanes: [`Group::round`] writes the new points back after the reruns).
    #[cold]
    fn rerun<const JACOBI: bool>(
        &mut self,
        l: usize,
        (tx, rx): (Vec3, Vec3),
        min_sum: Real,
    ) -> Result<Real, usize> {
        let n = self.n;
        let Some(job) = self.jobs[l].as_ref() else {
            return Ok(0.0);
        };
        let mut points = [Vec3::ZERO; MAX_ORDER];
        for (i, p) in points[..n].iter_mut().enumerate() {
            *p = self.points[i].get(l);
        }
        let round =
            crate::ipc::round::<JACOBI>(&job.planes[..n], tx, rx, &mut points[..n], min_sum);
        for (i, p) in points[..n].iter().enumerate() {
            self.points[i].set(l, *p);
        }
        round
    }
}

/// Algorithm 2 for one point in every lane, as [`crate::ipc::intersection_point`] computes it:
/// the new points from `prev` and `next` on `plane`, their displacement from `old` added to
/// `moved`; `flat` is set for a lane whose neighbours both lie on the plane
/// (`m + n <= min_sum`, where the scalar update stops).
#[inline(always)]
fn update(
    plane: &Planes,
    (prev, next, old): (&Points, &Points, &Points),
    min_sum: Real,
    (flat, moved): (&mut [bool; LANES], &mut Lanes),
) -> Points {
    let mut new = Points::default();
    for l in 0..LANES {
        let (nx, ny, nz, off) = (plane.x[l], plane.y[l], plane.z[l], plane.offset[l]);
        let dp = nx.mul_add(
            prev.x[l],
            ny.mul_add(prev.y[l], nz.mul_add(prev.z[l], -off)),
        );
        let dn = nx.mul_add(
            next.x[l],
            ny.mul_add(next.y[l], nz.mul_add(next.z[l], -off)),
        );
        let (m, nn) = (dp.abs(), dn.abs());
        let sum = m + nn;
        flat[l] |= sum <= min_sum;
        let r = m / sum;
        let (tpx, tpy, tpz) = (
            prev.x[l] - dp * nx,
            prev.y[l] - dp * ny,
            prev.z[l] - dp * nz,
        );
        let (tnx, tny, tnz) = (
            next.x[l] - dn * nx,
            next.y[l] - dn * ny,
            next.z[l] - dn * nz,
        );
        new.x[l] = tpx + r * (tnx - tpx);
        new.y[l] = tpy + r * (tny - tpy);
        new.z[l] = tpz + r * (tnz - tpz);
        let (dx, dy, dz) = (
            new.x[l] - old.x[l],
            new.y[l] - old.y[l],
            new.z[l] - old.z[l],
        );
        moved[l] += (dx * dx + dy * dy + dz * dz).sqrt();
    }
    new
}
