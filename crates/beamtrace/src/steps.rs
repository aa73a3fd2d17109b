//! `beamtrace trace SCENE --steps`: every time step of a dynamic scene, incrementally by
//! default. Output: one JSON document `{ "steps": [ { "step", "paths", "stats" } ] }`, JSON
//! lines (one step object per line) with `--jsonl`, or a per-step table.

use crate::args::{SceneArgs, TraceArgs};
use crate::output::FORMAT_VERSION;
use crate::trace::{load_scene, solver_for};
use anyhow::{Context, bail};
use bt_beams::PathReport;
use bt_dynamic::{IncrementalTracer, StepOptions, UpdateStats, trace_scratch};
use bt_paths::CandidateStats;
use bt_paths::wvrn::WvrnStats;
use bt_scene::dynamic::{DynamicScene, builtin_dynamic_scene};
use bt_scene::{SceneDescription, Terminals};
use bt_solve::{OutcomeCounts, Solver};
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Debug, Serialize)]
pub struct StepsDocument {
    pub format_version: u32,
    pub scene: String,
    pub frequency_hz: f64,
    pub max_order: usize,
    pub solver: Solver,
    pub wvrn: bool,
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
/// (and any other static source) as one step.
pub fn load_dynamic(args: &SceneArgs) -> anyhow::Result<DynamicScene> {
    let overrides = args.material.frequency.is_some() || args.material.material.is_some();
    let dynamic_source = args.scene.starts_with("builtin:")
        || [".json", ".toml"]
            .iter()
            .any(|e| args.scene.to_ascii_lowercase().ends_with(e));
    if overrides && dynamic_source {
        bail!(
            "--frequency and --material are not supported with --steps on scene files yet: set \"frequency_hz\" and the materials in the scene"
        );
    }
    let terminals = Terminals {
        tx: args.tx,
        rx: args.rx,
    };
    if let Some(name) = args.scene.strip_prefix("builtin:") {
        return match builtin_dynamic_scene(name, terminals) {
            Some(scene) => Ok(scene?),
            None => bail!(
                "unknown built-in scene \"{name}\" (built-in scenes: {})",
                bt_scene::builtin_names().join(", ")
            ),
        };
    }
    let path = Path::new(&args.scene);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "json" || ext == "toml" {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let display = path.display().to_string();
        let desc: SceneDescription = if ext == "json" {
            bt_scene::io::parse_json(&text, &display)?
        } else {
            bt_scene::io::parse_toml(&text, &display)?
        };
        return Ok(DynamicScene::from_description(&desc, &display, terminals)?);
    }
    let loaded = load_scene(args)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok(DynamicScene::from_static(loaded.scene))
}

pub fn run(args: &TraceArgs) -> anyhow::Result<ExitCode> {
    let dynamic = load_dynamic(&args.paths.scene)?;
    let scene0 = dynamic.step(0);
    let solver = solver_for(args, scene0)?;
    let options = StepOptions {
        max_order: args.paths.max_order,
        solver,
        wvrn: args.candidate_mode() != bt_solve::pipeline::CandidateMode::Exhaustive,
        parallel: !args.single_thread,
    };
    let incremental = !args.from_scratch;
    let radio = args.paths.radio.options()?;
    let mut tracer = IncrementalTracer::new(options);
    let mut steps = Vec::with_capacity(dynamic.len());
    for (k, scene) in dynamic.scenes().iter().enumerate() {
        let t0 = Instant::now();
        let result = if incremental {
            tracer.step(scene)
        } else {
            trace_scratch(scene, k, &options)
        };
        let time_s = t0.elapsed().as_secs_f64();
        let paths = bt_beams::report(scene, &result.trace.paths, &radio)?;
        let step = StepDocument {
            step: k,
            tx: scene.tx().to_array(),
            rx: scene.rx().to_array(),
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
        max_order: args.paths.max_order,
        solver,
        wvrn: options.wvrn,
        incremental,
        steps,
    };
    if args.json || args.out.is_some() {
        let json = serde_json::to_string_pretty(&doc).context("serialising the steps")?;
        if let Some(path) = &args.out {
            std::fs::write(path, format!("{json}\n"))
                .with_context(|| format!("writing {}", path.display()))?;
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
        "scene {}  {} steps  max order {}  wvrn {}  {}",
        doc.scene,
        doc.steps.len(),
        doc.max_order,
        if doc.wvrn { "on" } else { "off" },
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
