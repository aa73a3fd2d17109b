//! Command-line arguments.

use anyhow::{Context, bail};
use bt_geom::Vec3;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Real-time radio ray tracing for beam management.
#[derive(Debug, Parser)]
#[command(name = "beamtrace", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Trace every specular path between TX and RX in a scene (JSON/TOML scene, OBJ or PLY mesh,
    /// or builtin:living-room).
    Trace(TraceArgs),
    /// Trace the built-in furnished living room.
    Demo(DemoArgs),
    /// Scene utilities.
    Scene {
        #[command(subcommand)]
        command: SceneCommand,
    },
}

#[derive(Debug, Subcommand)]
pub enum SceneCommand {
    /// Validate a scene and report every problem (exit code 1 when there are any).
    Check(SceneArgs),
}

/// Arguments that select and load a scene.
#[derive(Debug, Args, Clone)]
pub struct SceneArgs {
    /// Scene file (.json, .toml, .obj, .ply) or builtin:NAME.
    pub scene: String,
    /// Transmitter position X,Y,Z in metres (overrides the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub tx: Option<Vec3>,
    /// Receiver position X,Y,Z in metres (overrides the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub rx: Option<Vec3>,
    /// Meshes: surfaces smaller than this (m²) only block.
    #[arg(long, default_value_t = 0.25)]
    pub min_reflector_area: f64,
    /// Meshes: faces whose normals differ by less than this (degrees) merge into one surface.
    #[arg(long, default_value_t = 1.0)]
    pub merge_angle_deg: f64,
    /// Meshes: faces whose planes differ by less than this (metres) merge into one surface.
    #[arg(long, default_value_t = 1e-3)]
    pub merge_distance: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// The image method (exact reference).
    Image,
    /// Iterative path convergence (the paper's algorithm).
    Ipc,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IpcOrderArg {
    /// Each point uses its neighbours' newest values.
    GaussSeidel,
    /// All points from the previous round (the parallel hardware).
    Jacobi,
}

#[derive(Debug, Args, Clone)]
pub struct TraceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Path solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Image)]
    pub solver: SolverArg,
    /// IPC update order.
    #[arg(long, value_enum, default_value_t = IpcOrderArg::GaussSeidel)]
    pub ipc_order: IpcOrderArg,
    /// IPC convergence threshold on the mean displacement per round, metres
    /// (default 1e-13 × scene extent).
    #[arg(long)]
    pub ipc_threshold: Option<f64>,
    /// IPC round cap.
    #[arg(long, default_value_t = bt_solve::ipc::DEFAULT_MAX_ITERATIONS)]
    pub ipc_max_iterations: u32,
    /// Use one thread (benchmarking); the output is identical either way.
    #[arg(long)]
    pub single_thread: bool,
    /// Print the JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON document to this file (the table still goes to stdout unless --json).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Debug, Args, Clone)]
pub struct DemoArgs {
    /// Path solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Image)]
    pub solver: SolverArg,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Print the JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl DemoArgs {
    pub fn into_trace(self) -> TraceArgs {
        TraceArgs {
            scene: SceneArgs {
                scene: "builtin:living-room".into(),
                tx: None,
                rx: None,
                min_reflector_area: 0.25,
                merge_angle_deg: 1.0,
                merge_distance: 1e-3,
            },
            max_order: self.max_order,
            solver: self.solver,
            ipc_order: IpcOrderArg::GaussSeidel,
            ipc_threshold: None,
            ipc_max_iterations: bt_solve::ipc::DEFAULT_MAX_ITERATIONS,
            single_thread: false,
            json: self.json,
            out: None,
        }
    }
}

/// Parse `X,Y,Z` (metres); negative values are fine (`--tx -1.5,0,2`).
pub fn parse_vec3(s: &str) -> anyhow::Result<Vec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        bail!("expected X,Y,Z (three comma-separated numbers in metres), got \"{s}\"");
    }
    let mut v = [0.0; 3];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p
            .parse::<f64>()
            .with_context(|| format!("coordinate {} of \"{s}\" is not a number", i + 1))?;
        if !v[i].is_finite() {
            bail!("coordinate {} of \"{s}\" is not finite", i + 1);
        }
    }
    Ok(Vec3::from_array(v))
}
