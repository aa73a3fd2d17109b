//! `beamtrace trace SCENE --steps`: every time step of a dynamic scene, incrementally by
//! default. Output: one JSON document `{ "steps": [ { "step", "paths", "stats" } ] }`, JSON
//! lines (one step object per line) with `--jsonl`, or a per-step table.

use crate::args::TraceArgs;
use crate::load::load_dynamic;
use anyhow::Context;
use bt_beams::{StepDocument, StepsDocument};
use std::process::ExitCode;
use std::time::Instant;

pub fn run(args: &TraceArgs) -> anyhow::Result<ExitCode> {
    let loaded = load_dynamic(&args.scene)?;
    let dynamic = &loaded.scene;
    crate::load::require_every_step(dynamic.scenes(), &args.scene)?;
    let scene0 = dynamic.step(0);
    let options = crate::trace::options_for(&args.solve, scene0)?;
    let incremental = !args.from_scratch;
    let radio = args.radio.options()?.for_order(options.max_order);
    let mut tracer = bt_solve::Tracer::new(scene0.clone(), options);
    let mut steps = Vec::with_capacity(dynamic.len());
    for scene in dynamic.scenes() {
        let t0 = Instant::now();
        let result = if incremental {
            tracer.update(scene)?
        } else {
            tracer.update_from_scratch(scene)?
        };
        let step = StepDocument::report(scene, result, &radio, t0.elapsed())?;
        if args.jsonl {
            println!(
                "{}",
                serde_json::to_string(&step).context("serialising a step")?
            );
        }
        steps.push(step);
    }
    let doc = StepsDocument::new(scene0, &options, incremental, steps);
    if args.json || args.out.is_some() {
        let json = serde_json::to_string_pretty(&doc).context("serialising the steps")?;
        if let Some(path) = &args.out {
            let inputs = &loaded.sources;
            crate::files::write(path, format!("{json}\n").as_bytes(), inputs, &["json"])?;
            eprintln!("wrote {} ({} steps)", path.display(), doc.steps.len());
        } else if args.json && !args.jsonl {
            println!("{json}");
        }
    }
    if args.out.is_none() && !args.json && !args.jsonl {
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
        "{:>4} {:>5} {:>6} {:>10} {:>6} {:>7} {:>7} {:>5} {:>8}  least-loss path",
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
                    p.route()
                };
                format!("loss {:.1} dB  {names}", p.loss_db)
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
    println!("{STEPS_LEGEND}");
}

/// What the steps table's columns mean (docs/dynamic-scenes.md).
const STEPS_LEGEND: &str = "moved: surfaces moved since the previous step; links: WVRN links \
re-tested that changed (-: the step was traced in full); solved / reused: candidates solved \
anew / taken over from the previous step; los: a line-of-sight path exists; least-loss path: \
the path of smallest loss_db (free space and the materials' constant losses) and its surfaces";
