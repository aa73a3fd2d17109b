//! `beamtrace hls`: scene -> fixed-point model -> PE schedule -> Verilog, and `hls sim` /
//! `hls synth` on a generated directory.

use crate::args::{HlsArgs, HlsCommand, HlsGenArgs};
use anyhow::{Context, bail};
use bt_hls::{CLOCK_HZ, OutputDir, PlanOptions};
use bt_scene::Scene;
use bt_schedule::GaParams;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;

pub fn run(args: &HlsArgs) -> anyhow::Result<ExitCode> {
    match &args.command {
        HlsCommand::Gen(a) => generate(a),
        HlsCommand::Sim { dir, simulator } => simulate(dir, simulator.kind()),
        HlsCommand::Synth {
            dir,
            lut_adders,
            per_block,
        } => {
            let adders = if *lut_adders {
                bt_hls::AdderMapping::Luts
            } else {
                bt_hls::AdderMapping::CarryChain
            };
            let options = bt_hls::SynthOptions {
                adders,
                netlist: false,
                per_block: *per_block,
            };
            let bar =
                crate::progress::spinner(&format!("synthesising {} with Yosys", dir.display()));
            let r = bt_hls::synthesize_with(dir, &options);
            bar.finish_and_clear();
            let r = r.with_context(|| format!("synthesising {}", dir.display()))?;
            println!(
                "{}: Yosys synth_intel -family cycloneive (EP4CE115, 114,480 LEs), adders {}",
                dir.display(),
                if *lut_adders {
                    "in LUTs"
                } else {
                    "on the carry chain"
                }
            );
            println!("  logic cells      {:>10}", r.logic_cells);
            println!("  registers        {:>10}", r.registers);
            println!(
                "  memory bits      {:>10}   ({} M9K blocks)",
                r.memory_bits, r.m9k_blocks
            );
            println!(
                "  18x18 multipliers {:>9}   (of {})",
                r.multipliers,
                bt_hls::EP4CE115_MULTIPLIERS
            );
            println!(
                "  share of EP4CE115 {:>9.2} %   (paper, Table III: IPC 4 %-43 % of LEs)",
                r.percent_of_ep4ce115
            );
            for b in &r.blocks {
                println!(
                    "  {:<16} {:>3} x {:>8} logic cells {:>7} registers {:>3} M9K {:>3} multipliers",
                    b.module, b.instances, b.logic_cells, b.registers, b.m9k_blocks, b.multipliers
                );
            }
            println!(
                "  (area section written to {})",
                dir.join("report.md").display()
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
    crate::progress::heartbeat(&bar, "hls sim");
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
        r.predicted_cycles(),
        r.irq_cycles == r.predicted.run_cycles,
        r.tb_cycles,
        r.predicted.tb_cycles
    );
    let latency = r.step_latency_s();
    let worst = latency.iter().copied().fold(0.0, f64::max);
    println!(
        "measured latency per step at 50 MHz (longest run of each step, ms): {}; worst {:.3} ms",
        latency
            .iter()
            .map(|s| format!("{:.3}", s * 1e3))
            .collect::<Vec<_>>()
            .join(", "),
        worst * 1e3
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
    /// Paths started from the points they converged to at the previous step (`--steps
    /// --warm-start`).
    pub warm_started: usize,
    /// `dynamic`: the host loads one round of every path as groups (the round template) and
    /// the accelerator dispatches them until each path stops.
    pub schedule: &'static str,
    pub pe_budget: u32,
    /// The round template's statistics (makespan = its groups).
    pub stats: bt_schedule::ScheduleStats,
    /// Slots, jobs and dispatcher waits of the dispatched run (from the verification run).
    pub dispatch: bt_hls::dispatch::DispatchRun,
    /// PE instances of the platform (the one design all steps run on).
    pub platform_instances: u32,
    /// Mean cycles of a dispatched slot (`2·(jobs + 2) + max(pe_latency, dispatch + 1)`).
    pub mean_cycles_per_slot: f64,
    /// `CYCLES` of the run, predicted by the controller's cycle-exact twin
    /// (`bt_hls::dispatch::predict`) from the verification run; `hls sim` measures it.
    pub predicted_cycles: u64,
    pub latency_s_at_50mhz: f64,
    /// Host work per step, seconds: candidates, accelerator input and the round template.
    pub host_time_s: f64,
    /// Runs of the bit-exact model whose results feed the template or the bus program: 0
    /// (1 on warm-started steps, where the model stands in for the read-back).
    pub host_model_runs: u32,
    /// Seconds of the model run after the plan (verification only: expected bus words,
    /// `predicted_cycles`, `fixed_vs_f64`).
    pub verify_model_time_s: f64,
    /// Fixed point vs the f64 image method, from the verification run (whose results the
    /// co-simulation proves equal to the accelerator's, bit for bit).
    pub fixed_vs_f64: bt_accel::FixedDeviation,
    pub rtl_written: bool,
}

fn generate(args: &HlsGenArgs) -> anyhow::Result<ExitCode> {
    if args.max_order == 0 {
        bail!("--max-order must be at least 1 (line of sight needs no accelerator)");
    }
    let loaded = if args.steps {
        crate::load::load_dynamic(&args.scene)?.map(|d| d.scenes().to_vec())
    } else {
        crate::load::load_scene(&args.scene)?.map(|s| vec![s])
    };
    let scenes: &[Scene] = &loaded.scene;
    crate::load::require_every_step(scenes, &args.scene)?;
    // The output directory is locked, built aside and moved in: a user's own files survive.
    let mut out = OutputDir::begin(&args.output, &loaded.sources)
        .with_context(|| format!("creating {}", args.output.display()))?;
    // The platform's planes: the reflectors that no step moves (a PE for each that a step
    // meets, `bt_hls::Platform::fitting`).
    let planes = bt_accel::static_reflectors(scenes);
    let options = step_options(args, planes.len());
    let mut planned: Vec<bt_accel::PlannedStep> = Vec::with_capacity(scenes.len());
    for (k, scene) in scenes.iter().enumerate() {
        let bar = crate::progress::spinner(&format!("planning step {k} of {}", scenes.len()));
        let step = bt_accel::plan_step(scene, &planes, k, &options, planned.last())
            .with_context(|| args.scene.scene.clone())?;
        bar.finish_and_clear();
        planned.push(step);
    }
    let work: Vec<bt_hls::StepWork> = planned.iter().map(bt_accel::PlannedStep::work).collect();
    let platform = bt_hls::Platform {
        m9k_budget: args.m9k_budget,
        multiplier_budget: args.multiplier_budget,
        ..bt_hls::Platform::fitting(&work)?
    };
    // Refused here too with --plan-only: what could not be built is not planned.
    platform.check()?;
    let k = platform.instances.len() as u32;
    for p in planned.iter_mut() {
        // A stream's platform may hold PEs a step does not use: predict on all of them.
        if p.plan.schedule.instances.len() != k as usize {
            p.predict_on(k as usize)?;
        }
    }
    let rtl_written = !args.plan_only;
    if rtl_written {
        let report = bt_hls::generate_steps_into(&platform, &work, &mut out)?;
        debug_assert_eq!(report.num_instances, k);
    }
    let summaries: Vec<HlsSummary> = scenes
        .iter()
        .zip(planned)
        .map(|(scene, p)| summary(p, scene, args, k, rtl_written))
        .collect();
    if args.steps {
        let doc = report_steps(args, summaries, &mut out)?;
        let done = out
            .commit()
            .with_context(|| format!("writing {}", args.output.display()))?;
        crate::files::warn_left_alone(&done);
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
        let done = out
            .commit()
            .with_context(|| format!("writing {}", args.output.display()))?;
        crate::files::warn_left_alone(&done);
        print_summary(s, &args.output);
    }
    Ok(ExitCode::SUCCESS)
}

/// `hls gen`'s per-step report from a planned step on a platform of `k` PEs.
fn summary(
    p: bt_accel::PlannedStep,
    scene: &Scene,
    args: &HlsGenArgs,
    k: u32,
    rtl_written: bool,
) -> HlsSummary {
    let cycles = p.plan.predicted_cycles;
    HlsSummary {
        scene: scene.name().to_string(),
        step: args.steps.then_some(p.index),
        max_order: args.max_order,
        planes: p.step.input.planes.len(),
        paths: p.step.input.paths.len(),
        points: p.plan.points as usize,
        host_paths: p.step.host_sequences.len(),
        warm_started: p.warm_started,
        schedule: "dynamic",
        pe_budget: p.plan.pe_budget,
        dispatch: p.plan.dispatch,
        stats: p.plan.stats,
        platform_instances: k,
        mean_cycles_per_slot: p.plan.mean_cycles_per_slot,
        predicted_cycles: cycles,
        latency_s_at_50mhz: cycles as f64 / CLOCK_HZ,
        host_time_s: p.host_time_s,
        host_model_runs: p.host_model_runs,
        verify_model_time_s: p.verify_model_time_s,
        fixed_vs_f64: p.fixed,
        rtl_written,
    }
}

/// How `hls gen` plans each step on a platform of `planes` static reflectors: on
/// [`bt_hls::DEFAULT_GENERIC_PES`] generic PEs unless `--generic-pes` says otherwise; with
/// `--generic-pes 0` or `--pe-budget`, PEs per plane: as many as planes unless `--pe-budget`
/// says otherwise (the PEs of planes no path meets become copies; 0: no copy).
fn step_options(args: &HlsGenArgs, planes: usize) -> bt_accel::StepOptions {
    bt_accel::StepOptions {
        trace: bt_solve::pipeline::TraceOptions {
            candidates: args.candidates.mode(),
            max_candidates: args.max_candidates,
            diffraction: bt_solve::pipeline::DiffractionOptions {
                max_diffractions: usize::from(args.diffraction),
                ..Default::default()
            },
            ..bt_solve::pipeline::TraceOptions::new(args.max_order)
        },
        threshold_lsb: args.threshold_lsb,
        max_rounds: args.max_rounds,
        plan: PlanOptions {
            schedule: bt_hls::ScheduleKind::List,
            pe_budget: match args.pe_budget {
                None => Some(planes as u32),
                Some(0) => None,
                Some(n) => Some(n),
            },
            ga: GaParams::default(),
            // --pe-budget sizes PEs per plane; otherwise generic PEs (0: per plane).
            generic_pes: match (args.pe_budget, args.generic_pes) {
                (Some(_), _) | (None, Some(0)) => None,
                (None, g) => Some(g.unwrap_or(bt_hls::DEFAULT_GENERIC_PES)),
            },
        },
        warm_start: args.warm_start,
        round_order: args.round_order.order(),
    }
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
        "slots",
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
            s.dispatch.slots,
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
        schedule: "dynamic",
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
        "schedule {}: {} PE instances ({} duplicates), round template of {} groups; dispatched {} slots, {} jobs",
        s.schedule,
        s.stats.instances,
        s.stats.duplicates,
        s.stats.makespan,
        s.dispatch.slots,
        s.dispatch.jobs
    );
    println!(
        "cycles per run {} ({:.1} per slot, {} PEs on the platform) = {:.3} ms at 50 MHz; host {:.3} ms, {} model runs feeding the host's work (+ {:.3} ms verification run)",
        s.predicted_cycles,
        s.mean_cycles_per_slot,
        s.platform_instances,
        s.latency_s_at_50mhz * 1e3,
        s.host_time_s * 1e3,
        s.host_model_runs,
        s.verify_model_time_s * 1e3
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
    if f.reference == bt_accel::Reference::StepCandidates {
        println!(
            "  (the reference traced the step's own candidates: enumerating every sequence \
             would exceed --max-candidates)"
        );
    }
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
