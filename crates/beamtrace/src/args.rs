//! Command-line arguments.

use crate::numbers;
use anyhow::{Context, bail};
use bt_geom::Vec3;
use bt_solve::settings::{IpcSettings, Named, SbrSettings, SolveSettings};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Real-time radio ray tracing for beam management.
#[derive(Debug, Parser)]
#[command(name = "beamtrace", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// What the columns of `trace`'s table mean (docs/output-format.md has every JSON field).
const TRACE_COLUMNS: &str = "Table columns: rank (by order, then length); ord: interactions \
(0: line of sight); length_m: unfolded length, m; delay_ns; aod_az, aod_el: departure \
direction at TX, degrees (azimuth from +x towards +y, elevation up); aoa_az, aoa_el: where the \
wave arrives from at RX; loss_db: free space + the materials' constant reflection losses + a \
diffraction's excess loss (the paper's ranking uses it); gain_db: the polarised complex gain \
with the antennas and ITU materials, 20·log10|a|; surfaces: in order, an edge as A|B. \
docs/output-format.md.";

/// What `wvrn`'s table says.
const WVRN_TABLE: &str = "The table lists the pairs of surfaces the network does not link, \
with why: coplanar (both in one plane: no ray leaves one and reaches the other), occluded \
(other surfaces hide every segment from one to the other). Linked pairs are the rest. docs/wvrn.md.";

/// What the columns of `beams`' table mean.
const BEAMS_COLUMNS: &str = "Table columns: rank; tx_beam, rx_beam: indices in the DFT \
codebooks; tx_az/el, rx_az/el: the beams' main-lobe directions, degrees ('no direction': the \
main lobe lies outside the visible region); power_dbm: received power with that pair, the \
paths summed coherently at the carrier; path: with --ranking paper, the rank of the path the \
pair was chosen for. docs/channel.md §7.";

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Trace every specular path between TX and RX in a scene, with --diffraction or
    /// --max-diffractions 2 those that diffract on edges, and with --transmission those that
    /// cross walls (JSON/TOML scene, Mitsuba/Sionna XML scene, OBJ, PLY or STL mesh, glTF
    /// scene, point cloud, or builtin:NAME).
    #[command(after_help = TRACE_COLUMNS)]
    Trace(TraceArgs),
    /// Extract planar surfaces from a point cloud (PLY or PCD) into a scene file.
    Extract(ExtractArgs),
    /// Sample a scene's surfaces into a noisy synthetic point cloud (PLY or PCD by extension).
    Sample(SampleArgs),
    /// Compile a scene into FPGA RTL (fixed-point model, PE schedule, Verilog), co-simulate,
    /// synthesise.
    Hls(HlsArgs),
    /// Trace the built-in furnished living room.
    Demo(DemoArgs),
    /// Build the weak visibility relationship network (WVRN) of a scene and export it as a
    /// table, JSON or Graphviz DOT.
    #[command(after_help = WVRN_TABLE)]
    Wvrn(WvrnArgs),
    /// Coverage sweep: trace the TX to every point of a receiver grid; writes coverage.csv and
    /// a heat map (coverage.svg, coverage.png) over the floor plan into --out.
    Sweep(SweepArgs),
    /// Write one self-contained HTML page showing the scene and its paths in 3-D (three.js
    /// inlined, no network needed); dynamic scenes get a time-step slider.
    View(ViewArgs),
    /// Channel impulse response (taps: gain, delay) as CSV, frequency response at subcarriers,
    /// and a power-delay-profile plot (SVG and PNG).
    Channel(ChannelArgs),
    /// Beam sweep: received power of every TX/RX beam pair of DFT codebooks on ULA/UPA arrays,
    /// the best pair and the ranked list.
    #[command(after_help = BEAMS_COLUMNS)]
    Beams(BeamsArgs),
    /// Serve traces: one JSON request per line (receiver, transmitter and object moves), one
    /// JSON answer per line with the path records of `trace --json`, from one long-lived
    /// tracer; stdin/stdout, or a TCP or Unix socket (docs/serve.md).
    Serve(ServeArgs),
    /// Scene utilities.
    Scene {
        #[command(subcommand)]
        command: SceneCommand,
    },
    /// The paper's validation studies.
    Study {
        #[command(subcommand)]
        command: StudyCommand,
    },
}

#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Section III: generated 2-D rooms with a moving vertex, image method vs IPC vs SBR
    /// (writes results.csv, summary.md and Figs. 5-7 as SVG and PNG into --out).
    #[command(name = "2d")]
    TwoD(Study2dArgs),
    /// Section VI: the dynamic living room (a person walks, a door opens) at every time step,
    /// image method vs IPC vs SBR vs the FPGA's fixed-point IPC with per-step cycle counts
    /// (writes results.csv, fpga.csv, summary.md and Figs. 17-19 as SVG and PNG into --out).
    LivingRoom(StudyLivingRoomArgs),
    /// Issue 31: twin-driven beam selection against exhaustive, hierarchical and
    /// keep-previous sweeps with TR 38.843's metrics, a UE moving through each scenario
    /// (writes summary.json, details.json, decisions.csv, trajectory.csv and two figures
    /// into --out; docs/study-beam-management.md).
    BeamManagement(StudyBeamManagementArgs),
}

