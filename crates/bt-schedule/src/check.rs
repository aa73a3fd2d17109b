//! Legality check and measurements of a [`Schedule`].

use std::collections::BTreeSet;

use crate::error::{Report, ScheduleError, ScheduleViolation};
use crate::occupancy::NONE;
use crate::problem::Prepared;
use crate::{Job, PeInstance, Problem, Schedule};

/// Measurements of a schedule (serialised next to `schedule.json`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScheduleStats {
    /// Slots up to and including the last one holding a job.
    pub makespan: u32,
    /// Latency factor after eq. 14, in slots: the sum over paths **and units** (phases of
    /// rounds; a Jacobi round is one unit) of (latest slot - earliest slot) of that unit's
    /// jobs. The paper sums over paths only; a path spans all its rounds, so we take each
    /// unit on its own, which is 0 exactly when every unit runs all its PEs in one slot (the
    /// paper's goal).
    pub latency_factor: u64,
    /// Busy cells / (instances x makespan), in [0, 1]; 0 for an empty schedule.
    pub utilisation: f64,
    /// PE instances (columns), originals and duplicates.
    pub instances: u32,
    /// Duplicates: the dedicated instances minus distinct planes among them (generic PEs are
    /// no plane's duplicates).
    pub duplicates: u32,
    /// Jobs placed (cells holding a job).
    pub jobs: u64,
    /// A lower bound on the makespan with these instances, in slots: the larger of the
    /// busiest plane's jobs per copy and, over paths, rounds x slots one round's phases need;
    /// on generic PEs, the jobs over the PEs.
    pub makespan_lower_bound: u32,
}

impl Schedule {
    /// Verifies the schedule is legal for `problem` and reports every violation at once:
    /// each job `(path, round < rounds, point)` appears exactly once; it runs on an instance of
    /// the plane of its point; instances are distinct and of existing planes; every slot row
    /// has one entry per instance (so an instance runs at most one job per slot); and phase
    /// order: every job of a unit (phase of a round) of a path is in a slot strictly later
    /// than every job of the unit before it of that path.
    pub fn check(&self, problem: &Problem) -> Result<(), ScheduleError> {
        let prep = Prepared::new(problem)?;
        let mut report = Report::new();
        self.check_instances(problem, &mut report);
        let at = self.check_slots(problem, &prep, &mut report);
        check_rounds(problem, &prep, &at, &mut report);
        if report.is_empty() {
            Ok(())
        } else {
            Err(ScheduleError::IllegalSchedule(report))
        }
    }

    /// Instances are distinct and of existing planes.
    fn check_instances(&self, problem: &Problem, report: &mut Report<ScheduleViolation>) {
        let mut seen = BTreeSet::new();
        for (i, inst) in self.instances.iter().enumerate() {
            if !seen.insert(*inst) {
                report.push(ScheduleViolation::DuplicateInstance {
                    plane: inst.plane,
                    copy: inst.copy,
                });
            }
            if inst.plane >= problem.num_planes && !inst.is_generic() {
                report.push(ScheduleViolation::InstancePlaneOutOfRange {
                    instance: to_u32(i),
                    plane: inst.plane,
                    num_planes: problem.num_planes,
                });
            }
        }
    }

    /// Every slot row has one entry per instance, each a job of `problem` on an instance of
    /// its point's plane, no job twice; returns the slot of each job (`NONE` where missing),
    /// by job index.
    fn check_slots(
        &self,
        problem: &Problem,
        prep: &Prepared<'_>,
        report: &mut Report<ScheduleViolation>,
    ) -> Vec<u32> {
        let mut at = vec![NONE; prep.total_jobs()];
        for (t, row) in self.slots.iter().enumerate() {
            let slot = to_u32(t);
            if row.len() != self.instances.len() {
                report.push(ScheduleViolation::RowLength {
                    slot,
                    len: to_u32(row.len()),
                    expected: to_u32(self.instances.len()),
                });
            }
            for (i, cell) in row.iter().enumerate().take(self.instances.len()) {
                let Some(job) = *cell else { continue };
                let instance = to_u32(i);
                let Some(index) = job_index(prep, job) else {
                    report.push(ScheduleViolation::UnknownJob {
                        slot,
                        instance,
                        job,
                    });
                    continue;
                };
                let expected = problem.paths[job.path as usize].planes[job.point as usize];
                let plane = self.instances[i].plane;
                if !self.instances[i].takes(expected) {
                    report.push(ScheduleViolation::WrongPlane {
                        job,
                        instance,
                        plane,
                        expected,
                    });
                }
                if at[index] == NONE {
                    at[index] = slot;
                } else {
                    report.push(ScheduleViolation::DuplicateJob {
                        job,
                        first: at[index],
                        slot,
                    });
                }
            }
        }
        at
    }

