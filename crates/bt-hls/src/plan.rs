//! Planning one accelerator run without writing RTL: the PE schedule of a scheduling problem
//! and the exact cycle count it implies (`hls gen --plan-only`, one time step of a study).

use bt_schedule::{Budget, GaParams, Problem, Schedule, ScheduleStats};

use crate::HlsError;

/// Which scheduler places the jobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScheduleKind {
    /// The paper's three passes: GA, PE duplication, ASAP fill ([`bt_schedule::schedule_ga`]).
    Ga,
    /// The list scheduler: one PE per plane, paths with the most jobs first
    /// ([`bt_schedule::schedule_list_on`]) or in index order ([`bt_schedule::schedule_list`],
    /// the baseline [`Plan::list_makespan`]), whichever is shorter; or, with a
    /// [`PlanOptions::pe_budget`] above the planes used, the extra PEs as copies of the busiest
    /// planes ([`bt_schedule::schedule_list_duplicated`]).
    List,
}

impl ScheduleKind {
    /// Name in outputs (`ga`, `list`).
    pub fn name(self) -> &'static str {
        match self {
            ScheduleKind::Ga => "ga",
            ScheduleKind::List => "list",
        }
    }
}

/// How to schedule.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanOptions {
    /// Scheduler.
    pub schedule: ScheduleKind,
    /// Total PE instances allowed; `None`: the planes used plus 25 % for the GA's duplicates,
    /// none for the list scheduler. Never below the planes used (one original PE each).
    pub pe_budget: Option<u32>,
    /// GA parameters (seed included); ignored by the list scheduler.
    pub ga: GaParams,
    /// Dynamic dispatch on this many generic PEs (any PE takes any plane's job,
    /// [`bt_schedule::generic_round_template`]) instead of PEs per plane; `pe_budget` is then
    /// not read. `None`: PEs per plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generic_pes: Option<u32>,
}

/// A scheduled run: the schedule, its statistics and its cycle count.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The schedule (legal for the problem: checked).
    pub schedule: Schedule,
    /// Its statistics.
    pub stats: ScheduleStats,
    /// Makespan of the list schedule with one PE per plane and the paths in index order, slots
    /// (the baseline).
    pub list_makespan: u32,
    /// The PE budget applied.
    pub pe_budget: u32,
    /// Path points (the point memory initialised before the first slot).
    pub points: u64,
    /// Mean cycles of a schedule slot ([`slot_cycles`]): `predicted_cycles / makespan`.
    pub mean_cycles_per_slot: f64,
    /// Cycles from start to done ([`run_cycles`], or with dynamic dispatch
    /// [`crate::dispatch::predict`] once the rounds are known): what `CYCLES` will read.
    pub predicted_cycles: u64,
    /// Slots, jobs and dispatch waits of a dynamically dispatched run ([`plan_dispatch`] and
    /// [`predict_dispatch`]); zero for a static schedule.
    pub dispatch: crate::dispatch::DispatchRun,
}

/// Cycles of one schedule slot holding `jobs` jobs: load operands (jobs + 2: the schedule
/// memory's registered read adds one), run the PEs (`latency`, [`crate::pe_latency`]), write
/// back (jobs + 2).
/// The slot's jobs are packed in the schedule memory, so idle PEs cost nothing; an empty slot
/// counts as one job (its one entry only marks the slot's end).
pub fn slot_cycles(jobs: u32, latency: u32) -> u64 {
    2 * (u64::from(jobs.max(1)) + 2) + u64::from(latency)
}

/// Schedule-memory entries of `schedule`: its jobs packed slot after slot up to the makespan,
/// an empty slot as one entry (which only marks the slot's end).
pub fn schedule_entries(schedule: &Schedule) -> u32 {
    schedule
        .slots
        .iter()
        .take(schedule.makespan() as usize)
        .map(|row| (row.iter().flatten().count() as u32).max(1))
        .sum()
}

/// Cycles of one accelerator run of `schedule` (the `CYCLES` register): [`slot_cycles`] of
/// every slot up to the makespan (the host writes the start points before the start command).
/// Independent of how many PEs the platform has; `latency` is the design's PE latency
/// ([`crate::pe_latency`]).
pub fn run_cycles(schedule: &Schedule, latency: u32) -> u64 {
    schedule
        .slots
        .iter()
        .take(schedule.makespan() as usize)
        .map(|row| slot_cycles(row.iter().flatten().count() as u32, latency))
        .sum()
}

/// Schedule `problem` (from [`crate::HlsInput::problem`] or
/// [`crate::HlsInput::problem_for`]) and predict the run's cycles on a design whose PE takes
/// `latency` cycles ([`crate::HlsInput::pe_latency`]). Deterministic for the options (the GA
/// is seeded).
pub fn plan(problem: &Problem, options: &PlanOptions, latency: u32) -> Result<Plan, HlsError> {
    plan_with(problem, options, None, latency)
}

/// [`plan`] with the list scheduler onto a platform sized beforehand: `copies[p]` PEs of
/// plane `p` ([`bt_schedule::schedule_list_on`]), e.g. the copies the first time step chose
/// within the PE budget, so that every step runs on the same design.
pub fn plan_on(
    problem: &Problem,
    options: &PlanOptions,
    copies: &[u32],
    latency: u32,
) -> Result<Plan, HlsError> {
    plan_with(problem, options, Some(copies), latency)
}