#[derive(Debug, Args, Clone)]
pub struct StudyBeamManagementArgs {
    /// Output directory (created if missing).
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: PathBuf,
    /// Scenario: `living-room` (the dynamic living room, a UE walking a loop), `city` (a
    /// street of the built-in city) or a scene file (a street through its TX and RX);
    /// repeat for several. Default: living-room and city.
    #[arg(long = "scenario")]
    pub scenarios: Vec<String>,
    /// Seed of every random draw (echoed into details.json).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// UE positions (decisions) per scenario.
    #[arg(long, default_value_t = 1000)]
    pub positions: usize,
    /// Highest interaction order of the truth (a diffraction counts as one).
    #[arg(long, default_value_t = 2)]
    pub max_order: usize,
    /// Leave diffraction out of the truth.
    #[arg(long)]
    pub no_diffraction: bool,
    /// Highest reflection order of the twins' traces.
    #[arg(long, default_value_t = 2)]
    pub twin_max_order: usize,
    /// Let the twins trace first-order diffraction too.
    #[arg(long)]
    pub twin_diffraction: bool,
    /// Standard deviation of the L1-RSRP measurement error, dB.
    #[arg(long, default_value_t = 1.0, value_parser = numbers::decibels)]
    pub rsrp_noise_db: f64,
    /// L1-RSRP reporting step, dB (3GPP: 1; 0 reports exact values).
    #[arg(long, default_value_t = 1.0, value_parser = numbers::decibels)]
    pub rsrp_step_db: f64,
    /// The twins' UE position errors σ (horizontal, per axis), metres, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 0.05, 0.3, 1.0], value_parser = numbers::length_m)]
    pub position_sigmas: Vec<f64>,
    /// The twins' reporting latencies, milliseconds, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 100.0], value_parser = numbers::milliseconds)]
    pub latencies_ms: Vec<f64>,
    /// The K of the twin top-K methods, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2, 4, 8])]
    pub top_k: Vec<usize>,
    /// Transmitted power per resource element, dBm.
    #[arg(long, default_value_t = -6.0, value_parser = numbers::power_dbm, allow_hyphen_values = true)]
    pub tx_power_dbm: f64,
    /// Points per m² of the scan behind the extracted twin (0: no extracted twin).
    #[arg(long, default_value_t = 2000.0, value_parser = numbers::scan_density)]
    pub scan_density: f64,
    /// Range noise of the scan, metres.
    #[arg(long, default_value_t = 0.005, value_parser = numbers::length_m)]
    pub scan_noise: f64,
    /// Budget: no extracted twin from a scan of more points than this.
    #[arg(long, default_value_t = 5_000_000)]
    pub max_scan_points: u64,
    /// Budget: stop before the work rather than enumerate more candidates than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: u64,
}

