//! `beamtrace trace`, `demo` and `scene check`.

use crate::args::{SceneArgs, TraceArgs};
use crate::output::{self, TraceDocument};
use anyhow::Context;
use bt_import::{LoadOptions, Loaded};
use bt_scene::{Scene, SceneError, Terminals};
use std::process::ExitCode;
use std::time::Instant;

/// The load options the scene arguments select: `--material`/`--thickness` give every
/// material of any source that radio model; `--frequency` is the carrier of sources that carry
/// none (meshes, point clouds, XML scenes).
pub fn load_options(args: &SceneArgs) -> anyhow::Result<LoadOptions> {
    Ok(LoadOptions {
        terminals: Terminals {
            tx: args.tx,
            rx: args.rx,
        },
        merge: bt_mesh::MergeOptions {
            angle_tol_deg: args.merge_angle_deg,
            dist_tol_m: args.merge_distance,
            max_elements: args.max_mesh_elements,
            ..bt_mesh::MergeOptions::default()
        },
        min_reflector_area_m2: args.min_reflector_area,
        cloud: bt_import::cloud::ReadOptions {
            max_points: args.max_cloud_points,
            ..Default::default()
        },
        frequency_hz: args
            .material
            .frequency
            .unwrap_or(bt_scene::DEFAULT_FREQUENCY_HZ),
        radio: args.material.radio()?,
        ..LoadOptions::default()
    })
}

/// Load the scene named on the command line (a file or `builtin:NAME`), with a progress bar
/// while a point cloud's planes are extracted, and `--frequency` applied to scene files and
/// built-ins too.
pub fn load_scene(args: &SceneArgs) -> anyhow::Result<Loaded> {
    let options = load_options(args)?;
    let (bar, mut progress) = crate::cloud::extraction_progress();
    let loaded = bt_import::load_with_progress(&args.scene, &options, &mut progress);
    bar.finish_and_clear();
    let mut loaded = loaded?;
    if let Some(f) = args.material.frequency {
        loaded.scene = loaded.scene.with_frequency(f)?;
    }
    Ok(loaded)
}

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
    let options = args.solve.settings().trace_options(&scene)?;
    let solver = options.solver;
    let t1 = Instant::now();
    let (bar, mut progress) = crate::progress::tree_progress();
    let traced = bt_solve::pipeline::trace_scene_with_progress(&scene, &options, &mut progress);
    bar.finish_and_clear();
    let traced = traced?;
    let t3 = Instant::now();
    let radio = args.radio.options()?;
    let paths = bt_beams::report(&scene, &traced.result.paths, &radio)?;
    warn_near_field(&paths, &scene);
    let t4 = Instant::now();
    let doc = TraceDocument::new(
        &scene,
        &solver,
        args.solve.max_order,
        &radio,
        paths,
        (traced.candidates, traced.tree, traced.result.counts),
        [t1 - t0, traced.time.candidates, traced.time.solve, t4 - t3],
    );
    let json = serde_json::to_string_pretty(&doc).context("serialising the trace")?;
    if let Some(path) = &args.out {
        let inputs = crate::inputs(&args.scene);
        crate::files::write(path, format!("{json}\n").as_bytes(), &inputs, &["json"])?;
    }
    if args.json {
        println!("{json}");
    } else {
        output::print_table(&doc);
    }
    Ok(ExitCode::SUCCESS)
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
            println!(
                "{}: ok: {} surfaces ({} reflectors, {} blockers), extent {:.2} m, tx {:?}, rx {:?}, {:.3} GHz",
                args.scene,
                scene.surfaces().len(),
                reflectors,
                scene.surfaces().len() - reflectors,
                scene.extent(),
                scene.tx_world().to_array(),
                scene.rx_world().to_array(),
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
