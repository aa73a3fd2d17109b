//! `beamtrace hls`: scene -> fixed-point model -> PE schedule -> Verilog, and `hls sim` /
//! `hls synth` on a generated directory.

use crate::args::{HlsArgs, HlsCommand, HlsGenArgs};
use anyhow::{Context, bail};
use bt_hls::OutputDir;
use bt_hls::{HlsInput, PlanOptions};
use bt_paths::AllVisible;
use bt_scene::Scene;
use bt_schedule::{GaParams, Problem};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;

/// Clock of the paper's platform (Cyclone IV E at 50 MHz), Hz.
pub const CLOCK_HZ: f64 = bt_study::living_room::CLOCK_HZ;

pub fn run(args: &HlsArgs) -> anyhow::Result<ExitCode> {
    match &args.command {
        HlsCommand::Gen(a) => generate(a),
        HlsCommand::Sim { dir } => {
            let r = bt_hls::simulate(dir)
                .with_context(|| format!("co-simulating {}", dir.display()))?;
            println!(
                "{}: {} vectors, {} words compared, {} mismatches; CYCLES {} (predicted {}), testbench cycles {} (predicted {})",
                dir.display(),
                r.vectors,
                r.words_compared,
                r.mismatches,
                r.cycles,
                r.predicted_cycles,
                r.tb_cycles,
                r.predicted_tb_cycles
            );
            for m in r.mismatch_details.iter().take(20) {
                println!("  mismatch: {m}");
            }
            let ok = r.mismatches == 0
                && r.cycles == r.predicted_cycles
                && r.tb_cycles == r.predicted_tb_cycles;
            Ok(if ok {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            })
        }
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

/// What `hls gen` reports (also written as `DIR/summary.json`).
#[derive(Debug, Serialize)]
pub struct HlsSummary {
    pub scene: String,
    /// Time step of a dynamic scene (`hls gen --steps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<usize>,
    pub max_order: usize,
    pub planes: usize,
    pub paths: usize,
    pub points: usize,
    pub schedule: &'static str,
    pub seed: u64,
    pub pe_budget: u32,
    pub stats: bt_schedule::ScheduleStats,
    pub list_makespan: u32,
    pub cycles_per_slot: u64,
    pub predicted_cycles: u64,
    pub latency_s_at_50mhz: f64,
    pub fixed_vs_f64: FixedDeviation,
    pub rtl_written: bool,
}

/// Fixed-point model vs the f64 reference on the paths valid in f64 (image method).
#[derive(Debug, Serialize, Default)]
pub struct FixedDeviation {
    pub valid_paths_compared: usize,
    pub max_point_error_mm: f64,
    pub mean_point_error_mm: f64,
    pub max_angle_error_tx_deg: f64,
    pub max_angle_error_rx_deg: f64,
    /// Valid paths (in f64) the fixed-point model does not converge on.
    pub not_converged: usize,
    /// Valid paths the host check rejects (`bt_study::fpga::host_accepts`): lost paths.
    pub missed: usize,
    /// Candidates frozen by early stopping.
    pub left_bounds: usize,
    /// Converged, f64-valid results rejected by the reflection-law check.
    pub reflection_rejected: usize,
    /// Results the host accepts that are no path of the image method (false convergences).
    pub spurious: usize,
}

fn fixed_deviation(
    scene: &Scene,
    input: &HlsInput,
    max_order: usize,
) -> anyhow::Result<FixedDeviation> {
    let model = input.model()?;
    let results = model.run(input.tx, input.rx)?;
    let candidates = bt_paths::enumerate(scene, max_order, &AllVisible);
    let reference = bt_solve::trace(scene, &candidates, &bt_solve::Solver::Image, true);
    let mut err = FixedDeviation::default();
    // Input paths are the non-empty candidates in order (`bt_study::fpga::hls_input`).
    let candidates_of: Vec<Vec<bt_scene::SurfaceId>> = candidates
        .iter()
        .filter(|seq| !seq.is_empty())
        .map(|seq| seq.to_vec())
        .collect();
    debug_assert_eq!(candidates_of.len(), input.paths.len());
    err.left_bounds = results.iter().filter(|r| r.left_bounds).count();
    for (seq, r) in candidates_of.iter().zip(&results) {
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
    for path in &reference.paths {
        let Some(k) = input.paths.iter().position(|p| {
            p.len() == path.surfaces.len()
                && p.iter()
                    .zip(&path.surfaces)
                    .all(|(a, b)| input.planes[*a as usize].name == scene.surface(*b).name)
        }) else {
            continue;
        };
        let r = &results[k];
        if !r.converged {
            err.not_converged += 1;
        }
        if bt_study::fpga::host_accepts(scene, &candidates_of[k], r).is_err() {
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
    Ok(err)
}

fn generate(args: &HlsGenArgs) -> anyhow::Result<ExitCode> {
    if args.max_order == 0 {
        bail!("--max-order must be at least 1 (line of sight needs no accelerator)");
    }
    if args.steps {
        return generate_steps(args);
    }
    let loaded = crate::trace::load_scene(&args.scene)?;
    let mut out = OutputDir::begin(&args.output, &crate::inputs(&args.scene))
        .with_context(|| format!("creating {}", args.output.display()))?;
    let summary = generate_one(&loaded.scene, None, args, &mut out, "")?;
    out.commit()
        .with_context(|| format!("writing {}", args.output.display()))?;
    print_summary(&summary, &args.output);
    Ok(ExitCode::SUCCESS)
}

/// `hls gen --steps`: one accelerator (or schedule) per time step into `DIR/step-<k>/`, and
/// the per-step cycle counts in `DIR/steps.json`.
fn generate_steps(args: &HlsGenArgs) -> anyhow::Result<ExitCode> {
    let dynamic = crate::steps::load_dynamic(&args.scene)?;
    let mut top = OutputDir::begin(&args.output, &crate::inputs(&args.scene))
        .with_context(|| format!("creating {}", args.output.display()))?;
    let mut summaries = Vec::with_capacity(dynamic.len());
    println!(
        "{:>4} {:>6} {:>7} {:>9} {:>9} {:>12} {:>10}  directory",
        "step", "paths", "points", "instances", "makespan", "cycles", "ms@50MHz"
    );
    for (k, scene) in dynamic.scenes().iter().enumerate() {
        let dir = args.output.join(format!("step-{k}"));
        let s = generate_one(scene, Some(k), args, &mut top, &format!("step-{k}/"))?;
        println!(
            "{:>4} {:>6} {:>7} {:>9} {:>9} {:>12} {:>10.3}  {}",
            k,
            s.paths,
            s.points,
            s.stats.instances,
            s.stats.makespan,
            s.predicted_cycles,
            s.latency_s_at_50mhz * 1e3,
            dir.display()
        );
        summaries.push(s);
    }
    let total: u64 = summaries.iter().map(|s| s.predicted_cycles).sum();
    let doc = StepsSummary {
        scene: dynamic.step(0).name().to_string(),
        max_order: args.max_order,
        schedule: args.schedule.kind().name(),
        seed: args.seed,
        clock_hz: CLOCK_HZ,
        rtl_written: !args.plan_only,
        cycles: summaries.iter().map(|s| s.predicted_cycles).collect(),
        steps: summaries,
    };
    write(&mut top, "steps.json", &serde_json::to_string_pretty(&doc)?)?;
    top.commit()
        .with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "{} steps: {} cycles in all, mean {:.3} ms per step at 50 MHz; wrote {}/steps.json{}",
        doc.steps.len(),
        total,
        total as f64 / doc.steps.len().max(1) as f64 / CLOCK_HZ * 1e3,
        args.output.display(),
        if args.plan_only {
            " and step-<k>/{schedule,summary}.json (--plan-only: no RTL)"
        } else {
            " and step-<k>/ (RTL, testbench, summary.json)"
        }
    );
    Ok(ExitCode::SUCCESS)
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
    /// Predicted `CYCLES` per step (Fig. 19 of the paper), step 0 first.
    pub cycles: Vec<u64>,
    pub steps: Vec<HlsSummary>,
}

/// Model, schedule and (unless `--plan-only`) RTL of one scene into `out` under `prefix`
/// (`""` or `step-<k>/`).
fn generate_one(
    scene: &Scene,
    step: Option<usize>,
    args: &HlsGenArgs,
    out: &mut OutputDir,
    prefix: &str,
) -> anyhow::Result<HlsSummary> {
    bt_solve::pipeline::exhaustive_budget(scene, args.max_order, args.max_candidates)?;
    let (input, _) =
        bt_study::fpga::hls_input(scene, args.max_order, args.threshold_lsb, args.max_rounds);
    let at = match step {
        Some(k) => format!("{} step {k}", args.scene.scene),
        None => args.scene.scene.clone(),
    };
    if input.paths.is_empty() {
        bail!(
            "{at}: no candidate reflection paths up to order {}",
            args.max_order
        );
    }
    let points: u64 = input.paths.iter().map(|p| p.len() as u64).sum();
    bt_hls::check_capacity(input.paths.len() as u64, points)
        .with_context(|| format!("{at}: order {}", args.max_order))?;
    let problem: Problem = input.problem()?;
    let bar = crate::progress::spinner(&format!(
        "scheduling {} paths, {points} points",
        input.paths.len()
    ));
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
    let fixed = fixed_deviation(scene, &input, args.max_order)?;
    let rtl_written = !args.plan_only;
    if rtl_written {
        out.set_prefix(prefix)?;
        let report = bt_hls::generate_into(&input, &plan.schedule, out);
        out.set_prefix("")?;
        let report = report?;
        debug_assert_eq!(report.predicted_cycles, plan.predicted_cycles);
    } else {
        write(
            out,
            &format!("{prefix}schedule.json"),
            &serde_json::to_string(&plan.schedule)?,
        )?;
    }
    let summary = HlsSummary {
        scene: scene.name().to_string(),
        step,
        max_order: args.max_order,
        planes: input.planes.len(),
        paths: input.paths.len(),
        points: plan.points as usize,
        schedule: args.schedule.kind().name(),
        seed: args.seed,
        pe_budget: plan.pe_budget,
        list_makespan: plan.list_makespan,
        stats: plan.stats,
        cycles_per_slot: plan.cycles_per_slot,
        predicted_cycles: plan.predicted_cycles,
        latency_s_at_50mhz: plan.predicted_cycles as f64 / CLOCK_HZ,
        fixed_vs_f64: fixed,
        rtl_written,
    };
    write(
        out,
        &format!("{prefix}summary.json"),
        &serde_json::to_string_pretty(&summary)?,
    )?;
    Ok(summary)
}

fn write(out: &mut OutputDir, rel: &str, text: &str) -> anyhow::Result<()> {
    out.write(rel, format!("{text}\n").as_bytes())
        .with_context(|| format!("writing {}", out.dir().join(rel).display()))
}

fn print_summary(s: &HlsSummary, dir: &Path) {
    println!(
        "{}: {} planes, {} candidate paths (order <= {}), {} points",
        bt_scene::name::escape(&s.scene),
        s.planes,
        s.paths,
        s.max_order,
        s.points
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
        "cycles per time step {} ({} per slot) = {:.3} ms at 50 MHz",
        s.predicted_cycles,
        s.cycles_per_slot,
        s.latency_s_at_50mhz * 1e3
    );
    let f = &s.fixed_vs_f64;
    println!(
        "fixed point vs image method on {} valid paths: points max {:.3} mm (mean {:.3}), angle max {:.4} deg at TX, {:.4} deg at RX, {} not converged",
        f.valid_paths_compared,
        f.max_point_error_mm,
        f.mean_point_error_mm,
        f.max_angle_error_tx_deg,
        f.max_angle_error_rx_deg,
        f.not_converged
    );
    if s.rtl_written {
        println!(
            "wrote {}/rtl, tb, vectors, schedule.json, report.md, summary.json",
            dir.display()
        );
    } else {
        println!(
            "wrote {}/schedule.json and summary.json (--plan-only: no RTL)",
            dir.display()
        );
    }
}
