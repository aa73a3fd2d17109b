//! `beamtrace trace`, `demo` and `scene check`.

use crate::args::{IpcAccelArg, IpcOrderArg, SceneArgs, SolveArgs, SolverArg, TraceArgs};
use crate::output::{self, TraceDocument};
use anyhow::{Context, bail};
use bt_scene::io::{LoadOptions, Loaded};
use bt_scene::{Scene, SceneError, Terminals};
use bt_solve::{Acceleration, IpcOptions, SbrOptions, Solver, UpdateOrder};
use std::process::ExitCode;
use std::time::Instant;

/// The load options the scene arguments select.
pub fn load_options(args: &SceneArgs) -> LoadOptions {
    LoadOptions {
        terminals: Terminals {
            tx: args.tx,
            rx: args.rx,
        },
        merge: bt_mesh::MergeOptions {
            angle_tol_deg: args.merge_angle_deg,
            dist_tol_m: args.merge_distance,
            ..bt_mesh::MergeOptions::default()
        },
        min_reflector_area_m2: args.min_reflector_area,
        ..LoadOptions::default()
    }
}

/// Load the scene named on the command line (a file or `builtin:NAME`), with a progress bar
/// while a point cloud's planes are extracted.
pub fn load_scene(args: &SceneArgs) -> Result<Loaded, SceneError> {
    let (bar, mut progress) = crate::cloud::extraction_progress();
    let loaded = bt_scene::load_with_progress(&args.scene, &load_options(args), &mut progress);
    bar.finish_and_clear();
    loaded
}

/// The solver the arguments select, with defaults scaled to the scene.
pub fn solver_for(args: &SolveArgs, scene: &Scene) -> anyhow::Result<Solver> {
    Ok(match args.solver {
        SolverArg::Image => Solver::Image,
        SolverArg::Ipc => {
            let order = match args.ipc_order {
                IpcOrderArg::GaussSeidel => UpdateOrder::GaussSeidel,
                IpcOrderArg::Jacobi => UpdateOrder::Jacobi,
            };
            let mut options = IpcOptions::for_scene(scene, order);
            if let Some(t) = args.ipc_threshold {
                if !(t.is_finite() && t > 0.0) {
                    bail!("--ipc-threshold must be a positive number of metres, got {t}");
                }
                options.threshold = t;
            }
            if args.ipc_max_iterations == 0 {
                bail!("--ipc-max-iterations must be at least 1");
            }
            options.max_iterations = args.ipc_max_iterations;
            options.acceleration = match args.ipc_accel {
                IpcAccelArg::None => Acceleration::None,
                IpcAccelArg::Newton => Acceleration::Newton,
            };
            Solver::Ipc(options)
        }
        SolverArg::Sbr => {
            let options = SbrOptions::chosen(args.sbr_rays, args.sbr_step_deg, args.sbr_planar)
                .map_err(anyhow::Error::msg)?;
            if let Some(problem) = options.over_budget(args.max_rays) {
                bail!("{problem}");
            }
            Solver::Sbr(options)
        }
    })
}

/// The pipeline options the arguments select.
pub fn trace_options(args: &SolveArgs, solver: Solver) -> bt_solve::pipeline::TraceOptions {
    bt_solve::pipeline::TraceOptions {
        max_order: args.max_order,
        solver,
        candidates: args.candidate_mode(),
        parallel: !args.single_thread,
        max_candidates: args.max_candidates,
    }
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
    let solver = solver_for(&args.solve, &scene)?;
    let t1 = Instant::now();
    let options = trace_options(&args.solve, solver);
    let traced = bt_solve::pipeline::trace_scene(&scene, &options)?;
    let t3 = Instant::now();
    let paths = bt_beams::report(&scene, &traced.result.paths);
    if let Some(p) = paths
        .iter()
        .find(|p| bt_beams::in_near_field(p.length_m, scene.frequency_hz()))
    {
        eprintln!(
            "warning: a path is {:.3e} m long, shorter than one wavelength ({:.3e} m): Friis does \
             not hold in the near field; its free-space loss is clamped to the value at one wavelength",
            p.length_m,
            bt_beams::near_field_limit_m(scene.frequency_hz())
        );
    }
    let t4 = Instant::now();
    let doc = TraceDocument::new(
        &scene,
        &solver,
        args.solve.max_order,
        paths,
        traced.candidates,
        traced.tree,
        traced.result.counts,
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
                scene.tx().to_array(),
                scene.rx().to_array(),
                scene.frequency_hz() / 1e9
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(e @ SceneError::Invalid { .. }) => {
            println!("{e}");
            Ok(ExitCode::from(1))
        }
        Err(e) => Err(e.into()),
    }
}
