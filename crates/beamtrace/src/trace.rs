//! `beamtrace trace`, `demo` and `scene check`.

use crate::args::{SceneArgs, TraceArgs};
use crate::load::load_scene;
use crate::output;
use anyhow::Context;
use bt_beams::TraceDocument;
use bt_scene::{Scene, SceneError};
use std::process::ExitCode;
use std::time::Instant;

pub fn run(args: &TraceArgs) -> anyhow::Result<ExitCode> {
    if args.steps {
        return crate::steps::run(args);
    }
    let t0 = Instant::now();
    let loaded = load_scene(&args.scene)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let scene = loaded.scene;
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let (tx, rx) = crate::load::terminals(&scene, &args.scene)?;
    let options = options_for(&args.solve, &scene)?;
    let t1 = Instant::now();
    let (bar, mut progress) = crate::progress::tree_progress();
    let mut tracer = bt_solve::Tracer::new(scene, options);
    let traced = tracer.trace_with_progress(tx, rx, &mut progress);
    bar.finish_and_clear();
    let traced = traced?;
    let scene = tracer.scene();
    let radio = args.radio.options()?.for_order(options.max_order);
    let doc = TraceDocument::report(scene, &options, &traced, &radio, t1 - t0)?;
    warn_near_field(&doc.paths, scene);
    let json = serde_json::to_string_pretty(&doc).context("serialising the trace")?;
    if let Some(path) = &args.out {
        // The document went to the file: the terminal gets one line, not the document again.
        let inputs = &loaded.sources;
        crate::files::write(path, format!("{json}\n").as_bytes(), inputs, &["json"])?;
        eprintln!("wrote {} ({} paths)", path.display(), doc.paths.len());
    } else if args.json {
        println!("{json}");
    } else {
        output::print_table(&doc);
    }
    // The process ends with this command: the scene and the beam tree are left to the exit
    // instead of freed piece by piece on this thread (Munich: 17 M instructions).
    std::mem::forget(tracer);
    Ok(ExitCode::SUCCESS)
}

/// The trace options `solve` gives for `scene`, their warnings (transmission's opaque
/// materials) printed to stderr: every command that traces takes its options here.
pub fn options_for(
    solve: &crate::args::SolveArgs,
    scene: &Scene,
) -> anyhow::Result<bt_solve::pipeline::TraceOptions> {
    let options = solve.settings().trace_options(scene)?;
    for w in options.warnings(scene) {
        eprintln!("warning: {w}");
    }
    Ok(options)
}

/// Friis needs the far field: say so when a path is shorter than a wavelength (its loss is
/// clamped at 0 dB by `bt_channel::free_space`).
pub fn warn_near_field(paths: &[bt_beams::PathReport], scene: &Scene) {
    if let Some(p) = paths.iter().find(|p| p.near_field) {
        eprintln!(
            "warning: path {} is {:.4} m long, under one wavelength ({:.4} m) at {:.3} GHz: \
             near field, Friis does not hold (its loss is clamped to the value at one wavelength)",
            p.rank,
            p.length_m,
            bt_beams::SPEED_OF_LIGHT / scene.frequency_hz(),
            scene.frequency_hz() / 1e9
        );
    }
}

pub fn check(args: &SceneArgs) -> anyhow::Result<ExitCode> {
    match load_scene(args) {
        Ok(loaded) => {
            let scene = &loaded.scene;
            for w in loaded.warnings.iter().chain(&scene.warnings()) {
                println!("warning: {w}");
            }
            let reflectors = scene.reflectors().count();
            // Bare geometry (no terminal in the file or flags) says "none".
            let at = |p: Option<bt_scene::Vec3>| {
                p.map_or_else(|| "none".to_string(), |p| format!("{:?}", p.to_array()))
            };
            println!(
                "{}: ok: {} surfaces ({} reflectors, {} blockers), extent {:.2} m, tx {}, rx {}, {:.3} GHz",
                args.scene,
                scene.surfaces().len(),
                reflectors,
                scene.surfaces().len() - reflectors,
                scene.extent(),
                at(scene.tx_world()),
                at(scene.rx_world()),
                scene.frequency_hz() / 1e9
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => match e.downcast::<bt_import::ImportError>() {
            Ok(bt_import::ImportError::Scene(e @ SceneError::Invalid { .. })) => {
                println!("{e}");
                Ok(ExitCode::from(1))
            }
            Ok(e) => Err(e.into()),
            Err(e) => Err(e),
        },
    }
}
