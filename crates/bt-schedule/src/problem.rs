//! Validation of a [`Problem`] and the validated view the schedulers work on.

use crate::error::{ProblemIssue, Report, ScheduleError};
use crate::{Budget, PeInstance, Problem};

/// Job indices are `u32` internally; `u32::MAX` marks "none".
const MAX_JOBS: u64 = u32::MAX as u64 - 1;

impl Problem {
    /// Checks the problem and reports every defect at once: empty paths, paths with zero
    /// rounds, plane indices `>= num_planes`, the same plane at two consecutive points, and
    /// sizes beyond the `u32` ids. The same plane at non-consecutive points (A-B-A) is legal:
    /// both jobs of a round then need a PE of that plane, so they take two slots unless the
    /// plane's PE is duplicated.
    pub fn validate(&self) -> Result<(), ScheduleError> {
        Prepared::new(self).map(|_| ())
    }
}

/// Distinct planes used by the paths, ascending (only in-range entries).
pub(crate) fn used_planes(problem: &Problem) -> Vec<u32> {
    let mut used = vec![false; problem.num_planes as usize];
    for path in &problem.paths {
        for &plane in &path.planes {
            if let Some(u) = used.get_mut(plane as usize) {
                *u = true;
            }
        }
    }
    (0..problem.num_planes)
        .filter(|&p| used[p as usize])
        .collect()
}

/// A validated problem with the indices the schedulers need.
///
/// Within a round, a path's jobs are indexed by *rank*: the points of phase 0 first (in point
/// order), then those of phase 1, ..., so that every phase's jobs are contiguous. A *unit* is
/// one phase of one round, the schedulers' atom of dependency: it starts after the unit
/// before it of the same path has ended.
pub(crate) struct Prepared<'a> {
    pub problem: &'a Problem,
    /// Jobs per plane over all paths and rounds, indexed by plane.
    pub load: Vec<u64>,
    /// Distinct planes used, ascending.
    pub used_planes: Vec<u32>,
    /// First job index of each path (`paths.len() + 1` entries). Job index of
    /// `(path, round, point)` is `job_offset[path] + round * order + rank(point)`.
    pub job_offset: Vec<u32>,
    /// First unit index of each path (`paths.len() + 1` entries); unit `round * phases +
    /// phase` of a path.
    pub unit_offset: Vec<u32>,
    /// Effective phases per round of each path (1..=order).
    phases: Vec<u32>,
    /// Per path (at `point_offset[path]`), the point of each rank.
    ranked_points: Vec<u32>,
    /// Per path, the plane of each rank.
    ranked_planes: Vec<u32>,
    point_offset: Vec<u32>,
    /// Distinct `(plane, count)` needed by one unit of each path and phase, flattened.
    needs: Vec<(u32, u32)>,
    /// `need_offset[phase_offset[path] + phase]..` holds that phase's needs.
    need_offset: Vec<u32>,
    phase_offset: Vec<u32>,
}

/// The first rank of phase `h` in a round of `order` points over `phases` phases, and its
/// size: phase `h` holds points `h, h + phases, ...`.
fn phase_span(order: u32, phases: u32, h: u32) -> (u32, u32) {
    let size = |g: u32| (order - g).div_ceil(phases);
    ((0..h).map(size).sum(), size(h))
}

impl<'a> Prepared<'a> {
    pub fn new(problem: &'a Problem) -> Result<Self, ScheduleError> {
        let mut issues = Report::new();
        if u32::try_from(problem.paths.len()).is_err() {
            issues.push(ProblemIssue::TooManyPaths {
                count: problem.paths.len() as u64,
            });
            return Err(ScheduleError::InvalidProblem(issues));
        }
        let mut total_jobs: u64 = 0;
        for (p, path) in problem.paths.iter().enumerate() {
            let p = p as u32;
            if path.planes.is_empty() {
                issues.push(ProblemIssue::EmptyPath { path: p });
            }
            if path.rounds == 0 {
                issues.push(ProblemIssue::ZeroRounds { path: p });
            }
            if path.phases == 0 {
                issues.push(ProblemIssue::ZeroPhases { path: p });
            }
            for (i, &plane) in path.planes.iter().enumerate() {
                let point = u32::try_from(i).unwrap_or(u32::MAX);
                if plane >= problem.num_planes {
                    issues.push(ProblemIssue::PlaneOutOfRange {
                        path: p,
                        point,
                        plane,
                        num_planes: problem.num_planes,
                    });
                }
                if i > 0 && path.planes[i - 1] == plane {
                    issues.push(ProblemIssue::RepeatedPlane {
                        path: p,
                        point,
                        plane,
                    });
                }
            }
            total_jobs =
                total_jobs.saturating_add((path.planes.len() as u64) * u64::from(path.rounds));
        }
        if total_jobs > MAX_JOBS {
            issues.push(ProblemIssue::TooManyJobs {
                count: total_jobs,
                limit: MAX_JOBS,
            });
        }
        if !issues.is_empty() {
            return Err(ScheduleError::InvalidProblem(issues));
        }

        Ok(Self::index(problem))
    }