fn plan_with(
    problem: &Problem,
    options: &PlanOptions,
    copies: Option<&[u32]>,
    latency: u32,
) -> Result<Plan, HlsError> {
    let planes_used = {
        let mut used: Vec<u32> = problem
            .paths
            .iter()
            .flat_map(|p| p.planes.iter().copied())
            .collect();
        used.sort_unstable();
        used.dedup();
        used.len() as u32
    };
    let budget = Budget {
        max_instances: options
            .pe_budget
            .unwrap_or(planes_used + planes_used / 4)
            .max(planes_used),
    };
    let list = bt_schedule::schedule_list(
        problem,
        &Budget {
            max_instances: planes_used,
        },
    )?;
    let list_makespan = list.stats(problem).makespan;
    let schedule = match (copies, options.schedule, options.pe_budget) {
        // A platform sized beforehand: the list scheduler onto its copies.
        (Some(copies), _, _) => bt_schedule::schedule_list_on(problem, copies)?,
        // Extra PEs asked for: copies of the busiest planes (offline sizing of the platform).
        (None, ScheduleKind::List, Some(b)) if b > planes_used => {
            bt_schedule::schedule_list_duplicated(problem, &budget)?
        }
        // Most jobs first, the long paths' chains starting at once (living room step 0: 1,115
        // -> 1,013 slots, the busiest plane's load being 1,008), unless the index order is
        // shorter: the two list schedules cost microseconds.
        (None, ScheduleKind::List, _) => {
            let longest_first = bt_schedule::schedule_list_on(problem, &[])?;
            if longest_first.makespan() <= list.makespan() {
                longest_first
            } else {
                list
            }
        }
        (None, ScheduleKind::Ga, _) => bt_schedule::schedule_ga(problem, &budget, &options.ga)?,
    };
    schedule.check(problem)?;
    let stats = schedule.stats(problem);
    let pe_budget = budget.max_instances.max(schedule.instances.len() as u32);
    let points: u64 = problem.paths.iter().map(|p| p.planes.len() as u64).sum();
    Ok(Plan {
        dispatch: crate::dispatch::DispatchRun::default(),
        predicted_cycles: run_cycles(&schedule, latency),
        mean_cycles_per_slot: run_cycles(&schedule, latency) as f64
            / f64::from(stats.makespan.max(1)),
        schedule,
        stats,
        list_makespan,
        pe_budget,
        points,
    })
}

/// Plan a step for dynamic dispatch without knowing any path's rounds (no model run): the
/// round template of `problem` ([`bt_schedule::round_template`]; its `rounds` are not read)
/// on `copies[p]` PEs of plane `p` (the platform's), or with [`PlanOptions::pe_budget`] on the
/// copies [`bt_schedule::size_copies`] picks by one round's load per plane, or one PE per
/// plane; with [`PlanOptions::generic_pes`], on that many generic PEs. `predicted_cycles` stays 0 until [`predict_dispatch`].
pub fn plan_dispatch(
    problem: &Problem,
    options: &PlanOptions,
    copies: Option<&[u32]>,
) -> Result<Plan, HlsError> {
    let one = problem.one_round();
    let schedule = match options.generic_pes {
        Some(g) => bt_schedule::generic_round_template(&one, g)?,
        None => {
            let copies = match (copies, options.pe_budget) {
                (Some(c), _) => c.to_vec(),
                (None, Some(b)) => {
                    bt_schedule::dispatch_copies(&one, &Budget { max_instances: b })?
                }
                (None, None) => Vec::new(),
            };
            bt_schedule::round_template(&one, &copies)?
        }
    };
    schedule.check(&one)?;
    let stats = schedule.stats(&one);
    let points: u64 = problem.paths.iter().map(|p| p.planes.len() as u64).sum();
    Ok(Plan {
        list_makespan: stats.makespan,
        pe_budget: options.pe_budget.unwrap_or(0).max(stats.instances),
        stats,
        schedule,
        points,
        mean_cycles_per_slot: 0.0,
        predicted_cycles: 0,
        dispatch: crate::dispatch::DispatchRun::default(),
    })
}

/// The cycles of a [`plan_dispatch`] plan once path `p`'s rounds are known (`rounds[p]`,
/// read back from the accelerator, or from the model run after the step for verification)
/// on a platform of `columns` PEs whose PE takes `latency` cycles: sets `predicted_cycles`,
/// `mean_cycles_per_slot` and `dispatch`.
pub fn predict_dispatch(
    plan: &mut Plan,
    rounds: &[u32],
    columns: usize,
    latency: u32,
) -> Result<(), HlsError> {
    let groups = crate::dispatch::groups(&plan.schedule, rounds.len())?;
    let run = crate::dispatch::predict(&groups, columns, rounds, latency);
    plan.predicted_cycles = run.cycles;
    plan.mean_cycles_per_slot = run.cycles as f64 / run.slots.max(1) as f64;
    plan.dispatch = run;
    Ok(())
}
