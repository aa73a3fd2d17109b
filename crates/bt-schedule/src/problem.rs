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
pub(crate) struct Prepared<'a> {
    pub problem: &'a Problem,
    /// Jobs per plane over all paths and rounds, indexed by plane.
    pub load: Vec<u64>,
    /// Distinct planes used, ascending.
    pub used_planes: Vec<u32>,
    /// First job index of each path (`paths.len() + 1` entries). Job index of
    /// `(path, round, point)` is `job_offset[path] + round * order + point`.
    pub job_offset: Vec<u32>,
    /// First path-round index of each path (`paths.len() + 1` entries).
    pub round_offset: Vec<u32>,
    /// Distinct `(plane, count)` needed by one round of each path, flattened.
    needs: Vec<(u32, u32)>,
    need_offset: Vec<u32>,
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

        let n = problem.paths.len();
        let mut load = vec![0u64; problem.num_planes as usize];
        let mut job_offset = Vec::with_capacity(n + 1);
        let mut round_offset = Vec::with_capacity(n + 1);
        let mut needs = Vec::new();
        let mut need_offset = Vec::with_capacity(n + 1);
        let (mut jobs, mut rounds) = (0u32, 0u64);
        for path in &problem.paths {
            job_offset.push(jobs);
            round_offset.push(rounds);
            need_offset.push(needs.len() as u32);
            let start = needs.len();
            for &plane in &path.planes {
                load[plane as usize] += u64::from(path.rounds);
                match needs[start..].iter_mut().find(|(q, _)| *q == plane) {
                    Some((_, count)) => *count += 1,
                    None => needs.push((plane, 1)),
                }
            }
            // Bounded by MAX_JOBS above.
            jobs += path.planes.len() as u32 * path.rounds;
            rounds += u64::from(path.rounds);
        }
        job_offset.push(jobs);
        round_offset.push(rounds);
        need_offset.push(needs.len() as u32);
        // Rounds <= jobs <= MAX_JOBS since every path has a point.
        let round_offset = round_offset.into_iter().map(|r| r as u32).collect();
        Ok(Prepared {
            problem,
            load,
            used_planes: used_planes(problem),
            job_offset,
            round_offset,
            needs,
            need_offset,
        })
    }

    pub fn total_jobs(&self) -> usize {
        *self.job_offset.last().unwrap_or(&0) as usize
    }

    pub fn total_rounds(&self) -> usize {
        *self.round_offset.last().unwrap_or(&0) as usize
    }

    /// Distinct `(plane, count)` one round of `path` needs.
    pub fn needs(&self, path: usize) -> &[(u32, u32)] {
        &self.needs[self.need_offset[path] as usize..self.need_offset[path + 1] as usize]
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
