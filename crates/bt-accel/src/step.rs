//! One time step on the host: candidates, the accelerator's input, the fixed-point model run
//! that sizes each path's round budget, the PE schedule and the comparison with f64.

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
    /// The model's results (what the accelerator reads back, bit for bit).
    pub results: Vec<PathResult>,
    /// Paths started from the previous step's converged points.
    pub warm_started: usize,
    /// The PE schedule of this step.
    pub plan: Plan,
    /// Fixed point vs the f64 image method.
    pub fixed: FixedDeviation,
    /// Host work, seconds: candidates, accelerator input and the PE schedule.
    pub host_time_s: f64,
    /// Seconds of the model run that sizes each path's round budget.
    pub budget_model_time_s: f64,
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
    let warm_started = match previous {
        Some(p) if options.warm_start => warm_start(&mut step, &p.step, &p.results),
        _ => 0,
    };
    let t1 = Instant::now();
    if step.input.paths.is_empty() {
        return Err(AccelError::NoCandidate {
            step: index,
            max_order: trace.max_order,
        });
    }
    let model = step.input.model().map_err(hardware)?;
    let results = model
        .run(step.input.tx, step.input.rx)
        .map_err(|e| hardware(e.into()))?;
    let problem = step.input.problem_for(&results);
    let latency = step.input.pe_latency();
    let t2 = Instant::now();
    let plan = match previous {
        // Copies sized once, at the first step, within the PE budget; every later step is
        // scheduled onto them, so that one design runs the whole stream.
        Some(p) if fixed_copies(&options.plan) => {
            bt_hls::plan_on(&problem, &options.plan, &p.plan.schedule.copies(), latency)
        }
        _ => bt_hls::plan(&problem, &options.plan, latency),
    }
    .map_err(hardware)?;
    let t3 = Instant::now();
    let fixed = fixed_deviation(scene, &step, &results, trace.max_order)
        .map_err(|e| candidates_failed(e.into()))?;
    Ok(PlannedStep {
        index,
        step,
        results,
        warm_started,
        plan,
        fixed,
        host_time_s: ((t1 - t0) + (t3 - t2)).as_secs_f64(),
        budget_model_time_s: (t2 - t1).as_secs_f64(),
    })
}

impl PlannedStep {
    /// The work the host loads over the bus for this step.
    pub fn work(&self) -> bt_hls::StepWork {
        bt_hls::StepWork {
            input: self.step.input.clone(),
            schedule: self.plan.schedule.clone(),
        }
    }
}
