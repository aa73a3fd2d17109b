//! One time step on the host: candidates, the accelerator's input and the round template of
//! dynamic dispatch (no model run: the accelerator decides each path's rounds itself); then,
//! for verification only, the fixed-point model run that stands for the accelerator's
//! read-back (expected words, the run's cycles) and the comparison with f64.

use std::time::Instant;

use bt_hls::{HlsError, PathResult, Plan, PlanOptions};
use bt_scene::{Scene, SurfaceId};
use bt_solve::pipeline::{TraceError, TraceOptions};

use crate::bridge::{StepInput, step_input, warm_start};
use crate::deviation::{FixedDeviation, fixed_deviation};

/// Why a step could not be planned.
#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    /// Candidate generation failed (budget, beam tree, terminals).
    #[error("step {step}: {source}")]
    Candidates {
        /// Time step, from 0.
        step: usize,
        /// The pipeline's error.
        source: TraceError,
    },
    /// No candidate over the platform's planes: nothing for the accelerator.
    #[error("step {step}: no candidate reflection path over static planes up to order {max_order}")]
    NoCandidate {
        /// Time step, from 0.
        step: usize,
        /// The order asked for.
        max_order: usize,
    },
    /// Diffraction was asked for: the PEs solve reflections only.
    #[error(
        "the accelerator traces specular paths only (its PEs solve reflections, not diffractions); \
         trace diffracted paths on the host with `beamtrace trace --diffraction`"
    )]
    Diffraction,
    /// The model or the scheduler refused the work.
    #[error("step {step}: {source}")]
    Hardware {
        /// Time step, from 0.
        step: usize,
        /// The generator's error.
        source: HlsError,
    },
}

/// How each step is planned.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOptions {
    /// Candidate generation (order, generator, budget); `parallel` is ignored (the host's time
    /// is measured single-threaded).
    pub trace: TraceOptions,
    /// Convergence threshold on a round's L∞ displacement, 1/256 mm.
    pub threshold_lsb: u32,
    /// Round cap of the fixed-point IPC.
    pub max_rounds: u32,
    /// Scheduler.
    pub plan: PlanOptions,
    /// Start paths the previous step converged on from its points ([`warm_start`]).
    pub warm_start: bool,
    /// Update order of the accelerator's rounds (red-black: about half Jacobi's rounds).
    pub round_order: bt_fixed::RoundOrder,
}

/// One step planned on the host.
#[derive(Debug, Clone)]
pub struct PlannedStep {
    /// Time step, from 0.
    pub index: usize,
    /// The accelerator's input and the host's share of the candidates.
    pub step: StepInput,
    /// The model's results (what the accelerator reads back, bit for bit), computed after the
    /// plan for verification: nothing the host loads depends on them.
    pub results: Vec<PathResult>,
    /// Paths started from the previous step's converged points.
    pub warm_started: usize,
    /// The round template of this step, and the cycles its dispatched run takes (from
    /// `results`).
    pub plan: Plan,
    /// Fixed point vs the f64 image method.
    pub fixed: FixedDeviation,
    /// Host work, seconds: candidates, accelerator input and the round template.
    pub host_time_s: f64,
    /// Runs of the bit-exact model whose results feed the schedule or the bus program: 0 by
    /// default (the template needs no round count; the model runs after, for verification);
    /// 1 with [`StepOptions::warm_start`] from step 1 on, where the previous step's model run
    /// stands in for the accelerator's read-back of its points.
    pub host_model_runs: u32,
    /// Seconds of a model run that sized round budgets: always 0 since dynamic dispatch
    /// (kept for callers that add it to the host's time).
    pub budget_model_time_s: f64,
    /// Seconds of the verification run of the model after the plan (`results`): not host
    /// work of a deployed accelerator, which reads its results back.
    pub verify_model_time_s: f64,
}

/// Whether the PE copies are sized once for all steps: the list scheduler with a PE budget
/// (the GA keeps its own duplication per step).
fn fixed_copies(plan: &PlanOptions) -> bool {
    plan.schedule == bt_hls::ScheduleKind::List && plan.pe_budget.is_some()
}