    /// The indices of a problem that passed the checks of [`Prepared::new`].
    fn index(problem: &'a Problem) -> Self {
        let n = problem.paths.len();
        let mut prep = Prepared {
            problem,
            load: vec![0u64; problem.num_planes as usize],
            used_planes: used_planes(problem),
            job_offset: Vec::with_capacity(n + 1),
            unit_offset: Vec::with_capacity(n + 1),
            phases: Vec::with_capacity(n),
            ranked_points: Vec::new(),
            ranked_planes: Vec::new(),
            point_offset: Vec::with_capacity(n + 1),
            needs: Vec::new(),
            need_offset: Vec::new(),
            phase_offset: Vec::with_capacity(n + 1),
        };
        let (mut jobs, mut units) = (0u32, 0u64);
        for path in &problem.paths {
            let order = path.planes.len() as u32;
            let phases = path.phases.clamp(1, order);
            prep.job_offset.push(jobs);
            prep.unit_offset.push(units as u32);
            prep.point_offset.push(prep.ranked_points.len() as u32);
            prep.phase_offset.push(prep.need_offset.len() as u32);
            prep.phases.push(phases);
            for h in 0..phases {
                prep.need_offset.push(prep.needs.len() as u32);
                let start = prep.needs.len();
                for i in (h..order).step_by(phases as usize) {
                    let plane = path.planes[i as usize];
                    prep.ranked_points.push(i);
                    prep.ranked_planes.push(plane);
                    prep.load[plane as usize] += u64::from(path.rounds);
                    match prep.needs[start..].iter_mut().find(|(q, _)| *q == plane) {
                        Some((_, count)) => *count += 1,
                        None => prep.needs.push((plane, 1)),
                    }
                }
            }
            // Bounded by MAX_JOBS above.
            jobs += order * path.rounds;
            units += u64::from(path.rounds) * u64::from(phases);
        }
        prep.job_offset.push(jobs);
        // Units <= jobs <= MAX_JOBS since every phase has a point.
        prep.unit_offset.push(units as u32);
        prep.point_offset.push(prep.ranked_points.len() as u32);
        prep.phase_offset.push(prep.need_offset.len() as u32);
        prep.need_offset.push(prep.needs.len() as u32);
        prep
    }

    pub fn total_jobs(&self) -> usize {
        *self.job_offset.last().unwrap_or(&0) as usize
    }

    pub fn total_units(&self) -> usize {
        *self.unit_offset.last().unwrap_or(&0) as usize
    }

    /// Effective phases per round of `path`.
    pub fn phases(&self, path: usize) -> u32 {
        self.phases[path]
    }

    /// The ranks of phase `phase` of `path` within a round.
    pub fn phase_ranks(&self, path: usize, phase: u32) -> std::ops::Range<usize> {
        let order = self.problem.paths[path].planes.len() as u32;
        let (start, size) = phase_span(order, self.phases[path], phase);
        start as usize..(start + size) as usize
    }

    /// The planes of phase `phase` of `path`, in rank order.
    pub fn phase_planes(&self, path: usize, phase: u32) -> &[u32] {
        let base = self.point_offset[path] as usize;
        let r = self.phase_ranks(path, phase);
        &self.ranked_planes[base + r.start..base + r.end]
    }

    /// The point of rank `rank` of `path`.
    pub fn point_of_rank(&self, path: usize, rank: usize) -> u32 {
        self.ranked_points[self.point_offset[path] as usize + rank]
    }

    /// The rank of point `point` of `path` (which must exist).
    pub fn rank_of_point(&self, path: usize, point: u32) -> usize {
        let order = self.problem.paths[path].planes.len() as u32;
        let phases = self.phases[path];
        let (start, _) = phase_span(order, phases, point % phases);
        (start + point / phases) as usize
    }

    /// Distinct `(plane, count)` one unit of phase `phase` of `path` needs.
    pub fn needs(&self, path: usize, phase: u32) -> &[(u32, u32)] {
        let k = (self.phase_offset[path] + phase) as usize;
        &self.needs[self.need_offset[k] as usize..self.need_offset[k + 1] as usize]
    }

    /// Fails unless `budget` gives every used plane one PE.
    pub fn check_budget(&self, budget: &Budget) -> Result<(), ScheduleError> {
        let needed = self.used_planes.len() as u32;
        if budget.max_instances < needed {
            return Err(ScheduleError::BudgetTooSmall {
                max_instances: budget.max_instances,
                needed,
            });
        }
        Ok(())
    }

    /// `copies[p]` PEs of plane `p`, raised to one for every used plane.
    pub fn copies_at_least(&self, copies: &[u32]) -> Vec<u32> {
        self.base_copies()
            .iter()
            .enumerate()
            .map(|(p, &base)| base.max(copies.get(p).copied().unwrap_or(0)))
            .collect()
    }

    /// One PE per used plane.
    pub fn base_copies(&self) -> Vec<u32> {
        let mut copies = vec![0u32; self.problem.num_planes as usize];
        for &p in &self.used_planes {
            copies[p as usize] = 1;
        }
        copies
    }
}

/// The PE instances of a schedule under construction, sorted by `(plane, copy)`.
#[derive(Debug, Clone)]
pub(crate) struct InstanceSet {
    pub instances: Vec<PeInstance>,
    /// `first[plane]..first[plane + 1]` are the columns of that plane's copies.
    first: Vec<u32>,
}

impl InstanceSet {
    /// `copies[plane]` instances of each plane.
    pub fn from_copies(copies: &[u32]) -> Self {
        let mut instances = Vec::new();
        let mut first = Vec::with_capacity(copies.len() + 1);
        for (plane, &n) in copies.iter().enumerate() {
            first.push(instances.len() as u32);
            instances.extend((0..n).map(|copy| PeInstance {
                plane: plane as u32,
                copy,
            }));
        }
        first.push(instances.len() as u32);
        InstanceSet { instances, first }
    }

    /// Columns holding copies of `plane`.
    pub fn columns(&self, plane: u32) -> std::ops::Range<usize> {
        self.first[plane as usize] as usize..self.first[plane as usize + 1] as usize
    }

    pub fn len(&self) -> usize {
        self.instances.len()
    }
}
