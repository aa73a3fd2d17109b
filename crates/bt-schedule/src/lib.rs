//! PE scheduling for the IPC accelerator (paper section V, eq. 14, Fig. 12).
//!
//! CONTRACT (written before the implementation; `bt-hls` codes against these types):
//! A *job* is one evaluation of Algorithm 2 for one point of one candidate path in one IPC
//! round. It runs on a processing element (PE) instance of the plane that point lies on and
//! takes exactly one *slot*. A path's round runs in [`PathJob::phases`] *phases* (1: Jacobi,
//! 2: red-black), point `i` in phase `i % phases`: every job of a phase must be in a slot
//! strictly after every job of the phase before it (the previous phase of the same round, or
//! the last phase of the previous round) of the same path.
//!
//! # Entry points
//! - [`Problem::validate`] checks the input at the boundary (every problem reported at once).
//! - [`schedule_list`] is the baseline: paths in index order, every job at its earliest free
//!   slot, no duplicates.
//! - [`schedule_ga`] is the paper's three-pass procedure: (1) a genetic algorithm over path
//!   priorities, (2) duplication of the busiest PEs within a [`Budget`], (3) ASAP fill.
//! - [`round_template`] is what dynamic dispatch loads: one round of every path as groups
//!   (a phase's jobs on distinct PEs), built without knowing any path's rounds.
//! - [`Schedule::check`] proves a schedule legal; [`Schedule::stats`] measures it (makespan,
//!   latency factor of eq. 14, utilisation).
//!
//! The latency factor of eq. 14 is summed over paths **and rounds** here (the paper sums over
//! paths): see [`ScheduleStats::latency_factor`].
//!
//! Time is counted in *slots* (one PE evaluation each); a schedule's makespan is its number of
//! slots. Everything here is deterministic: the GA draws from a ChaCha RNG seeded by
//! [`GaParams::seed`], and parallel fitness evaluation preserves order.
#![warn(missing_docs)]

mod asap;
mod check;
mod decode;
mod error;
mod ga;
mod list;
mod occupancy;
mod problem;
pub mod synthetic;
mod template;

pub use check::ScheduleStats;
pub use error::{ProblemIssue, REPORT_LIMIT, Report, ScheduleError, ScheduleViolation};
pub use ga::{GaParams, schedule_ga};
pub use list::{schedule_list, schedule_list_duplicated, schedule_list_on, size_copies};
pub use template::{dispatch_copies, generic_round_template, round_template};

/// One candidate path as the scheduler sees it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PathJob {
    /// Plane index of each interaction point, TX side first (length = reflection order).
    pub planes: Vec<u32>,
    /// IPC rounds this path needs (from the fixed-point model; early stopping frees the PEs).
    pub rounds: u32,
    /// Phases of a round (≥ 1): point `i` is updated in phase `i % phases`, after the phase
    /// before it. 1 = Jacobi (every point from the previous round), 2 = red-black (even points,
    /// then odd points from them: `bt_fixed::RoundOrder`). More phases than points count as
    /// one per point.
    #[serde(default = "one_phase")]
    pub phases: u32,
}

impl PathJob {
    /// A path of `planes` running `rounds` Jacobi rounds (one phase).
    pub fn jacobi(planes: Vec<u32>, rounds: u32) -> PathJob {
        PathJob {
            planes,
            rounds,
            phases: 1,
        }
    }
}

fn one_phase() -> u32 {
    1
}

/// The whole scheduling problem of one time step.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Problem {
    /// Number of planes (PEs before duplication); every `PathJob::planes` entry is below it.
    pub num_planes: u32,
    /// Candidate paths; their index is the path id used in [`Job::path`].
    pub paths: Vec<PathJob>,
}

/// One job placed in the schedule.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct Job {
    /// Index into [`Problem::paths`].
    pub path: u32,
    /// IPC round, 0-based.
    pub round: u32,
    /// Point index within the path, 0-based from the TX side.
    pub point: u32,
}

/// A physical PE: a copy of the PE of one plane.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct PeInstance {
    /// Plane whose PE this is (index below [`Problem::num_planes`]).
    pub plane: u32,
    /// 0 for the original, 1.. for duplicates.
    pub copy: u32,
}

impl PeInstance {
    /// The `plane` of a generic PE: one that takes any plane's job, its plane's coefficients
    /// loaded with the job (`bt-hls`'s generic platform).
    pub const ANY_PLANE: u32 = u32::MAX;

    /// Generic PE number `copy` ([`PeInstance::ANY_PLANE`]).
    pub fn generic(copy: u32) -> PeInstance {
        PeInstance {
            plane: Self::ANY_PLANE,
            copy,
        }
    }

    /// Whether this is a generic PE.
    pub fn is_generic(self) -> bool {
        self.plane == Self::ANY_PLANE
    }

    /// Whether this PE can run a job on `plane`.
    pub fn takes(self, plane: u32) -> bool {
        self.is_generic() || self.plane == plane
    }
}

/// A complete schedule: `slots[t][i]` is the job PE instance `instances[i]` runs in slot `t`.
///
/// Serialised as is (`schedule.json`): `instances` as `{plane, copy}` objects and `slots` as
/// one array per slot holding `null` or `{path, round, point}` per instance. Schedules built by
/// this crate list `instances` sorted by `(plane, copy)`, give only used planes a PE, and have
/// no trailing empty slot.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Schedule {
    /// The PE instances (columns of `slots`).
    pub instances: Vec<PeInstance>,
    /// One row per slot, `instances.len()` entries per row; `None` = the PE idles.
    pub slots: Vec<Vec<Option<Job>>>,
}

impl Schedule {
    /// PE copies per plane (index = plane, up to the highest plane with an instance; generic
    /// PEs are no plane's copies).
    pub fn copies(&self) -> Vec<u32> {
        let mut copies = Vec::new();
        for inst in self.instances.iter().filter(|i| !i.is_generic()) {
            let p = inst.plane as usize;
            if copies.len() <= p {
                copies.resize(p + 1, 0);
            }
            copies[p] = copies[p].max(inst.copy + 1);
        }
        copies
    }
}

/// How many PE instances a schedule may use in total (originals plus duplicates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Budget {
    /// Total PE instances allowed; must be at least the number of distinct planes used by the
    /// problem's paths (one original PE each).
    pub max_instances: u32,
}

impl Budget {
    /// The smallest budget for `problem`: one PE per plane used, no duplicate.
    pub fn originals_only(problem: &Problem) -> Budget {
        let used = problem::used_planes(problem);
        Budget {
            max_instances: u32::try_from(used.len()).unwrap_or(u32::MAX),
        }
    }
}

impl Schedule {
    /// Makespan in slots: index of the last slot with a job, plus one (0 for no job).
    pub fn makespan(&self) -> u32 {
        let last = self
            .slots
            .iter()
            .rposition(|row| row.iter().any(Option::is_some));
        last.map_or(0, |t| u32::try_from(t + 1).unwrap_or(u32::MAX))
    }

    /// Number of jobs placed (non-empty cells).
    pub fn job_count(&self) -> u64 {
        self.slots
            .iter()
            .map(|row| row.iter().filter(|c| c.is_some()).count() as u64)
            .sum()
    }
}

#[cfg(test)]
mod tests;