/// Plan step `index` of a scene on a platform whose PEs are `planes`; `previous` is the step
/// before (for the warm start and, with a PE budget, the platform's PE copies).
pub fn plan_step(
    scene: &Scene,
    planes: &[SurfaceId],
    index: usize,
    options: &StepOptions,
    previous: Option<&PlannedStep>,
) -> Result<PlannedStep, AccelError> {
    if options.trace.diffraction.enabled().is_some() {
        return Err(AccelError::Diffraction);
    }
    let hardware = |source| AccelError::Hardware {
        step: index,
        source,
    };
    let t0 = Instant::now();
    let trace = TraceOptions {
        parallel: false,
        ..options.trace
    };
    let candidates_failed = |source| AccelError::Candidates {
        step: index,
        source,
    };
    let candidates = bt_solve::pipeline::candidates(scene, &trace).map_err(candidates_failed)?;
    let mut step = step_input(
        scene,
        planes,
        &candidates,
        options.threshold_lsb,
        options.max_rounds,
    )
    .map_err(|e| candidates_failed(e.into()))?;
    step.input.round_order = options.round_order;
    // A warm start feeds the previous step's results into this step's start points: on the
    // accelerator those are its read-back, here the model's run stands in for it.
    let (warm_started, host_model_runs) = match previous {
        Some(p) if options.warm_start => (warm_start(&mut step, &p.step, &p.results), 1),
        _ => (0, 0),
    };
    if step.input.paths.is_empty() {
        return Err(AccelError::NoCandidate {
            step: index,
            max_order: trace.max_order,
        });
    }
    let problem = step.input.one_round_problem();
    let copies = match previous {
        // Copies sized once, at the first step, within the PE budget; every later step runs
        // on them, so that one design runs the whole stream.
        Some(p) if fixed_copies(&options.plan) => Some(p.plan.schedule.copies()),
        _ => None,
    };
    let mut plan =
        bt_hls::plan_dispatch(&problem, &options.plan, copies.as_deref()).map_err(hardware)?;
    let t2 = Instant::now();
    // Verification only, after the plan: the model stands for the accelerator's read-back.
    let model = step.input.model().map_err(hardware)?;
    let results = model
        .run(step.input.tx, step.input.rx)
        .map_err(|e| hardware(e.into()))?;
    let rounds: Vec<u32> = results.iter().map(|r| r.rounds).collect();
    // The platform fitted to this step alone ([`bt_hls::Platform::fitting`]): a PE per
    // instance of the schedule; [`PlannedStep::predict_on`] re-predicts on a larger one.
    let columns = plan.schedule.instances.len();
    bt_hls::predict_dispatch(&mut plan, &rounds, columns, step.input.pe_latency())
        .map_err(hardware)?;
    let t3 = Instant::now();
    let budget = (trace.max_order, trace.max_candidates);
    let fixed = fixed_deviation(scene, (&step, &candidates), &results, budget)
        .map_err(|e| candidates_failed(e.into()))?;
    Ok(PlannedStep {
        index,
        step,
        results,
        warm_started,
        plan,
        fixed,
        host_time_s: (t2 - t0).as_secs_f64(),
        host_model_runs,
        budget_model_time_s: 0.0,
        verify_model_time_s: (t3 - t2).as_secs_f64(),
    })
}

impl PlannedStep {
    /// Predict the step's cycles again on a platform of `columns` PEs (one that runs several
    /// steps may have PEs this step's schedule does not use; the dispatcher stops examining
    /// groups once every PE column of the slot it builds is taken, so the count matters).
    /// Sets `plan.predicted_cycles` and `plan.dispatch`.
    pub fn predict_on(&mut self, columns: usize) -> Result<(), AccelError> {
        let rounds: Vec<u32> = self.results.iter().map(|r| r.rounds).collect();
        bt_hls::predict_dispatch(
            &mut self.plan,
            &rounds,
            columns,
            self.step.input.pe_latency(),
        )
        .map_err(|source| AccelError::Hardware {
            step: self.index,
            source,
        })
    }

    /// The work the host loads over the bus for this step.
    pub fn work(&self) -> bt_hls::StepWork {
        bt_hls::StepWork {
            input: self.step.input.clone(),
            schedule: self.plan.schedule.clone(),
        }
    }
}