    /// Measures the schedule. Meant for schedules that pass [`Schedule::check`]; on others it
    /// is best effort (jobs that are not part of `problem` are ignored for the latency factor).
    pub fn stats(&self, problem: &Problem) -> ScheduleStats {
        let makespan = self.makespan();
        let instances = to_u32(self.instances.len());
        let dedicated: Vec<PeInstance> = self
            .instances
            .iter()
            .copied()
            .filter(|i| !i.is_generic())
            .collect();
        let planes: BTreeSet<u32> = dedicated.iter().map(|i| i.plane).collect();
        let generic = instances - to_u32(dedicated.len());
        let jobs = self.job_count();
        let cells = u64::from(instances) * u64::from(makespan);
        let utilisation = if cells == 0 {
            0.0
        } else {
            jobs as f64 / cells as f64
        };

        // Span of every unit; jobs that are not part of the problem are skipped.
        let prep = Prepared::new(problem).ok();
        let mut span = vec![(u32::MAX, 0u32); prep.as_ref().map_or(0, |p| p.total_units())];
        for (t, row) in self.slots.iter().enumerate() {
            for job in row.iter().flatten() {
                let Some(unit) = prep.as_ref().and_then(|p| unit_index(p, *job)) else {
                    continue;
                };
                let s = &mut span[unit];
                s.0 = s.0.min(to_u32(t));
                s.1 = s.1.max(to_u32(t));
            }
        }
        let latency_factor = span
            .iter()
            .filter(|s| s.0 != u32::MAX)
            .map(|&(a, b)| u64::from(b - a))
            .sum();

        let mut copies = vec![0u32; problem.num_planes as usize];
        for inst in &self.instances {
            if let Some(c) = copies.get_mut(inst.plane as usize) {
                *c += 1;
            }
        }
        ScheduleStats {
            makespan,
            latency_factor,
            utilisation,
            instances,
            duplicates: to_u32(dedicated.len()) - to_u32(planes.len()),
            jobs,
            makespan_lower_bound: if generic > 0 {
                // Any PE takes any job: the work spread over all of them.
                u32::try_from(jobs.div_ceil(u64::from(instances))).unwrap_or(u32::MAX)
            } else {
                lower_bound(problem, &copies)
            },
        }
    }
}

/// Makespan lower bound in slots with `copies[plane]` PEs per plane (a plane without PE is
/// counted as having one, so the bound stays finite).
pub(crate) fn lower_bound(problem: &Problem, copies: &[u32]) -> u32 {
    let per_copy = |jobs: u64, plane: u32| {
        let c = u64::from(copies.get(plane as usize).copied().unwrap_or(0).max(1));
        jobs.div_ceil(c)
    };
    let mut load = vec![0u64; problem.num_planes as usize];
    let mut chain = 0u64;
    let mut counts: Vec<(u32, u64)> = Vec::new();
    for path in &problem.paths {
        let order = path.planes.len();
        let phases = (path.phases as usize).clamp(1, order.max(1));
        let mut per_round = 0;
        for h in 0..phases {
            counts.clear();
            for &plane in path.planes.iter().skip(h).step_by(phases) {
                if let Some(l) = load.get_mut(plane as usize) {
                    *l += u64::from(path.rounds);
                }
                match counts.iter_mut().find(|(q, _)| *q == plane) {
                    Some((_, n)) => *n += 1,
                    None => counts.push((plane, 1)),
                }
            }
            per_round += counts
                .iter()
                .map(|&(q, n)| per_copy(n, q))
                .max()
                .unwrap_or(0);
        }
        chain = chain.max(per_round * u64::from(path.rounds));
    }
    let load_bound = (0..problem.num_planes)
        .map(|q| per_copy(load[q as usize], q))
        .max()
        .unwrap_or(0);
    u32::try_from(load_bound.max(chain)).unwrap_or(u32::MAX)
}

/// Every job of every round is placed, and (phase order) each unit of a path starts after the
/// unit before it has ended; `at` is the slot of each job by index.
fn check_rounds(
    problem: &Problem,
    prep: &Prepared<'_>,
    at: &[u32],
    report: &mut Report<ScheduleViolation>,
) {
    let mut previous_end: Option<u32> = None;
    let mut current_path = u32::MAX;
    crate::decode::for_each_unit(prep, |p, round, unit, jobs| {
        if p != current_path {
            (current_path, previous_end) = (p, None);
        }
        let phase = (unit - prep.unit_offset[p as usize] as usize) as u32 % prep.phases(p as usize);
        let round_base = prep.job_offset[p as usize] as usize
            + round as usize * problem.paths[p as usize].planes.len();
        let (mut start, mut end) = (None::<u32>, None::<u32>);
        for j in jobs {
            let slot = at[j];
            if slot == NONE {
                report.push(ScheduleViolation::MissingJob {
                    job: Job {
                        path: p,
                        round,
                        point: prep.point_of_rank(p as usize, j - round_base),
                    },
                });
            } else {
                start = Some(start.map_or(slot, |s| s.min(slot)));
                end = Some(end.map_or(slot, |e| e.max(slot)));
            }
        }
        if let (Some(start), Some(previous_end)) = (start, previous_end) {
            if start <= previous_end {
                report.push(ScheduleViolation::Dependency {
                    path: p,
                    round,
                    phase,
                    start,
                    previous_end,
                });
            }
        }
        previous_end = end.or(previous_end);
    });
}

/// Job index of a job of the problem, `None` if out of range.
fn job_index(prep: &Prepared<'_>, job: Job) -> Option<usize> {
    let path = prep.problem.paths.get(job.path as usize)?;
    if job.round >= path.rounds || job.point as usize >= path.planes.len() {
        return None;
    }
    Some(
        prep.job_offset[job.path as usize] as usize
            + job.round as usize * path.planes.len()
            + prep.rank_of_point(job.path as usize, job.point),
    )
}

/// Unit index (phase of a round) of a job of the problem, `None` if out of range.
fn unit_index(prep: &Prepared<'_>, job: Job) -> Option<usize> {
    job_index(prep, job)?;
    let p = job.path as usize;
    let phases = prep.phases(p);
    Some(prep.unit_offset[p] as usize + (job.round * phases + job.point % phases) as usize)
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}