#[derive(Debug, Args, Clone)]
pub struct StudyLivingRoomArgs {
    /// Output directory (created if missing).
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: PathBuf,
    /// The dynamic scene whose time steps are traced (a scene file with steps, or builtin:NAME).
    #[arg(long, default_value = "builtin:living-room-dynamic")]
    pub steps_from: String,
    /// SBR grid step over the whole sphere, degrees (the paper: 1, i.e. 64,800 rays).
    #[arg(long, default_value_t = 1.0, value_parser = numbers::sbr_step_deg)]
    pub sbr_step_deg: f64,
    #[command(flatten)]
    pub budgets: StudyBudgetArgs,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Seed (echoed into the outputs).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Total PE instances per step: extra PEs become copies of the busiest planes (default
    /// none). Each step's accelerator dispatches its paths' rounds itself (docs/hardware.md).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub pe_budget: Option<u32>,
    /// Fixed-point convergence threshold on a round's largest displacement, in 1/256 mm.
    #[arg(long, default_value_t = 16)]
    pub threshold_lsb: u32,
    /// Round cap of the fixed-point IPC (1 to 65536: each round is a pass over every path).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub max_rounds: u32,
    /// Start every step's accelerator run from the beam tree's window centres instead of the
    /// points the previous step converged to.
    #[arg(long)]
    pub cold_start: bool,
    /// Update order of the accelerator's rounds.
    #[arg(long, value_enum, default_value_t = RoundOrderArg::RedBlack)]
    pub round_order: RoundOrderArg,
}

/// The budgets both studies check before any work.
#[derive(Debug, Args, Clone)]
pub struct StudyBudgetArgs {
    /// Budget: refuse an SBR grid of more rays than this.
    #[arg(long, default_value_t = bt_solve::sbr::DEFAULT_MAX_RAYS)]
    pub max_rays: u64,
    /// Budget: stop before the work rather than enumerate more candidates than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: u64,
}

#[derive(Debug, Args, Clone)]
pub struct Study2dArgs {
    /// Number of rooms (shapes cycle L, T, U, convex: 100 gives 25 of each, as Table I).
    #[arg(long, default_value_t = 100)]
    pub rooms: usize,
    /// Time steps per room (the moving vertex advances once per step).
    #[arg(long, default_value_t = 10)]
    pub steps: usize,
    /// Budget: refuse a study of more rooms × steps than this.
    #[arg(long, default_value_t = bt_study::MAX_ROOM_STEPS.limit)]
    pub max_room_steps: u64,
    /// Seed of the room generator (echoed into the outputs).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory (created if missing).
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: PathBuf,
    /// SBR angular step, degrees (the paper: 1).
    #[arg(long, default_value_t = 1.0, value_parser = numbers::sbr_step_deg)]
    pub sbr_step_deg: f64,
    #[command(flatten)]
    pub budgets: StudyBudgetArgs,
    /// Launch SBR rays over the whole sphere (azimuth × elevation grid) instead of only in the
    /// plane of the room.
    #[arg(long)]
    pub sbr_sphere: bool,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
}

#[derive(Debug, Subcommand)]
pub enum SceneCommand {
    /// Validate a scene and report every problem (exit code 1 when there are any).
    Check(SceneArgs),
}

/// Arguments that select and load a scene.
#[derive(Debug, Args, Clone)]
pub struct SceneArgs {
    /// Scene file (.json, .toml, Mitsuba/Sionna .xml, .obj, .ply, .stl mesh, .gltf/.glb, .ply/.pcd point cloud)
    /// or builtin:NAME.
    pub scene: String,
    /// Transmitter position X,Y,Z in metres (overrides the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub tx: Option<Vec3>,
    /// Receiver position X,Y,Z in metres (overrides the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub rx: Option<Vec3>,
    /// Meshes: surfaces whose merged region (all its coplanar pieces together) is smaller
    /// than this (m²) only block.
    #[arg(long, default_value_t = 0.25, value_parser = numbers::non_negative)]
    pub min_reflector_area: f64,
    /// Meshes: faces whose normals differ by less than this (degrees) merge into one surface.
    #[arg(long, default_value_t = 1.0, value_parser = numbers::merge_angle_deg)]
    pub merge_angle_deg: f64,
    /// Meshes: faces whose planes differ by less than this (metres) merge into one surface.
    #[arg(long, default_value_t = 1e-3, value_parser = numbers::length_m)]
    pub merge_distance: f64,
    /// Meshes: budget on vertices and on faces of a mesh file, and of all the meshes of an XML
    /// scene together; a larger mesh stops before the merge.
    #[arg(long, default_value_t = bt_mesh::DEFAULT_MAX_ELEMENTS)]
    pub max_mesh_elements: u64,
    /// Point clouds: budget on the points a file declares; a larger cloud stops before reading.
    #[arg(long, default_value_t = bt_import::cloud::DEFAULT_MAX_POINTS)]
    pub max_cloud_points: u64,
    /// Budget on the size of every input file (scene, mesh, cloud), bytes; a larger file is
    /// refused before it is read.
    #[arg(long, default_value_t = bt_import::MAX_FILE_BYTES.limit)]
    pub max_file_bytes: u64,
    /// XML scenes: budget on the bytes all $parameter substitutions produce.
    #[arg(long, default_value_t = bt_import::xml::MAX_XML_SUBSTITUTION.limit)]
    pub max_xml_substitution: u64,
    /// Keep the loaded scene in the user's cache ($BEAMTRACE_CACHE_DIR, else
    /// $XDG_CACHE_HOME/beamtrace, else ~/.cache/beamtrace) and load it from there when the
    /// files and these options are unchanged (XML scenes, meshes, scene files)
    #[arg(long)]
    pub cache: bool,
    #[command(flatten)]
    pub material: MaterialArgs,
}

impl SceneArgs {
    /// `scene` with every other option at its command-line default: parsed by clap, so these
    /// defaults are the ones `--help` shows.
    pub fn defaults_for(scene: &str) -> SceneArgs {
        #[derive(Parser)]
        struct SceneOnly {
            #[command(flatten)]
            scene: SceneArgs,
        }
        SceneOnly::try_parse_from(["beamtrace", "--", scene])
            .expect("a lone positional scene always parses")
            .scene
    }
}

/// Carrier and radio material overrides (any scene source).
#[derive(Debug, Args, Clone, Default)]
pub struct MaterialArgs {
    /// Carrier frequency, Hz (overrides the scene's, at every step with --steps; meshes, point
    /// clouds and XML scenes default to 28e9).
    #[arg(long, value_parser = numbers::frequency_hz)]
    pub frequency: Option<f64>,
    /// Radio material of every surface: itu:NAME (ITU-R P.2040-3, e.g. itu:concrete) or
    /// custom:EPS_R,SIGMA (relative permittivity, conductivity in S/m).
    #[arg(long, value_parser = parse_material)]
    pub material: Option<String>,
    /// Slab thickness in metres: of --material; without it, of every material the scene
    /// leaves a half-space (so that --transmission crosses it; slabs keep their own).
    #[arg(long, allow_hyphen_values = true, value_parser = numbers::length_m)]
    pub thickness: Option<f64>,
}

impl MaterialArgs {
    /// The radio material `--material`/`--thickness` select, checked.
    pub fn radio(&self) -> anyhow::Result<Option<bt_channel::RadioMaterial>> {
        let Some(spec) = &self.material else {
            return Ok(None);
        };
        let radio = bt_channel::RadioMaterial::from_spec(spec, self.thickness);
        Ok(Some(radio.context("--material/--thickness")?))
    }
}

/// `--material` checked as [`bt_channel::RadioMaterial::from_spec`] reads it.
fn parse_material(s: &str) -> Result<String, bt_channel::ChannelError> {
    bt_channel::RadioMaterial::from_spec(s, None).map(|_| s.to_string())
}

/// Antennas at both ends and the transmitted power.
#[derive(Debug, Args, Clone)]
pub struct RadioArgs {
    /// TX antenna pattern: iso or tr38901 (3GPP TR 38.901 element, 8 dBi).
    #[arg(long, default_value = "iso", value_parser = parse_pattern)]
    pub tx_pattern: bt_channel::Pattern,
    /// RX antenna pattern: iso or tr38901.
    #[arg(long, default_value = "iso", value_parser = parse_pattern)]
    pub rx_pattern: bt_channel::Pattern,
    /// TX polarisation: V, H, +45 or -45.
    #[arg(long, default_value = "V", value_parser = parse_polarization, allow_hyphen_values = true)]
    pub tx_polarization: bt_channel::Polarization,
    /// RX polarisation: V, H, +45 or -45.
    #[arg(long, default_value = "V", value_parser = parse_polarization, allow_hyphen_values = true)]
    pub rx_polarization: bt_channel::Polarization,
    /// TX antenna/array orientation YAW,PITCH,ROLL in degrees (0,0,0: boresight +x).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    pub tx_orientation: Vec3,
    /// RX antenna/array orientation YAW,PITCH,ROLL in degrees.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    pub rx_orientation: Vec3,
    /// Transmitted power, dBm (for power_dbm).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = numbers::power_dbm)]
    pub tx_power_dbm: f64,
    #[command(flatten)]
    pub coefficient: CoefficientArgs,
}

/// The diffraction coefficient of diffracted paths' gains (every command that reports gains).
#[derive(Debug, Args, Clone, Copy)]
pub struct CoefficientArgs {
    /// Diffraction coefficient of diffracted paths: utd (Kouyoumjian-Pathak with Luebbers'
    /// lossy faces, continuous at every boundary) or sionna-rt-2.2 (Sionna RT 2.2's gains, to
    /// compare with Sionna: its combination, and its diffracted leg for a PathSolver whose
    /// max_depth is --max-order). docs/channel.md §8.
    #[arg(long, default_value = "utd", value_parser = parse_coefficient)]
    pub diffraction_coefficient: bt_channel::DiffractionCoefficient,
}

impl CoefficientArgs {
    /// Default radio options with this coefficient (commands without antenna options); the
    /// caller sets the trace's order ([`bt_beams::RadioOptions::for_order`]).
    pub fn options(self) -> bt_beams::RadioOptions {
        bt_beams::RadioOptions {
            diffraction_coefficient: self.diffraction_coefficient,
            ..bt_beams::RadioOptions::default()
        }
    }
}

fn parse_coefficient(
    s: &str,
) -> Result<bt_channel::DiffractionCoefficient, bt_channel::ChannelError> {
    s.parse()
}

fn parse_pattern(s: &str) -> Result<bt_channel::Pattern, bt_channel::ChannelError> {
    s.parse()
}

fn parse_polarization(s: &str) -> Result<bt_channel::Polarization, bt_channel::ChannelError> {
    s.parse()
}

impl RadioArgs {
    /// The report's radio options; the caller sets the trace's order
    /// ([`bt_beams::RadioOptions::for_order`]).
    pub fn options(&self) -> anyhow::Result<bt_beams::RadioOptions> {
        let antenna = |pattern, polarization, o: Vec3| {
            let orientation = bt_channel::Orientation::from_degrees(o.x, o.y, o.z);
            bt_channel::Antenna::new(pattern, polarization, orientation)
        };
        Ok(bt_beams::RadioOptions {
            tx: antenna(self.tx_pattern, self.tx_polarization, self.tx_orientation),
            rx: antenna(self.rx_pattern, self.rx_polarization, self.rx_orientation),
            tx_power_dbm: self.tx_power_dbm,
            diffraction_coefficient: self.coefficient.diffraction_coefficient,
            sionna_max_depth: None,
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// The image method (exact reference).
    Image,
    /// Iterative path convergence (the paper's algorithm).
    Ipc,
    /// Shooting and bouncing rays (the baseline; approximate paths).
    Sbr,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IpcOrderArg {
    /// Each point uses its neighbours' newest values.
    GaussSeidel,
    /// All points from the previous round (the parallel hardware).
    Jacobi,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IpcAccelArg {
    /// The paper's rounds alone.
    None,
    /// The paper's rounds until nearly settled, then Newton steps on the reflection law.
    Newton,
}

#[derive(Debug, Args, Clone)]
pub struct TraceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub radio: RadioArgs,
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Print the JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON document to this file instead of the terminal (which gets one line
    /// saying where it went).
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: Option<PathBuf>,
    /// Trace every time step of a dynamic scene (static scenes have one step).
    #[arg(long)]
    pub steps: bool,
    /// With --steps: print one JSON object per step and line.
    #[arg(long, requires = "steps")]
    pub jsonl: bool,
    /// With --steps: trace each step from scratch instead of updating the previous one.
    #[arg(long, requires = "steps")]
    pub from_scratch: bool,
}

#[derive(Debug, Args, Clone)]
pub struct ServeArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub radio: RadioArgs,
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Where requests come from: tcp:HOST:PORT or unix:PATH (one stream per connection,
    /// connections served at the same time); stdin/stdout when absent.
    #[arg(long, value_parser = parse_listen)]
    pub listen: Option<Listen>,
    /// Budget: with --listen, serve at most this many connections at a time (each holds its
    /// own tracer); a further client waits to be accepted.
    #[arg(long, default_value_t = bt_serve::MAX_CONNECTIONS as u64,
          value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub max_connections: u64,
    /// Budget: refuse a request line longer than this many bytes (answered with an error
    /// line; the stream goes on).
    #[arg(long, default_value_t = bt_serve::MAX_LINE_BYTES as u64,
          value_parser = clap::value_parser!(u64).range(1..=1 << 30))]
    pub max_line_bytes: u64,
    /// Budget: refuse a request with more receivers than this.
    #[arg(long, default_value_t = bt_serve::MAX_RECEIVERS as u64,
          value_parser = clap::value_parser!(u64).range(1..=1 << 20))]
    pub max_receivers: u64,
    /// With --tx-array or --rx-array (the other one 1x8), every answer holds a "beams" object:
    /// the beam sweep of `beams` over its paths, its best pair and the first --top pairs.
    #[command(flatten)]
    pub arrays: ArrayArgs,
    /// Pairs of the ranking in each answer's "beams".
    #[arg(long, default_value_t = 5)]
    pub top: usize,
    /// Microseconds a second thread spins after each answer waiting for the next one, to
    /// take half of a lone receiver's tree walk, report and JSON (lower latency for a busy
    /// stream, at the price of that core while it spins); 0: every answer on one thread.
    #[arg(long, default_value_t = bt_serve::PARTNER_SPIN_US,
          value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    pub partner_spin_us: u64,
}

/// The transport of `serve --listen`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Listen {
    /// `tcp:HOST:PORT` (port 0: any free port, printed on stderr).
    Tcp(String),
    /// `unix:PATH`.
    Unix(PathBuf),
}

fn parse_listen(s: &str) -> Result<Listen, String> {
    if let Some(address) = s.strip_prefix("tcp:") {
        if !address.contains(':') {
            return Err(format!("tcp:{address}: expected tcp:HOST:PORT"));
        }
        return Ok(Listen::Tcp(address.to_string()));
    }
    match s.strip_prefix("unix:") {
        Some(path) if !path.is_empty() => Ok(Listen::Unix(PathBuf::from(path))),
        _ => Err("expected tcp:HOST:PORT or unix:PATH".into()),
    }
}

/// How to trace: order, solver and its options, candidate generator, budget, threads (shared
/// by `trace`, `sweep` and `view`).
#[derive(Debug, Args, Clone)]
pub struct SolveArgs {
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
    #[arg(long, value_parser = numbers::positive_length_m)]
    pub ipc_threshold: Option<f64>,
    /// IPC round cap.
    #[arg(long, default_value_t = bt_solve::ipc::DEFAULT_MAX_ITERATIONS)]
    pub ipc_max_iterations: u32,
    /// IPC acceleration once the rounds have nearly settled (none = the paper's IPC).
    #[arg(long, value_enum, default_value_t = IpcAccelArg::None)]
    pub ipc_accel: IpcAccelArg,
    /// SBR: azimuth × elevation grid step, degrees (default 1, i.e. 360 × 180 rays).
    #[arg(long, conflicts_with = "sbr_rays", value_parser = numbers::sbr_step_deg)]
    pub sbr_step_deg: Option<f64>,
    /// SBR: launch this many rays on a Fibonacci sphere instead of a grid.
    #[arg(long)]
    pub sbr_rays: Option<u32>,
    /// SBR: launch only in the horizontal plane through TX (2-D scenes of vertical walls).
    #[arg(long)]
    pub sbr_planar: bool,
    /// Budget: refuse an SBR launch pattern of more rays than this.
    #[arg(long, default_value_t = bt_solve::sbr::DEFAULT_MAX_RAYS)]
    pub max_rays: u64,
    /// Use one thread (benchmarking); the output is identical either way.
    #[arg(long)]
    pub single_thread: bool,
    /// Candidate generator: the beam tree (default), every sequence over the WVRN, or every
    /// sequence (exhaustive, for checking). All three give the same paths.
    #[arg(long, value_enum, default_value_t = CandidatesArg::BeamTree)]
    pub candidates: CandidatesArg,
    /// Old spelling of `--candidates wvrn`.
    #[arg(long, overrides_with = "no_wvrn", hide = true)]
    pub wvrn: bool,
    /// Old spelling of `--candidates exhaustive`.
    #[arg(long, overrides_with = "wvrn", hide = true)]
    pub no_wvrn: bool,
    /// Budget: stop with an error rather than generate more candidates (beam-tree nodes).
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: u64,
    /// Budget: with --candidates wvrn, refuse a network of more pair tests (node pairs ×
    /// surfaces) than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_WVRN_TESTS)]
    pub max_wvrn_tests: u64,
    /// Edge diffraction: paths may diffract once, on a wedge or a free edge, anywhere in the
    /// sequence (the diffraction counts in --max-order). Same as --max-diffractions 1.
    #[arg(long)]
    pub diffraction: bool,
    /// Diffractions per path (0, 1 or 2; overrides --diffraction). Each counts in
    /// --max-order.
    #[arg(long)]
    pub max_diffractions: Option<usize>,
    /// Edges shorter than this (metres) do not diffract.
    #[arg(long, default_value_t = 0.0, value_parser = numbers::length_m)]
    pub min_edge_length: f64,
    /// Transmission: waves also cross every reflector whose material is a slab (ITU-R P.2040
    /// thin slab, no deflection; each crossing counts in --max-order). Half-spaces stay
    /// opaque; a material's "transmission": true does the same for that material alone.
    #[arg(long)]
    pub transmission: bool,
}

#[derive(Debug, Args, Clone)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Receiver grid x0:x1:dx,y0:y1:dy,z in metres (both ends included), e.g.
    /// 0.25:5.75:0.25,0.25:4.25:0.25,1.2.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_grid)]
    pub grid: bt_coverage::Grid,
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Output directory (created if missing): coverage.csv, coverage.svg, coverage.png.
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: PathBuf,
    /// Budget: refuse grids with more points than this (checked before any work).
    #[arg(long, default_value_t = bt_coverage::DEFAULT_MAX_POINTS)]
    pub max_points: u64,
    /// What the heat map shows.
    #[arg(long, value_enum, default_value_t = MapArg::Gain)]
    pub map: MapArg,
    #[command(flatten)]
    pub coefficient: CoefficientArgs,
}

