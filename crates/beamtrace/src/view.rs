//! `beamtrace view`: one self-contained HTML page of a scene (every time step of a dynamic
//! scene) and its paths, traced here or read from a `trace --json` document.

use crate::args::ViewArgs;
use crate::load::load_dynamic;
use anyhow::Context;
use bt_view::StepPaths;
use std::process::ExitCode;

pub fn run(args: &ViewArgs) -> anyhow::Result<ExitCode> {
    let loaded = load_dynamic(&args.scene)?;
    let scenes: Vec<&bt_scene::Scene> = loaded.scene.scenes().iter().collect();
    // The inputs the page must not replace: every file the load read, and the paths document.
    let mut inputs = loaded.sources.clone();
    inputs.extend(args.paths.iter().cloned());
    bt_output::refuse_input(&args.output, &inputs)?;
    let paths = match &args.paths {
        Some(file) => {
            let name = file.display().to_string();
            let text = std::fs::read_to_string(file).with_context(|| format!("reading {name}"))?;
            let paths = bt_view::read_paths(&text, &name)?;
            bt_view::check_steps(&paths, scenes.len(), &name)?;
            bt_view::check_surfaces(&paths, &scenes, &name)?;
            paths
        }
        None => {
            let options = crate::trace::options_for(&args.solve, scenes[0])?;
            let mut tracer = bt_solve::Tracer::new(scenes[0].clone(), options);
            let mut steps = Vec::with_capacity(scenes.len());
            for scene in &scenes {
                // Bare geometry (no TX or RX in the file or flags) is drawn without paths.
                let Ok(ends) = scene.terminals() else {
                    steps.push(StepPaths::none());
                    continue;
                };
                tracer.set_scene((*scene).clone());
                let traced = tracer.trace(scene.to_world(ends.tx), scene.to_world(ends.rx))?;
                let radio = args
                    .coefficient
                    .options()
                    .for_order(tracer.options().max_order);
                let reports = bt_beams::report(scene, &traced.result.paths, &radio)?;
                steps.push(StepPaths::from_reports(scene, &reports));
            }
            steps
        }
    };
    let html = bt_view::page(&scenes, &paths);
    crate::files::write(&args.output, html.as_bytes(), &inputs, &[])?;
    let total: usize = paths.iter().map(|s| s.paths.len()).sum();
    println!(
        "{}: {} time step(s), {} paths -> {} ({} KiB)",
        scenes[0].name(),
        scenes.len(),
        total,
        args.output.display(),
        html.len() / 1024
    );
    Ok(ExitCode::SUCCESS)
}
