//! `beamtrace trace SCENE --steps`: every time step of a dynamic scene, incrementally by
//! default. Output: one JSON document `{ "steps": [ { "step", "paths", "stats" } ] }`, JSON
//! lines (one step object per line) with `--jsonl`, or a per-step table.

use crate::args::{SceneArgs, TraceArgs};
use crate::output::FORMAT_VERSION;
use crate::trace::load_options;
use anyhow::Context;
use bt_beams::PathReport;
use bt_dynamic::{IncrementalTracer, UpdateStats, trace_scratch};
use bt_paths::CandidateStats;
use bt_paths::wvrn::WvrnStats;
use bt_scene::dynamic::DynamicScene;
use bt_solve::{OutcomeCounts, Solver};
use serde::Serialize;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Debug, Serialize)]
pub struct StepsDocument {
    pub format_version: u32,
    pub scene: String,
    pub frequency_hz: f64,
    pub max_order: usize,
    pub solver: Solver,
    pub candidates: bt_solve::pipeline::CandidateMode,
    pub incremental: bool,
    pub steps: Vec<StepDocument>,
}

#[derive(Debug, Serialize)]
pub struct StepDocument {
    pub step: usize,
    pub tx: [f64; 3],
    pub rx: [f64; 3],
    pub paths: Vec<PathReport>,
    pub stats: StepStats,
}

#[derive(Debug, Serialize)]
pub struct StepStats {
    pub candidates: CandidateStats,
    pub outcomes: OutcomeCounts,
    pub valid_paths: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wvrn: Option<WvrnStats>,
    pub update: UpdateStats,
    /// Wall-clock seconds of the step (WVRN, candidates, solving; the only varying field).
    pub time_s: f64,
}

/// Load a scene as a dynamic scene: JSON/TOML files and built-ins with their steps; meshes
/// (and any other static source) as one step. Import warnings go to stderr.
pub fn load_dynamic(args: &SceneArgs) -> anyhow::Result<DynamicScene> {
    let options = load_options(args)?;
    let (bar, mut progress) = crate::cloud::extraction_progress();
    let loaded = bt_import::load_dynamic(&args.scene, &options, &mut progress);
    bar.finish_and_clear();
    let (mut scene, warnings) = loaded?;
    if let Some(f) = args.material.frequency {
        scene = scene.with_frequency(f)?;
    }
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

pub fn run(args: &TraceArgs) -> anyhow::Result<ExitCode> {
    let dynamic = load_dynamic(&args.scene)?;
    let scene0 = dynamic.step(0);
    let options = args.solve.settings().trace_options(scene0)?;
    let solver = options.solver;
    let incremental = !args.from_scratch;
    let radio = args.radio.options()?;
    let mut tracer = IncrementalTracer::new(options);
    let mut steps = Vec::with_capacity(dynamic.len());
    for (k, scene) in dynamic.scenes().iter().enumerate() {
        let t0 = Instant::now();
        let result = if incremental {
            tracer.step(scene)?
        } else {
            trace_scratch(scene, k, &options)?
        };
        let time_s = t0.elapsed().as_secs_f64();
        let paths = bt_beams::report(scene, &result.trace.paths, &radio)?;
        let step = StepDocument {
            step: k,
            tx: scene.tx_world().to_array(),
            rx: scene.rx_world().to_array(),
            stats: StepStats {
                candidates: result.candidates,
                outcomes: result.trace.counts,
                valid_paths: paths.len(),
                wvrn: result.wvrn,
                update: result.update,
                time_s,
            },
            paths,
        };
        if args.jsonl {
            println!(
                "{}",
                serde_json::to_string(&step).context("serialising a step")?
            );
        }
        steps.push(step);
    }
    let doc = StepsDocument {
        format_version: FORMAT_VERSION,
        scene: scene0.name().to_string(),
        frequency_hz: scene0.frequency_hz(),
        max_order: args.solve.max_order,
        solver,
        candidates: options.candidates,
        incremental,
        steps,
    };
    if args.json || args.out.is_some() {
        let json = serde_json::to_string_pretty(&doc).context("serialising the steps")?;
        if let Some(path) = &args.out {
            let inputs = crate::inputs(&args.scene);
            crate::files::write(path, format!("{json}\n").as_bytes(), &inputs, &["json"])?;
        }
        if args.json && !args.jsonl {
            println!("{json}");
        }
    }
    if !args.json && !args.jsonl {
        print_table(&doc);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_table(doc: &StepsDocument) {
    println!(
        "scene {}  {} steps  max order {}  candidates {:?}  {}",
        doc.scene,
        doc.steps.len(),
        doc.max_order,
        doc.candidates,
        if doc.incremental {
            "incremental"
        } else {
            "from scratch"
        }
    );
    println!(
        "{:>4} {:>5} {:>6} {:>10} {:>6} {:>7} {:>7} {:>5} {:>8}  strongest path",
        "step", "moved", "paths", "candidates", "links", "solved", "reused", "los", "time_ms"
    );
    for s in &doc.steps {
        let best = s
            .paths
            .iter()
            .min_by(|a, b| a.loss_db.total_cmp(&b.loss_db))
            .map(|p| {
                let names = if p.surfaces.is_empty() {
                    "(line of sight)".to_string()
                } else {
                    p.surfaces.join(" > ")
                };
                format!("{:.1} dB  {names}", p.loss_db)
            })
            .unwrap_or_else(|| "-".into());
        let u = &s.stats.update;
        println!(
            "{:>4} {:>5} {:>6} {:>10} {:>6} {:>7} {:>7} {:>5} {:>8.3}  {}",
            s.step,
            u.moved_surfaces,
            s.stats.valid_paths,
            s.stats.candidates.candidates,
            if u.full {
                "-".to_string()
            } else {
                u.wvrn_links_changed.to_string()
            },
            u.solved,
            u.reused,
            if s.paths.iter().any(|p| p.order == 0) {
                "yes"
            } else {
                "no"
            },
            s.stats.time_s * 1e3,
            best
        );
    }
}