fn parse_grid(s: &str) -> Result<bt_coverage::Grid, bt_coverage::GridError> {
    s.parse()
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MapArg {
    /// Gain of the strongest path (dB, the negated loss).
    Gain,
    /// Number of paths.
    Paths,
    /// Delay of the shortest path (ns).
    Delay,
}

impl MapArg {
    pub fn quantity(self) -> bt_coverage::MapQuantity {
        match self {
            MapArg::Gain => bt_coverage::MapQuantity::StrongestGain,
            MapArg::Paths => bt_coverage::MapQuantity::Paths,
            MapArg::Delay => bt_coverage::MapQuantity::ShortestDelay,
        }
    }
}

#[derive(Debug, Args, Clone)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Show the paths of this `beamtrace trace --json` document instead of tracing the scene.
    #[arg(long)]
    pub paths: Option<PathBuf>,
    /// HTML file to write.
    #[arg(short = 'o', long = "output", visible_alias = "out")]
    pub output: PathBuf,
    #[command(flatten)]
    pub coefficient: CoefficientArgs,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CandidatesArg {
    /// Visibility-driven beam tree: only sequences geometry allows.
    BeamTree,
    /// Every sequence over the weak visibility network.
    Wvrn,
    /// Every sequence up to the order (side test only).
    Exhaustive,
}

impl CandidatesArg {
    /// The pipeline's candidate mode.
    pub fn mode(self) -> bt_solve::pipeline::CandidateMode {
        by_name(self)
    }
}

impl SolveArgs {
    /// The candidate generator the arguments select (the old `--wvrn`/`--no-wvrn` win).
    pub fn candidate_mode(&self) -> bt_solve::pipeline::CandidateMode {
        use bt_solve::pipeline::CandidateMode;
        if self.no_wvrn {
            return CandidateMode::Exhaustive;
        }
        if self.wvrn {
            return CandidateMode::Wvrn;
        }
        self.candidates.mode()
    }

    /// The library's settings these arguments give (checked when they meet a scene).
    pub fn settings(&self) -> SolveSettings {
        SolveSettings {
            max_order: self.max_order,
            solver: by_name(self.solver),
            ipc: IpcSettings {
                order: by_name(self.ipc_order),
                acceleration: by_name(self.ipc_accel),
                threshold: self.ipc_threshold,
                max_iterations: self.ipc_max_iterations,
            },
            sbr: SbrSettings {
                step_deg: self.sbr_step_deg,
                rays: self.sbr_rays,
                planar: self.sbr_planar,
                max_rays: self.max_rays,
            },
            candidates: self.candidate_mode(),
            max_candidates: self.max_candidates,
            max_wvrn_tests: self.max_wvrn_tests,
            parallel: !self.single_thread,
            transmission: self.transmission,
            diffraction: bt_solve::pipeline::DiffractionOptions {
                max_diffractions: self
                    .max_diffractions
                    .unwrap_or(usize::from(self.diffraction)),
                min_edge_length: self.min_edge_length,
            },
        }
    }
}

/// The library value a command-line value names: the flags' values are the library's names
/// (`bt_solve::settings`), checked for every value by a test.
fn by_name<T: Named>(value: impl ValueEnum) -> T {
    let name = value.to_possible_value().expect("no value is skipped");
    bt_solve::settings::parse(name.get_name()).expect("every flag value is a library name")
}

#[derive(Debug, Args, Clone)]
pub struct WvrnArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Print JSON (nodes, edges, pruned pairs with reasons, candidate reduction).
    #[arg(long, conflicts_with = "dot")]
    pub json: bool,
    /// Print Graphviz DOT (dynamic scenes: red edges change with the motion, green are static).
    #[arg(long)]
    pub dot: bool,
    /// Write the output to this file instead of stdout.
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: Option<PathBuf>,
    /// Dynamic scenes: the time step to export (0-based).
    #[arg(long, default_value_t = 0)]
    pub step: usize,
    /// Highest reflection order for the candidate reduction figures.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Budget: stop before the work rather than enumerate more candidates than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: u64,
    /// Budget: refuse a network of more pair tests (node pairs × surfaces) than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_WVRN_TESTS)]
    pub max_wvrn_tests: u64,
}

