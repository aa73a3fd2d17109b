//! `beamtrace hls`: scene -> fixed-point model -> PE schedule -> Verilog, and `hls sim` /
//! `hls synth` on a generated directory.

use crate::args::{HlsArgs, HlsCommand, HlsGenArgs};
use anyhow::{Context, bail};
use bt_hls::{OutputDir, PlanOptions};
use bt_paths::AllVisible;
use bt_scene::Scene;
use bt_schedule::{GaParams, Problem};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

/// Clock of the paper's platform (Cyclone IV E at 50 MHz), Hz.
pub const CLOCK_HZ: f64 = bt_study::living_room::CLOCK_HZ;

pub fn run(args: &HlsArgs) -> anyhow::Result<ExitCode> {
    match &args.command {
        HlsCommand::Gen(a) => generate(a),
        HlsCommand::Sim { dir, simulator } => simulate(dir, simulator.kind()),
        HlsCommand::Synth { dir } => {
            let r = bt_hls::synthesize(dir)
                .with_context(|| format!("synthesising {}", dir.display()))?;
            println!(
                "{}: Yosys synth_intel -family cycloneive (EP4CE115, 114,480 LEs)",
                dir.display()
            );
            println!("  logic cells      {:>10}", r.logic_cells);
            println!("  registers        {:>10}", r.registers);
            println!(
                "  memory bits      {:>10}   ({} M9K blocks)",
                r.memory_bits, r.m9k_blocks
            );
            println!(
                "  share of EP4CE115 {:>9.2} %   (paper, Table III: IPC 4 %-43 % of LEs)",
                r.percent_of_ep4ce115
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// `hls sim DIR`: build the testbench, run every step's bus program with a progress bar,
/// compare with the model.
fn simulate(dir: &Path, simulator: bt_hls::Simulator) -> anyhow::Result<ExitCode> {
    // indicatif draws to stderr and hides itself when stderr is not a terminal.
    let bar = ProgressBar::new_spinner();
    bar.set_message(format!("compiling with {}", simulator.name()));
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut on_progress = |p: bt_hls::SimProgress| match p {
        bt_hls::SimProgress::Compiling => {}
        bt_hls::SimProgress::Runs { done, total } => {
            if bar.length() != Some(total) {
                bar.set_length(total);
                bar.set_style(
                    ProgressStyle::with_template("{bar:40} {pos}/{len} runs {elapsed}")
                        .expect("static template"),
                );
            }
            bar.set_position(done);
        }
    };
    let r = bt_hls::simulate_with(dir, simulator, &mut on_progress)
        .with_context(|| format!("co-simulating {}", dir.display()))?;
    bar.finish_and_clear();
    println!(
        "{}: {} ({} steps, {} runs), {} words compared, {} mismatches; CYCLES of run 0 {} (predicted {}), runs as predicted: {}, testbench cycles {} (predicted {})",
        dir.display(),
        r.simulator.name(),
        r.steps,
        r.vectors,
        r.words_compared,
        r.mismatches,
        r.cycles,
        r.predicted_cycles,
        r.irq_cycles == r.predicted_run_cycles,
        r.tb_cycles,
        r.predicted_tb_cycles
    );
    for m in r.mismatch_details.iter().take(20) {
        println!("  mismatch: {m}");
    }
    Ok(if r.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// What `hls gen` reports for one time step (also `DIR/summary.json`, or
/// `DIR/step-<k>/summary.json` with `--steps`).
#[derive(Debug, Serialize)]
pub struct HlsSummary {
    pub scene: String,
    /// Time step of a dynamic scene (`hls gen --steps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<usize>,
    pub max_order: usize,
    pub planes: usize,
    /// Candidate paths sent to the accelerator.
    pub paths: usize,
    pub points: usize,
    /// Candidates through a moving surface, solved by the host (image method).
    pub host_paths: usize,
    /// Paths started from the points they converged to at the previous step (`--steps`
    /// without `--cold-start`).
    pub warm_started: usize,
    pub schedule: &'static str,
    pub seed: u64,
    pub pe_budget: u32,
    pub stats: bt_schedule::ScheduleStats,
    pub list_makespan: u32,
    /// PE instances of the platform (the one design all steps run on).
    pub platform_instances: u32,
    pub cycles_per_slot: u64,
    pub predicted_cycles: u64,
    pub latency_s_at_50mhz: f64,
    /// Host work per step, seconds: candidates, accelerator input and the PE schedule.
    pub host_time_s: f64,
    /// Seconds the host spends running the fixed-point model to size each path's round
    /// budget (not yet replaced by a fixed budget; see docs/hardware.md).
    pub budget_model_time_s: f64,
    pub fixed_vs_f64: FixedDeviation,
    pub rtl_written: bool,
}

/// Fixed-point model vs the f64 reference (image method over every candidate of the order).
#[derive(Debug, Serialize, Default)]
pub struct FixedDeviation {
    pub valid_paths_compared: usize,
    pub max_point_error_mm: f64,
    pub mean_point_error_mm: f64,
    pub max_angle_error_tx_deg: f64,
    pub max_angle_error_rx_deg: f64,
    /// Valid paths (in f64) the fixed-point model does not converge on.
    pub not_converged: usize,
    /// Exact paths lost: not among the accelerator's candidates (and not the host's), or
    /// rejected by the host check (`bt_study::fpga::host_accepts`).
    pub missed: usize,
    /// Exact paths through a moving surface, solved by the host.
    pub host_solved: usize,
    /// Candidates frozen by early stopping.
    pub left_bounds: usize,
    /// Converged, f64-valid results rejected by the reflection-law check.
    pub reflection_rejected: usize,
    /// Results the host accepts that are no path of the image method (false convergences).
    pub spurious: usize,
}

fn fixed_deviation(
    scene: &Scene,
    step: &bt_study::fpga::StepInput,
    results: &[bt_hls::PathResult],
    max_order: usize,
) -> FixedDeviation {
    let candidates = bt_paths::enumerate(scene, max_order, &AllVisible);
    let reference = bt_solve::trace(scene, &candidates, &bt_solve::Solver::Image, true);
    let mut err = FixedDeviation {
        left_bounds: results.iter().filter(|r| r.left_bounds).count(),
        ..FixedDeviation::default()
    };
    for (seq, r) in step.sequences.iter().zip(results) {
        match bt_study::fpga::host_accepts(scene, seq, r) {
            Ok(_) => {
                if !reference.paths.iter().any(|p| p.surfaces == *seq) {
                    err.spurious += 1;
                }
            }
            Err(bt_study::fpga::HostRejection::ReflectionLaw) => err.reflection_rejected += 1,
            Err(_) => {}
        }
    }
    let mut sum = 0.0;
    let mut count = 0usize;
    // Line of sight (no surface) needs no accelerator: the host adds it.
    for path in reference.paths.iter().filter(|p| !p.surfaces.is_empty()) {
        if step.host_sequences.contains(&path.surfaces) {
            err.host_solved += 1;
            continue;
        }
        let Some(k) = step.sequences.iter().position(|s| *s == path.surfaces) else {
            err.missed += 1;
            continue;
        };
        let r = &results[k];
        if !r.converged {
            err.not_converged += 1;
        }
        if bt_study::fpga::host_accepts(scene, &step.sequences[k], r).is_err() {
            err.missed += 1;
        }
        err.valid_paths_compared += 1;
        for (q, p) in r.points_m.iter().zip(&path.points) {
            let d = (glam::DVec3::from_array(*q) - *p).length() * 1e3;
            err.max_point_error_mm = err.max_point_error_mm.max(d);
            sum += d;
            count += 1;
        }
        let angle = |a: glam::DVec3, b: glam::DVec3| a.angle_between(b).to_degrees();
        let (tx, rx) = (scene.tx(), scene.rx());
        let first = glam::DVec3::from_array(r.points_m[0]);
        let last = glam::DVec3::from_array(*r.points_m.last().expect("order >= 1"));
        err.max_angle_error_tx_deg = err
            .max_angle_error_tx_deg
            .max(angle(first - tx, path.points[0] - tx));
        err.max_angle_error_rx_deg = err.max_angle_error_rx_deg.max(angle(
            last - rx,
            *path.points.last().expect("order >= 1") - rx,
        ));
    }
    err.mean_point_error_mm = if count > 0 { sum / count as f64 } else { 0.0 };
    err
}

fn generate(args: &HlsGenArgs) -> anyhow::Result<ExitCode> {
    if args.max_order == 0 {
        bail!("--max-order must be at least 1 (line of sight needs no accelerator)");
    }
    let scenes: Vec<Scene> = if args.steps {
        crate::steps::load_dynamic(&args.scene)?.scenes().to_vec()
    } else {
        vec![crate::trace::load_scene(&args.scene)?.scene]
    };
    // The output directory is built aside and swapped in: a user's own files in it survive.
    let mut out = OutputDir::begin(&args.output, &crate::inputs(&args.scene))
        .with_context(|| format!("creating {}", args.output.display()))?;
    // The platform: one PE per reflector that no step moves.
    let planes = bt_study::fpga::static_reflectors(&scenes);
    let mut planned: Vec<PlannedStep> = Vec::with_capacity(scenes.len());
    for (k, scene) in scenes.iter().enumerate() {
        let previous = planned.last().map(|p| (&p.step, p.results.as_slice()));
        let step = plan_step(scene, &planes, args, args.steps.then_some(k), previous)?;
        planned.push(step);
    }
    let work: Vec<bt_hls::StepWork> = planned
        .iter()
        .map(|p| bt_hls::StepWork {
            input: p.step.input.clone(),
            schedule: p.plan.schedule.clone(),
        })
        .collect();
    let platform = bt_hls::Platform {
        m9k_budget: args.m9k_budget,
        ..bt_hls::Platform::fitting(&work)?
    };
    let k = platform.instances.len() as u32;
    let rtl_written = !args.plan_only;
    if rtl_written {
        let report = bt_hls::generate_steps_into(&platform, &work, &mut out)?;
        debug_assert_eq!(report.num_instances, k);
    }
    let summaries: Vec<HlsSummary> = scenes
        .iter()
        .zip(planned)
        .map(|(scene, p)| p.summary(scene, args, k, rtl_written))
        .collect();
    if args.steps {
        let doc = report_steps(args, summaries, &mut out)?;
        out.commit()
            .with_context(|| format!("writing {}", args.output.display()))?;
        print_steps(args, &doc);
    } else {
        let s = &summaries[0];
        write(&mut out, "summary.json", &serde_json::to_string_pretty(s)?)?;
        if args.plan_only {
            write(
                &mut out,
                "schedule.json",
                &serde_json::to_string(&work[0].schedule)?,
            )?;
        }
        out.commit()
            .with_context(|| format!("writing {}", args.output.display()))?;
        print_summary(s, &args.output);
    }
    Ok(ExitCode::SUCCESS)
}

/// One step planned on the host: candidates, accelerator input, model results, schedule.
struct PlannedStep {
    step: bt_study::fpga::StepInput,
    /// The model's results (what the accelerator reads back), for the next step's warm start.
    results: Vec<bt_hls::PathResult>,
    /// Paths that start from the previous step's converged points.
    warm_started: usize,
    plan: bt_hls::Plan,
    fixed: FixedDeviation,
    host_time_s: f64,
    budget_model_time_s: f64,
    index: Option<usize>,
}

impl PlannedStep {
    fn summary(self, scene: &Scene, args: &HlsGenArgs, k: u32, rtl_written: bool) -> HlsSummary {
        let cycles = bt_hls::run_cycles(k, self.plan.stats.makespan);
        HlsSummary {
            scene: scene.name().to_string(),
            step: self.index,
            max_order: args.max_order,
            planes: self.step.input.planes.len(),
            paths: self.step.input.paths.len(),
            points: self.plan.points as usize,
            host_paths: self.step.host_sequences.len(),
            warm_started: self.warm_started,
            schedule: args.schedule.kind().name(),
            seed: args.seed,
            pe_budget: self.plan.pe_budget,
            list_makespan: self.plan.list_makespan,
            stats: self.plan.stats,
            platform_instances: k,
            cycles_per_slot: bt_hls::cycles_per_slot(k),
            predicted_cycles: cycles,
            latency_s_at_50mhz: cycles as f64 / CLOCK_HZ,
            host_time_s: self.host_time_s,
            budget_model_time_s: self.budget_model_time_s,
            fixed_vs_f64: self.fixed,
            rtl_written,
        }
    }
}

fn plan_step(
    scene: &Scene,
    planes: &[bt_scene::SurfaceId],
    args: &HlsGenArgs,
    index: Option<usize>,
    previous: Option<(&bt_study::fpga::StepInput, &[bt_hls::PathResult])>,
) -> anyhow::Result<PlannedStep> {
    let t0 = Instant::now();
    let options = bt_solve::pipeline::TraceOptions {
        candidates: args.candidates.mode(),
        parallel: false,
        ..bt_solve::pipeline::TraceOptions::new(args.max_order)
    };
    let candidates = bt_solve::pipeline::candidates(scene, &options)?;
    let mut step = bt_study::fpga::step_input(
        scene,
        planes,
        &candidates,
        args.threshold_lsb,
        args.max_rounds,
    );
    let warm_started = match previous {
        Some((prev, results)) if !args.cold_start => {
            bt_study::fpga::warm_start(&mut step, prev, results)
        }
        _ => 0,
    };
    let t1 = Instant::now();
    if step.input.paths.is_empty() {
        let at = index.map(|k| format!(" step {k}")).unwrap_or_default();
        bail!(
            "{}{at}: no candidate reflection path over static planes up to order {}",
            args.scene.scene,
            args.max_order
        );
    }
    let model = step.input.model()?;
    let results = model.run(step.input.tx, step.input.rx)?;
    let problem: Problem = step.input.problem_for(&results);
    let t2 = Instant::now();
    let bar = crate::progress::spinner(&format!("scheduling {} paths", step.input.paths.len()));
    let plan = bt_hls::plan(
        &problem,
        &PlanOptions {
            schedule: args.schedule.kind(),
            pe_budget: args.pe_budget,
            ga: GaParams {
                seed: args.seed,
                ..GaParams::default()
            },
        },
    )?;
    bar.finish_and_clear();
    let t3 = Instant::now();
    let fixed = fixed_deviation(scene, &step, &results, args.max_order);
    Ok(PlannedStep {
        step,
        results,
        warm_started,
        plan,
        fixed,
        host_time_s: ((t1 - t0) + (t3 - t2)).as_secs_f64(),
        budget_model_time_s: (t2 - t1).as_secs_f64(),
        index,
    })
}

/// `hls gen --steps`: the per-step table, `DIR/steps.json` and `DIR/step-<k>/` (schedule and
/// summary of each step; the one design, if written, is in DIR).
fn report_steps(
    args: &HlsGenArgs,
    summaries: Vec<HlsSummary>,
    out: &mut OutputDir,
) -> anyhow::Result<StepsSummary> {
    println!(
        "{:>4} {:>6} {:>5} {:>7} {:>9} {:>12} {:>10} {:>10} {:>7} {:>9}",
        "step",
        "paths",
        "host",
        "points",
        "makespan",
        "cycles",
        "ms@50MHz",
        "host ms",
        "missed",
        "spurious"
    );
    for s in &summaries {
        println!(
            "{:>4} {:>6} {:>5} {:>7} {:>9} {:>12} {:>10.3} {:>10.3} {:>7} {:>9}",
            s.step.unwrap_or(0),
            s.paths,
            s.host_paths,
            s.points,
            s.stats.makespan,
            s.predicted_cycles,
            s.latency_s_at_50mhz * 1e3,
            s.host_time_s * 1e3,
            s.fixed_vs_f64.missed,
            s.fixed_vs_f64.spurious
        );
        let rel = format!("step-{}/summary.json", s.step.unwrap_or(0));
        write(out, &rel, &serde_json::to_string_pretty(s)?)?;
    }
    let doc = StepsSummary {
        scene: summaries[0].scene.clone(),
        max_order: args.max_order,
        schedule: args.schedule.kind().name(),
        seed: args.seed,
        clock_hz: CLOCK_HZ,
        rtl_written: !args.plan_only,
        platform_instances: summaries[0].platform_instances,
        cycles: summaries.iter().map(|s| s.predicted_cycles).collect(),
        steps: summaries,
    };
    write(out, "steps.json", &serde_json::to_string_pretty(&doc)?)?;
    Ok(doc)
}

fn print_steps(args: &HlsGenArgs, doc: &StepsSummary) {
    let total: u64 = doc.cycles.iter().sum();
    println!(
        "{} steps on one design ({} PEs): {} cycles in all, mean {:.3} ms per step at 50 MHz; wrote {}/steps.json{}",
        doc.steps.len(),
        doc.platform_instances,
        total,
        total as f64 / doc.steps.len().max(1) as f64 / CLOCK_HZ * 1e3,
        args.output.display(),
        if args.plan_only {
            " and step-<k>/summary.json (--plan-only: no RTL)"
        } else {
            ", step-<k>/summary.json and the design (rtl/, tb/: hls sim DIR runs every step)"
        }
    );
}

/// What `hls gen --steps` writes as `DIR/steps.json`.
#[derive(Debug, Serialize)]
pub struct StepsSummary {
    pub scene: String,
    pub max_order: usize,
    pub schedule: &'static str,
    pub seed: u64,
    pub clock_hz: f64,
    pub rtl_written: bool,
    /// PE instances of the one design every step runs on.
    pub platform_instances: u32,
    /// Predicted `CYCLES` per step (Fig. 19 of the paper), step 0 first.
    pub cycles: Vec<u64>,
    pub steps: Vec<HlsSummary>,
}

fn write(out: &mut OutputDir, rel: &str, text: &str) -> anyhow::Result<()> {
    out.write(rel, format!("{text}\n").as_bytes())
        .with_context(|| format!("writing {}", out.dir().join(rel).display()))
}

fn print_summary(s: &HlsSummary, dir: &Path) {
    println!(
        "{}: {} planes, {} candidate paths (order <= {}), {} points, {} through moving surfaces (host)",
        s.scene, s.planes, s.paths, s.max_order, s.points, s.host_paths
    );
    println!(
        "schedule {} (seed {}): {} PE instances ({} duplicates, budget {}), makespan {} slots (list scheduler: {}), LF {}, utilisation {:.1} %",
        s.schedule,
        s.seed,
        s.stats.instances,
        s.stats.duplicates,
        s.pe_budget,
        s.stats.makespan,
        s.list_makespan,
        s.stats.latency_factor,
        100.0 * s.stats.utilisation
    );
    println!(
        "cycles per run {} ({} per slot, {} PEs on the platform) = {:.3} ms at 50 MHz; host {:.3} ms (+ {:.3} ms model run for the round budgets)",
        s.predicted_cycles,
        s.cycles_per_slot,
        s.platform_instances,
        s.latency_s_at_50mhz * 1e3,
        s.host_time_s * 1e3,
        s.budget_model_time_s * 1e3
    );
    let f = &s.fixed_vs_f64;
    println!(
        "fixed point vs image method on {} valid paths: points max {:.3} mm (mean {:.3}), angle max {:.4} deg at TX, {:.4} deg at RX, {} not converged, {} missed, {} spurious",
        f.valid_paths_compared,
        f.max_point_error_mm,
        f.mean_point_error_mm,
        f.max_angle_error_tx_deg,
        f.max_angle_error_rx_deg,
        f.not_converged,
        f.missed,
        f.spurious
    );
    if s.rtl_written {
        println!(
            "wrote {}/rtl, tb, vectors, platform.json, work.json, report.md, summary.json",
            dir.display()
        );
    } else {
        println!(
            "wrote {}/schedule.json and summary.json (--plan-only: no RTL)",
            dir.display()
        );
    }
}
