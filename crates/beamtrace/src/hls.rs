//! `beamtrace hls`: scene -> fixed-point model -> PE schedule -> Verilog, and `hls sim` /
//! `hls synth` on a generated directory.

use crate::args::{HlsArgs, HlsCommand, HlsGenArgs, ScheduleArg};
use anyhow::{Context, bail};
use bt_hls::{HlsInput, PE_LATENCY, PlaneSpec};
use bt_paths::AllVisible;
use bt_scene::Scene;
use bt_schedule::{Budget, GaParams, Problem, Schedule};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;

/// Clock of the paper's platform (Cyclone IV E at 50 MHz), Hz.
pub const CLOCK_HZ: f64 = 50e6;

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
            println!("  memory bits      {:>10}", r.memory_bits);
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
    pub fixed_vs_f64: FixedError,
    pub rtl_written: bool,
}

/// Fixed-point model vs the f64 reference on the paths valid in f64 (image method).
#[derive(Debug, Serialize, Default)]
pub struct FixedError {
    pub valid_paths_compared: usize,
    pub max_point_error_mm: f64,
    pub mean_point_error_mm: f64,
    pub max_angle_error_tx_deg: f64,
    pub max_angle_error_rx_deg: f64,
    pub not_converged: usize,
}

/// The HLS input of a scene: one plane per reflector (PE `bt_pe_<i>`), every candidate path of
/// order >= 1 up to `max_order`, initial points at the polygon centroids.
pub fn hls_input(
    scene: &Scene,
    max_order: usize,
    threshold_lsb: u32,
    max_rounds: u32,
) -> (HlsInput, Vec<usize>) {
    let reflectors: Vec<_> = scene.reflectors().collect();
    let index_of = |id: bt_scene::SurfaceId| {
        reflectors
            .iter()
            .position(|r| *r == id)
            .expect("candidates use reflectors") as u32
    };
    let candidates = bt_paths::enumerate(scene, max_order, &AllVisible);
    let mut paths = Vec::new();
    let mut init_points = Vec::new();
    let mut candidate_index = Vec::new();
    for (i, seq) in candidates.iter().enumerate() {
        if seq.is_empty() {
            continue;
        }
        paths.push(seq.iter().map(|id| index_of(*id)).collect());
        init_points.push(
            seq.iter()
                .map(|id| scene.surface(*id).polygon.centroid().to_array())
                .collect(),
        );
        candidate_index.push(i);
    }
    let planes = reflectors
        .iter()
        .map(|id| {
            let s = scene.surface(*id);
            let p = s.polygon.plane();
            PlaneSpec {
                name: s.name.clone(),
                normal: p.normal.to_array(),
                offset_m: p.offset,
            }
        })
        .collect();
    let input = HlsInput {
        planes,
        paths,
        init_points,
        tx: scene.tx().to_array(),
        rx: scene.rx().to_array(),
        threshold_lsb,
        max_rounds,
        test_vectors: Vec::new(),
    };
    (input, candidate_index)
}

fn fixed_error(scene: &Scene, input: &HlsInput, max_order: usize) -> anyhow::Result<FixedError> {
    let model = input.model()?;
    let results = model.run(input.tx, input.rx)?;
    let candidates = bt_paths::enumerate(scene, max_order, &AllVisible);
    let reference = bt_solve::trace(scene, &candidates, &bt_solve::Solver::Image, true);
    let mut err = FixedError::default();
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
    let loaded = crate::trace::load_scene(&args.scene)?;
    let scene = loaded.scene;
    if args.max_order == 0 {
        bail!("--max-order must be at least 1 (line of sight needs no accelerator)");
    }
    let (input, _) = hls_input(&scene, args.max_order, args.threshold_lsb, args.max_rounds);
    if input.paths.is_empty() {
        bail!(
            "{}: no candidate reflection paths up to order {}",
            args.scene.scene,
            args.max_order
        );
    }
    let problem: Problem = input.problem()?;
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
        max_instances: args
            .pe_budget
            .unwrap_or(planes_used + planes_used / 4)
            .max(planes_used),
    };
    let list = bt_schedule::schedule_list(
        &problem,
        &Budget {
            max_instances: planes_used,
        },
    )?;
    let schedule: Schedule = match args.schedule {
        ScheduleArg::List => list.clone(),
        ScheduleArg::Ga => bt_schedule::schedule_ga(
            &problem,
            &budget,
            &GaParams {
                seed: args.seed,
                ..GaParams::default()
            },
        )?,
    };
    schedule.check(&problem)?;
    let stats = schedule.stats(&problem);
    let points: usize = input.paths.iter().map(Vec::len).sum();
    let cycles_per_slot = 2 * (stats.instances as u64 + 1) + PE_LATENCY as u64;
    let predicted_cycles = points as u64 + stats.makespan as u64 * cycles_per_slot;
    let fixed = fixed_error(&scene, &input, args.max_order)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    let rtl_written = !args.plan_only;
    if rtl_written {
        let report = bt_hls::generate(&input, &schedule, &args.output)?;
        debug_assert_eq!(report.predicted_cycles, predicted_cycles);
    } else {
        write(
            &args.output.join("schedule.json"),
            &serde_json::to_string(&schedule)?,
        )?;
    }
    let summary = HlsSummary {
        scene: scene.name().to_string(),
        max_order: args.max_order,
        planes: input.planes.len(),
        paths: input.paths.len(),
        points,
        schedule: match args.schedule {
            ScheduleArg::Ga => "ga",
            ScheduleArg::List => "list",
        },
        seed: args.seed,
        pe_budget: budget.max_instances,
        list_makespan: list.stats(&problem).makespan,
        stats,
        cycles_per_slot,
        predicted_cycles,
        latency_s_at_50mhz: predicted_cycles as f64 / CLOCK_HZ,
        fixed_vs_f64: fixed,
        rtl_written,
    };
    write(
        &args.output.join("summary.json"),
        &serde_json::to_string_pretty(&summary)?,
    )?;
    print_summary(&summary, &args.output);
    Ok(ExitCode::SUCCESS)
}

fn write(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, format!("{text}\n")).with_context(|| format!("writing {}", path.display()))
}

fn print_summary(s: &HlsSummary, dir: &Path) {
    println!(
        "{}: {} planes, {} candidate paths (order <= {}), {} points",
        s.scene, s.planes, s.paths, s.max_order, s.points
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