#[derive(Debug, Args, Clone)]
pub struct DemoArgs {
    /// Path solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Image)]
    pub solver: SolverArg,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    #[command(flatten)]
    pub radio: RadioArgs,
    /// Print the JSON document instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl DemoArgs {
    pub fn into_trace(self) -> TraceArgs {
        TraceArgs {
            scene: SceneArgs::defaults_for("builtin:living-room"),
            radio: self.radio,
            solve: SolveArgs::with(self.max_order, self.solver),
            json: self.json,
            out: None,
            steps: false,
            jsonl: false,
            from_scratch: false,
        }
    }
}

/// What `channel` and `beams` trace.
#[derive(Debug, Args, Clone)]
pub struct PathArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub radio: RadioArgs,
    /// Highest reflection order.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Path solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Image)]
    pub solver: SolverArg,
    /// Edge diffraction: paths may diffract once (as `trace --diffraction`).
    #[arg(long)]
    pub diffraction: bool,
    /// Diffractions per path (0, 1 or 2; overrides --diffraction; as `trace`).
    #[arg(long)]
    pub max_diffractions: Option<usize>,
    /// Transmission through slab reflectors (as `trace --transmission`).
    #[arg(long)]
    pub transmission: bool,
}

impl PathArgs {
    /// The equivalent `trace` arguments (defaults for everything else).
    pub fn trace_args(&self) -> TraceArgs {
        TraceArgs {
            scene: self.scene.clone(),
            radio: self.radio.clone(),
            solve: SolveArgs {
                diffraction: self.diffraction,
                max_diffractions: self.max_diffractions,
                transmission: self.transmission,
                ..SolveArgs::with(self.max_order, self.solver)
            },
            json: false,
            out: None,
            steps: false,
            jsonl: false,
            from_scratch: false,
        }
    }
}

