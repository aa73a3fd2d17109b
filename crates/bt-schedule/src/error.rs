//! The crate's one error type and the items it reports.

use std::fmt;

use crate::Job;

/// How many items a [`Report`] keeps verbatim; the rest are only counted.
pub const REPORT_LIMIT: usize = 32;

/// A list of problems found in one pass: the first [`REPORT_LIMIT`] kept, all counted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Report<T> {
    /// The first items found, in discovery order.
    pub items: Vec<T>,
    /// How many were found in total (`>= items.len()`, and `>= 1` inside an error).
    pub count: usize,
}

impl<T> Report<T> {
    pub(crate) fn new() -> Self {
        Report {
            items: Vec::new(),
            count: 0,
        }
    }

    pub(crate) fn push(&mut self, item: T) {
        if self.items.len() < REPORT_LIMIT {
            self.items.push(item);
        }
        self.count += 1;
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.count == 0
    }
}

impl<T: fmt::Display> fmt::Display for Report<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} found", self.count)?;
        for (i, item) in self.items.iter().enumerate() {
            write!(f, "{}{item}", if i == 0 { ": " } else { "; " })?;
        }
        if self.count > self.items.len() {
            write!(f, "; and {} more", self.count - self.items.len())?;
        }
        Ok(())
    }
}

/// One defect of a [`crate::Problem`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProblemIssue {
    /// A path with no interaction point.
    #[error("path {path} has no point")]
    EmptyPath {
        /// Offending path.
        path: u32,
    },
    /// A path that needs no IPC round (it would have no job at all).
    #[error("path {path} has zero rounds")]
    ZeroRounds {
        /// Offending path.
        path: u32,
    },
    /// A path whose rounds have zero phases.
    #[error("path {path}: zero phases per round")]
    ZeroPhases {
        /// Offending path.
        path: u32,
    },
    /// A point on a plane index `>= num_planes`.
    #[error("path {path} point {point} lies on plane {plane}, but there are {num_planes} planes")]
    PlaneOutOfRange {
        /// Offending path.
        path: u32,
        /// Point index in the path.
        point: u32,
        /// The out-of-range plane.
        plane: u32,
        /// `Problem::num_planes`.
        num_planes: u32,
    },
    /// Two consecutive points on the same plane (a plane cannot reflect onto itself).
    /// Non-consecutive repeats (A-B-A) are legal.
    #[error("path {path} points {} and {point} both lie on plane {plane}", point - 1)]
    RepeatedPlane {
        /// Offending path.
        path: u32,
        /// Index of the second of the two points.
        point: u32,
        /// The repeated plane.
        plane: u32,
    },
    /// More paths than a `u32` path id can name.
    #[error("{count} paths exceed the u32 path id")]
    TooManyPaths {
        /// Number of paths.
        count: u64,
    },
    /// More jobs in total than the scheduler indexes (`u32::MAX - 1`).
    #[error("{count} jobs exceed the scheduler's limit of {limit}")]
    TooManyJobs {
        /// Total jobs (sum of points x rounds).
        count: u64,
        /// The limit.
        limit: u64,
    },
}

/// One reason a [`crate::Schedule`] is illegal for a problem.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScheduleViolation {
    /// The same PE instance listed twice.
    #[error("pe instance (plane {plane}, copy {copy}) is listed twice")]
    DuplicateInstance {
        /// Plane of the instance.
        plane: u32,
        /// Copy number of the instance.
        copy: u32,
    },
    /// A PE instance of a plane that does not exist.
    #[error("pe instance {instance} is on plane {plane}, but there are {num_planes} planes")]
    InstancePlaneOutOfRange {
        /// Column index.
        instance: u32,
        /// Its plane.
        plane: u32,
        /// `Problem::num_planes`.
        num_planes: u32,
    },
    /// A slot row whose length differs from the number of instances.
    #[error("slot {slot} has {len} entries for {expected} pe instances")]
    RowLength {
        /// Slot index.
        slot: u32,
        /// Entries in the row.
        len: u32,
        /// `instances.len()`.
        expected: u32,
    },
    /// A job that is not part of the problem (path, round or point out of range).
    #[error("slot {slot} instance {instance} holds unknown job {job:?}")]
    UnknownJob {
        /// Slot index.
        slot: u32,
        /// Column index.
        instance: u32,
        /// The job.
        job: Job,
    },
    /// A job on a PE of another plane.
    #[error("job {job:?} needs plane {expected} but runs on instance {instance} of plane {plane}")]
    WrongPlane {
        /// The job.
        job: Job,
        /// Column index.
        instance: u32,
        /// Plane of that instance.
        plane: u32,
        /// Plane of the job's point.
        expected: u32,
    },
    /// A job placed more than once.
    #[error("job {job:?} placed twice, in slots {first} and {slot}")]
    DuplicateJob {
        /// The job.
        job: Job,
        /// Slot of its first occurrence.
        first: u32,
        /// Slot of the repeated occurrence.
        slot: u32,
    },
    /// A job of the problem that the schedule lacks.
    #[error("job {job:?} is missing")]
    MissingJob {
        /// The job.
        job: Job,
    },
    /// Phase order broken: phase `phase` of round `round` starts no later than the phase
    /// before it (of this round, or the last one of the previous round) ends.
    #[error(
        "path {path} round {round} phase {phase} starts in slot {start}, not after the phase before it ending in slot {previous_end}"
    )]
    Dependency {
        /// Path.
        path: u32,
        /// Round of the phase that starts too early.
        round: u32,
        /// Phase (0 for Jacobi paths) that starts too early.
        phase: u32,
        /// Earliest slot of that phase.
        start: u32,
        /// Latest slot of the phase before it.
        previous_end: u32,
    },
}

/// Everything that can go wrong in this crate.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScheduleError {
    /// The problem is malformed.
    #[error("invalid scheduling problem: {0}")]
    InvalidProblem(Report<ProblemIssue>),
    /// The budget cannot give every used plane its original PE.
    #[error("budget of {max_instances} pe instances is below the {needed} planes the paths use")]
    BudgetTooSmall {
        /// `Budget::max_instances`.
        max_instances: u32,
        /// Distinct planes used by the problem.
        needed: u32,
    },
    /// A GA parameter is out of range.
    #[error("ga parameter `{name}` {reason}")]
    InvalidGaParams {
        /// Field of [`crate::GaParams`].
        name: &'static str,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A generic platform of no PE was asked for.
    #[error("a generic platform needs at least one pe")]
    NoGenericPe,
    /// The schedule breaks the rules (see [`crate::Schedule::check`]).
    #[error("illegal schedule: {0}")]
    IllegalSchedule(Report<ScheduleViolation>),
}