#[derive(Debug, Args, Clone)]
pub struct ChannelArgs {
    #[command(flatten)]
    pub paths: PathArgs,
    /// Channel impulse response CSV to write (one tap per path, by delay).
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: PathBuf,
    /// Also write the frequency response at the subcarriers to this CSV.
    #[arg(long)]
    pub cfr: Option<PathBuf>,
    /// Number of subcarriers of the frequency response, centred on the carrier.
    #[arg(long, default_value_t = 64)]
    pub subcarriers: usize,
    /// Subcarrier spacing, Hz.
    #[arg(long, default_value_t = 120e3, value_parser = numbers::spacing_hz)]
    pub subcarrier_spacing: f64,
    /// Budget: refuse a frequency response of more subcarriers than this.
    #[arg(long, default_value_t = bt_channel::MAX_SUBCARRIERS.limit)]
    pub max_subcarriers: u64,
    /// Budget: refuse a frequency response of more subcarriers × paths than this.
    #[arg(long, default_value_t = bt_channel::MAX_CFR_PRODUCTS.limit)]
    pub max_cfr_products: u64,
    /// Power-delay-profile plot: writes STEM.svg and STEM.png.
    #[arg(long)]
    pub pdp: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RankingArg {
    /// By received power, strongest first.
    Power,
    /// The paper's path ranking: the best pair for each path, paths by order, length, angle.
    Paper,
}

/// The arrays of a beam sweep (`beams`; `serve` answers with one when an array is given).
#[derive(Debug, Args, Clone)]
pub struct ArrayArgs {
    /// TX array ROWSxCOLUMNS (1xN is a horizontal ULA), elements in the antenna's local y-z
    /// plane, boresight along the antenna orientation [beams: default 1x8].
    #[arg(long, value_parser = parse_array_shape)]
    pub tx_array: Option<(usize, usize)>,
    /// RX array ROWSxCOLUMNS [beams: default 1x8].
    #[arg(long, value_parser = parse_array_shape)]
    pub rx_array: Option<(usize, usize)>,
    /// TX element spacing, wavelengths.
    #[arg(long, default_value_t = 0.5, value_parser = numbers::spacing_wavelengths)]
    pub tx_spacing: f64,
    /// RX element spacing, wavelengths.
    #[arg(long, default_value_t = 0.5, value_parser = numbers::spacing_wavelengths)]
    pub rx_spacing: f64,
    /// Ranking of the beam pairs.
    #[arg(long, value_enum, default_value_t = RankingArg::Power)]
    pub ranking: RankingArg,
    /// Budget: refuse a sweep of more beam pairs (TX beams × RX beams) than this.
    #[arg(long, default_value_t = bt_channel::MAX_BEAM_PAIRS.limit)]
    pub max_beam_pairs: u64,
}

#[derive(Debug, Args, Clone)]
pub struct BeamsArgs {
    #[command(flatten)]
    pub paths: PathArgs,
    #[command(flatten)]
    pub arrays: ArrayArgs,
    /// Print this many pairs of the ranked list (the JSON holds them all).
    #[arg(long, default_value_t = 10)]
    pub top: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON to this file.
    #[arg(short = 'o', long, visible_alias = "output")]
    pub out: Option<PathBuf>,
}

/// Parse `ROWSxCOLUMNS`, e.g. `1x8` or `4x4`.
pub fn parse_array_shape(s: &str) -> anyhow::Result<(usize, usize)> {
    let parse = |p: &str| p.trim().parse::<usize>().ok().filter(|n| *n > 0);
    match s.split_once(['x', 'X']).map(|(a, b)| (parse(a), parse(b))) {
        Some((Some(rows), Some(columns))) => Ok((rows, columns)),
        _ => bail!("expected ROWSxCOLUMNS with positive counts (e.g. 1x8 or 4x4), got \"{s}\""),
    }
}

impl SolveArgs {
    /// The defaults of every option but the order and the solver.
    pub fn with(max_order: usize, solver: SolverArg) -> Self {
        SolveArgs {
            max_order,
            solver,
            ipc_order: IpcOrderArg::GaussSeidel,
            ipc_threshold: None,
            ipc_max_iterations: bt_solve::ipc::DEFAULT_MAX_ITERATIONS,
            ipc_accel: IpcAccelArg::None,
            sbr_step_deg: None,
            sbr_rays: None,
            sbr_planar: false,
            max_rays: bt_solve::sbr::DEFAULT_MAX_RAYS,
            single_thread: false,
            candidates: CandidatesArg::BeamTree,
            wvrn: false,
            no_wvrn: false,
            max_candidates: bt_solve::pipeline::DEFAULT_MAX_CANDIDATES,
            max_wvrn_tests: bt_solve::pipeline::DEFAULT_MAX_WVRN_TESTS,
            diffraction: false,
            max_diffractions: None,
            min_edge_length: 0.0,
            transmission: false,
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

#[derive(Debug, Args, Clone)]
pub struct ExtractArgs {
    /// Point cloud: .ply (ASCII or binary) or .pcd (ASCII or binary), metres, z up.
    pub cloud: PathBuf,
    /// Scene file to write: .json or .toml (by extension; other extensions are refused).
    #[arg(short = 'o', long = "output", visible_alias = "out")]
    pub output: PathBuf,
    /// Also write the extraction report (JSON) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// RANSAC seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// RANSAC inlier distance, metres (about 3 σ of the sensor noise).
    #[arg(long, default_value_t = 0.015, value_parser = numbers::positive_length_m)]
    pub distance_threshold: f64,
    /// Planes of at least this area (m²) reflect; smaller ones only block (paper: 0.25).
    #[arg(long, default_value_t = 0.25, value_parser = numbers::non_negative)]
    pub min_reflector_area: f64,
    /// TX X,Y,Z in metres to store in the scene (optional).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub tx: Option<Vec3>,
    /// RX X,Y,Z in metres to store in the scene (optional).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub rx: Option<Vec3>,
    /// Budget on the points the cloud declares; a larger cloud stops before reading.
    #[arg(long, default_value_t = bt_import::cloud::DEFAULT_MAX_POINTS)]
    pub max_cloud_points: u64,
    /// Budget on the size of the cloud file, bytes; a larger file is refused before reading.
    #[arg(long, default_value_t = bt_import::MAX_FILE_BYTES.limit)]
    pub max_file_bytes: u64,
}

#[derive(Debug, Args, Clone)]
pub struct SampleArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Point cloud to write (.ply binary little-endian, or .pcd ASCII).
    #[arg(short = 'o', long = "output", visible_alias = "out")]
    pub output: PathBuf,
    /// Points per square metre of surface.
    #[arg(long, default_value_t = 2000.0, value_parser = numbers::positive)]
    pub density: f64,
    /// Budget: stop before sampling rather than generate more points than this (estimated
    /// as surface area × density).
    #[arg(long, default_value_t = 20_000_000)]
    pub max_points: u64,
    /// Gaussian noise along the surface normal, metres (standard deviation).
    #[arg(long, default_value_t = 0.005, value_parser = numbers::length_m)]
    pub noise: f64,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Debug, Args, Clone)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct HlsArgs {
    #[command(subcommand)]
    pub command: HlsCommand,
}

// Parsed once per run: the size of the largest variant (scene arguments) does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand, Clone)]
pub enum HlsCommand {
    /// Generate the accelerator for a scene into a directory.
    Gen(HlsGenArgs),
    /// Co-simulate a generated directory (every step's bus program) against the Rust model.
    Sim {
        /// Directory written by `hls gen`.
        dir: PathBuf,
        /// Simulator: Verilator (compiled, fast) or Icarus Verilog (interpreted, small designs).
        #[arg(long, value_enum, default_value_t = SimulatorArg::Verilator)]
        simulator: SimulatorArg,
    },
    /// Synthesise a generated directory with Yosys for the Cyclone IV E and report resources.
    Synth {
        /// Directory written by `hls gen`.
        dir: PathBuf,
        /// Build adders from plain LUTs (Yosys's own mapping, about two cells per bit) instead
        /// of the carry chain (one cell per bit, as Quartus): for comparison.
        #[arg(long)]
        lut_adders: bool,
        /// Keep the module hierarchy and report each block's cells (bt_top and every PE);
        /// the totals then lack the optimisations across PE ports of the flat run.
        #[arg(long)]
        per_block: bool,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SimulatorArg {
    /// Verilator 5 (`--binary --timing`).
    Verilator,
    /// Icarus Verilog.
    Icarus,
}

impl SimulatorArg {
    pub fn kind(self) -> bt_hls::Simulator {
        match self {
            SimulatorArg::Verilator => bt_hls::Simulator::Verilator,
            SimulatorArg::Icarus => bt_hls::Simulator::Icarus,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RoundOrderArg {
    /// Every point from the previous round (the paper's PE matrix).
    Jacobi,
    /// Even points, then odd points from them: about half the rounds, each in two phases.
    RedBlack,
}

impl RoundOrderArg {
    pub fn order(self) -> bt_hls::RoundOrder {
        match self {
            RoundOrderArg::Jacobi => bt_hls::RoundOrder::Jacobi,
            RoundOrderArg::RedBlack => bt_hls::RoundOrder::RedBlack,
        }
    }
}

#[derive(Debug, Args, Clone)]
pub struct HlsGenArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory.
    #[arg(short = 'o', long = "output", visible_alias = "out")]
    pub output: PathBuf,
    /// Highest reflection order of the candidate paths.
    #[arg(long, default_value_t = 3)]
    pub max_order: usize,
    /// Candidate generator of each step (as `trace --candidates`).
    #[arg(long, value_enum, default_value_t = CandidatesArg::BeamTree)]
    pub candidates: CandidatesArg,
    /// PEs per plane (not generic), N in all: the PEs beyond one per plane used become copies
    /// of the planes with the most jobs in one round (sized at step 0 for the whole stream).
    /// With --generic-pes 0 and no budget: one per static reflector, so the PEs of planes no
    /// path meets become copies; 0: no copy, one PE per plane a path meets.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=4096))]
    pub pe_budget: Option<u32>,
    /// Generic PEs (the default, 12): any PE takes any plane's job, its plane's coefficients
    /// loaded with it from a plane table the host writes, so the PE count follows the work,
    /// not the planes (docs/hardware.md). 0: PEs per plane, as the paper (sized by
    /// --pe-budget, which implies 0).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=255), conflicts_with = "pe_budget")]
    pub generic_pes: Option<u32>,
    /// Convergence threshold on a round's largest displacement, in 1/256 mm.
    #[arg(long, default_value_t = 16)]
    pub threshold_lsb: u32,
    /// Round cap of the fixed-point IPC (1 to 65535: the accelerator's ROUND_CAP register).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65535))]
    pub max_rounds: u32,
    /// M9K blocks the point and schedule memories may take (default: the EP4CE115's 432);
    /// a design that needs more is refused.
    #[arg(long, default_value_t = bt_hls::EP4CE115_M9K_BLOCKS)]
    pub m9k_budget: u32,
    /// 18 x 18 multiplier blocks the PEs' products may take (default: the EP4CE115's 266);
    /// the networks that save the most adders get them, the rest stay CSD networks (0: all).
    #[arg(long, default_value_t = bt_hls::EP4CE115_MULTIPLIERS)]
    pub multiplier_budget: u32,
    /// With --steps: start every step from the beam tree's window centres (the default; the
    /// flag is kept for scripts written before `--warm-start`).
    #[arg(long, conflicts_with = "warm_start")]
    pub cold_start: bool,
    /// With --steps: start each path the previous step converged on from the points it read
    /// back. `hls gen` has no accelerator to read from, so the model stands in for the
    /// read-back and the summary counts it in `host_model_runs`.
    #[arg(long)]
    pub warm_start: bool,
    /// Update order of the accelerator's rounds.
    #[arg(long, value_enum, default_value_t = RoundOrderArg::RedBlack)]
    pub round_order: RoundOrderArg,
    /// Model and schedule only (cycle counts, errors): skip writing RTL (for large scenes).
    #[arg(long)]
    pub plan_only: bool,
    /// Budget: stop before the work rather than enumerate more candidate paths than this.
    #[arg(long, default_value_t = bt_solve::pipeline::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: u64,
    /// Refused with an error: the accelerator is reflection-only (diffracted paths are traced
    /// on the host, `beamtrace trace --diffraction`).
    #[arg(long)]
    pub diffraction: bool,
    /// Every time step of a dynamic scene through ONE accelerator (synthesised once for the
    /// static planes; each step's candidates, start points and schedule are loaded over the
    /// bus): the design and the bus program of all steps into OUTPUT, per-step summaries into
    /// OUTPUT/step-K/, the per-step table into OUTPUT/steps.json.
    #[arg(long)]
    pub steps: bool,
}

/// `beamtrace hls SCENE -o DIR ...` is short for `beamtrace hls gen SCENE -o DIR ...` (the
/// spelling of the HLS issue); every other command line passes through unchanged.
pub fn with_default_subcommands(
    args: impl IntoIterator<Item = std::ffi::OsString>,
) -> Vec<std::ffi::OsString> {
    let mut args: Vec<std::ffi::OsString> = args.into_iter().collect();
    if args.get(1).is_some_and(|a| a == "hls") {
        let known = ["gen", "sim", "synth", "help", "-h", "--help"];
        if args.get(2).is_some_and(|a| !known.iter().any(|k| a == k)) {
            args.insert(2, "gen".into());
        }
    }
    args
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clap's own checks of every command (names, short flags and aliases unique per
    /// command), and every file a command writes named by `-o`, `--out` and `--output` alike.
    #[test]
    fn every_output_takes_o_out_and_output() {
        use clap::CommandFactory;
        let cli = Cli::command();
        cli.clone().debug_assert();
        fn walk(cmd: &clap::Command, path: &str, found: &mut Vec<String>) {
            for arg in cmd.get_arguments() {
                let long = arg.get_long().unwrap_or_default();
                if long == "out" || long == "output" {
                    let aliases = arg.get_visible_aliases().unwrap_or_default();
                    let other = if long == "out" { "output" } else { "out" };
                    assert!(aliases.contains(&other), "{path} --{long}: no --{other}");
                    assert_eq!(arg.get_short(), Some('o'), "{path} --{long}: no -o");
                    found.push(path.to_string());
                }
            }
            for sub in cmd.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()), found);
            }
        }
        let mut found = Vec::new();
        walk(&cli, "beamtrace", &mut found);
        assert!(found.len() >= 10, "outputs found: {found:?}");
    }

    #[test]
    fn scene_defaults_are_the_command_lines() {
        let a = SceneArgs::defaults_for("-room.json");
        assert_eq!(a.scene, "-room.json");
        assert!(a.tx.is_none() && a.rx.is_none() && a.material.material.is_none());
        assert_eq!(
            (a.min_reflector_area, a.merge_angle_deg, a.merge_distance),
            (0.25, 1.0, 1e-3)
        );
        assert_eq!(a.max_mesh_elements, bt_mesh::DEFAULT_MAX_ELEMENTS);
        assert_eq!(a.max_cloud_points, bt_import::cloud::DEFAULT_MAX_POINTS);
    }

    #[test]
    fn every_solver_flag_value_is_the_library_name_of_one_value() {
        fn all_named<A: ValueEnum, T: Named + PartialEq + std::fmt::Debug>() {
            let values: Vec<T> = A::value_variants()
                .iter()
                .map(|v| by_name(v.clone()))
                .collect();
            assert_eq!(values.len(), T::NAMES.len());
            assert!(T::NAMES.iter().all(|(_, v)| values.contains(v)));
        }
        all_named::<SolverArg, bt_solve::settings::SolverKind>();
        all_named::<IpcOrderArg, bt_solve::UpdateOrder>();
        all_named::<IpcAccelArg, bt_solve::Acceleration>();
        all_named::<CandidatesArg, bt_solve::pipeline::CandidateMode>();
    }

    #[test]
    fn the_default_flags_are_the_library_defaults() {
        let defaults = SolveArgs::with(3, SolverArg::Image);
        assert_eq!(defaults.settings(), SolveSettings::default());
        let parsed = Cli::try_parse_from(["beamtrace", "trace", "builtin:living-room"]).unwrap();
        let Command::Trace(trace) = parsed.command else {
            panic!("not the trace command")
        };
        assert_eq!(trace.solve.settings(), SolveSettings::default());
    }
}
