//! RTL generation, co-simulation and synthesis of the beamtrace IPC accelerator (paper
//! sections IV-V): generic PEs that take any plane's job (its coefficients from a plane table
//! the host writes), or one PE per plane with its constants as shift-add networks, a controller
//! that dispatches each path's rounds at run time ([`dispatch`]: no round count is loaded, so
//! the host never runs the model to plan), the coordinate updater-buffer, per-path
//! convergence flags and an Avalon-MM register interface.
//!
//! * [`generate`] writes `rtl/*.v` (through the [`verilog`] AST and its one printer),
//!   `tb/` (bus-program testbench + stimulus), `vectors/*.json`, `schedule.json`,
//!   `hls_input.json` and `report.md` (with the register map). Pure function of its inputs.
//! * [`lint`] runs `verilator --lint-only -Wall` on every generated module.
//! * [`simulate`] runs the testbench (Icarus Verilog) and compares every word read over the
//!   bus with the `bt-fixed` model, bit for bit, and the cycle counts with [`Report`]'s
//!   exact formula.
//! * [`synthesize`] runs `yosys synth_intel` for Cyclone IV E and parses the cell counts.
//!
//! Units: metres in [`HlsInput`]; millimetre words on the bus; fine words (mm × 2^8) inside.

#![warn(missing_docs)]

pub mod dispatch;
mod error;
mod host;
mod input;
mod plan;
mod rtl;
mod tools;

use std::path::{Path, PathBuf};

pub use bt_output::OutputDir;
use bt_schedule::Schedule;

pub use bt_fixed::{BoundsM, EarlyStop, FixedOutcome, PathResult, RoundOrder};
pub use error::HlsError;
pub use host::{BusOp, CyclePrediction, TB_PROGRAM_WORDS, VectorExpectation, status_word};
pub use input::{
    AddressMap, Capacity, EP4CE115_M9K_BLOCKS, MAX_ADDRESS_BITS, MIN_ADDRESS_BITS, m9k_blocks,
};
pub use input::{HlsInput, PlaneSpec, Platform, StepWork, pe_latency};
pub use plan::{
    Plan, PlanOptions, ScheduleKind, plan, plan_dispatch, plan_on, predict_dispatch, run_cycles,
    schedule_entries, slot_cycles,
};
pub use rtl::mult::EP4CE115_MULTIPLIERS;
pub use rtl::pe::{PE_CORE_MODULE, pe_module_name, point_bits, sum_bits};
pub use rtl::top::MAP_VERSION;
pub use rtl::verilog;
pub use tools::{
    AdderMapping, BlockArea, EP4CE115_LES, LintReport, SimProgress, SimReport, Simulator,
    SynthOptions, SynthReport, area_markdown, cell_models, lint, simulate, simulate_netlist,
    simulate_with, synthesize, synthesize_rtl, synthesize_with,
};

use error::io_err;
use host::{host_program, register_map, stimulus};
use input::Design;

/// Generic PEs of `hls gen`'s design by default: the fewest at which the cold steps of the
/// unseen ~30-plane rooms and of the living room stay within a millisecond at 50 MHz
/// (docs/hardware.md's sweep: 0.73 ms at 12 on the hardest room, 1.07 ms at 10).
pub const DEFAULT_GENERIC_PES: u32 = 12;

/// Clock of the accelerator on the paper's platform (Intel Cyclone IV E at 50 MHz), Hz: a run
/// takes its cycle count (the CYCLES register, [`run_cycles`]) over this, in seconds.
pub const CLOCK_HZ: f64 = 50e6;

/// Word addresses of the control registers (Avalon-MM, 32-bit words).
pub mod regs {
    /// W: bit 0 = start (ignored while busy). R: bit 0 = busy, bit 1 = done.
    pub const CTRL: u32 = 0;
    /// R: clock cycles of the last run (start command to done).
    pub const CYCLES: u32 = 1;
    /// R: `{instances[7:0], version[7:0], path capacity[15:0]}`.
    pub const INFO: u32 = 2;
    /// R: convergence threshold, fine LSB.
    pub const THRESHOLD: u32 = 3;
    /// RW: TX x, y, z (millimetre words) at 4, 5, 6.
    pub const TX: u32 = 4;
    /// RW: RX x, y, z (millimetre words) at 8, 9, 10.
    pub const RX: u32 = 8;
    /// RW: paths of the loaded step (the ready queue holds PATH_BASE[0..PATHS] at a start).
    pub const PATHS: u32 = 12;
    /// W: the bits above 32 of the schedule entries written after it (only in designs whose
    /// entries are wider than 32 bits: many paths, points and PEs).
    pub const SCHED_HI: u32 = 13;
    /// RW: round cap of every path (16 bits): a path that reaches it stops unconverged.
    pub const ROUND_CAP: u32 = 14;
}

/// What [`generate`] produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// Written files, relative to the output directory, sorted.
    pub files: Vec<String>,
    /// PE instances (columns of the schedule memory).
    pub num_instances: u32,
    /// RAM sizes of the platform.
    pub capacity: Capacity,
    /// Groups of each step's round template (its makespan, one group a slot).
    pub makespans: Vec<u32>,
    /// The cycles the host program takes (JSON: `run_cycles`, `predicted_tb_cycles`).
    #[serde(flatten)]
    pub predicted: CyclePrediction,
    /// Bus writes the host makes to load every step's work (schedule, start points, TX/RX).
    pub load_writes: u64,
    /// Where the status, point and schedule regions start (JSON: `status_base`,
    /// `point_base`, `sched_base`).
    #[serde(flatten)]
    pub address_map: AddressMap,
    /// Register map and cycle formulas (markdown), also in `report.md`.
    pub docs: String,
}

fn write(
    out: &mut OutputDir,
    rel: &str,
    contents: &[u8],
    files: &mut Vec<String>,
) -> Result<(), HlsError> {
    out.write(rel, contents)?;
    files.push(rel.to_string());
    Ok(())
}

/// The generated modules (the PEs' shared core, the PEs of the platform's planes, then
/// `bt_top`), as `(module name, Verilog text)`. Pure function of the inputs.
pub fn rtl_modules(platform: &Platform) -> Result<Vec<(String, String)>, HlsError> {
    let model = input::platform_model(platform)?;
    rtl_of(platform, &model)
}

fn rtl_of(
    platform: &Platform,
    model: &bt_fixed::FixedIpc,
) -> Result<Vec<(String, String)>, HlsError> {
    let mut planes: std::collections::BTreeMap<u32, u32> = std::collections::BTreeMap::new();
    for i in platform.instances.iter().filter(|i| !i.is_generic()) {
        *planes.entry(i.plane).or_insert(0) += 1;
    }
    let wd = bt_fixed::Widths::for_coord(model.coord_bits());
    let fixed: Vec<(u32, u32, &bt_fixed::FixedPlane)> = planes
        .iter()
        .map(|(&p, &copies)| (p, copies, &model.planes()[p as usize]))
        .collect();
    let core = rtl::pe::pe_core_module(wd);
    let mut out = vec![(core.name.clone(), verilog::print_module(&core))];
    if platform.is_generic() {
        let m = rtl::generic::generic_pe_module(wd)?;
        out.push((m.name.clone(), verilog::print_module(&m)));
    }
    let multipliers = rtl::mult::network_forms(&fixed, wd, platform.multiplier_budget);
    for (p, _, plane) in fixed {
        let spec = &platform.planes[p as usize];
        let forms = multipliers
            .forms
            .get(&p)
            .copied()
            .unwrap_or([rtl::mult::NetworkForm::Csd; 3]);
        let m = rtl::pe::pe_module(p as usize, &spec.name, (plane, forms), wd)?;
        out.push((m.name.clone(), verilog::print_module(&m)));
    }
    let top = rtl::top::top_module(&rtl::top::TopParams::of(platform, model)?);
    out.push((top.name.clone(), verilog::print_module(&top)));
    Ok(out)
}

/// Generates the accelerator of one run: [`generate_steps`] with the smallest platform for
/// `input` scheduled by `schedule`.
pub fn generate(input: &HlsInput, schedule: &Schedule, out_dir: &Path) -> Result<Report, HlsError> {
    let work = vec![StepWork {
        input: input.clone(),
        schedule: schedule.clone(),
    }];
    generate_steps(&Platform::fitting(&work)?, &work, out_dir)
}

/// Generates ONE accelerator (`platform`) and the host program that runs every step of `work`
/// through it into `out_dir`: `rtl/<module>.v`, `tb/bt_tb.v`, `tb/stim.hex`,
/// `vectors/vector_<n>.json` (one per run), `platform.json`, `work.json`, `report.md`,
/// `report.json`. Deterministic: same inputs, same bytes.
///
/// The directory is locked, built aside and moved in (`bt_output::OutputDir`): files of the
/// user's in `out_dir` are never touched, files of a previous run are replaced. Files of a
/// previous run's manifest left alone are not reported here; a caller that prints them uses
/// [`generate_steps_into`] and commits itself (as `beamtrace hls gen` does).
pub fn generate_steps(
    platform: &Platform,
    work: &[StepWork],
    out_dir: &Path,
) -> Result<Report, HlsError> {
    let mut out = OutputDir::begin(out_dir, &[])?;
    let report = generate_steps_into(platform, work, &mut out)?;
    out.commit()?;
    Ok(report)
}

/// [`generate_steps`] into an output directory under construction (the caller adds its own
/// files and commits).
pub fn generate_steps_into(
    platform: &Platform,
    work: &[StepWork],
    out_dir: &mut OutputDir,
) -> Result<Report, HlsError> {
    let d = Design::new(platform, work)?;
    let modules = rtl_of(platform, &d.model)?;
    let (ops, runs) = host_program(&d)?;
    let prog = stimulus(&ops);
    if prog.len() > TB_PROGRAM_WORDS {
        return Err(HlsError::TooLarge(format!(
            "bus program of {} words exceeds the testbench's {TB_PROGRAM_WORDS}",
            prog.len()
        )));
    }
    let docs = register_map(&d);
    let mut files = Vec::new();
    for (name, text) in &modules {
        write(
            out_dir,
            &format!("rtl/{name}.v"),
            text.as_bytes(),
            &mut files,
        )?;
    }
    write(
        out_dir,
        "tb/bt_tb.v",
        include_str!("bt_tb.v").as_bytes(),
        &mut files,
    )?;
    let hex: String = prog.iter().map(|w| format!("{w:08x}\n")).collect();
    write(out_dir, "tb/stim.hex", hex.as_bytes(), &mut files)?;
    for (n, v) in runs.iter().enumerate() {
        write(
            out_dir,
            &format!("vectors/vector_{n}.json"),
            &to_json(v)?,
            &mut files,
        )?;
    }
    write(out_dir, "platform.json", &to_json(platform)?, &mut files)?;
    write(out_dir, "work.json", &to_json(&work)?, &mut files)?;
    let load_writes = ops.iter().filter(|o| matches!(o, BusOp::Write(..))).count() as u64;
    let report = Report {
        files: Vec::new(),
        num_instances: d.layout.num_instances,
        capacity: platform.capacity,
        makespans: d.steps.iter().map(|s| s.makespan).collect(),
        predicted: CyclePrediction::of(&ops, &runs),
        load_writes,
        address_map: d.layout.map,
        docs: docs.clone(),
    };
    let mut md = docs;
    md.push_str(&format!(
        "\n## Design\n\n* {} PE instances ({} planes), capacity {} paths, {} points, {} slots\n* PE latency {} cycles\n* {} steps, {} runs; makespan per step {:?}\n",
        d.layout.num_instances,
        modules.len() - 1,
        platform.capacity.paths,
        platform.capacity.points,
        platform.capacity.slots,
        pe_latency(platform.coord_bits),
        d.steps.len(),
        runs.len(),
        report.makespans
    ));
    write(out_dir, "report.md", md.as_bytes(), &mut files)?;
    write(out_dir, "report.json", &to_json(&report)?, &mut files)?;
    files.sort();
    Ok(Report { files, ..report })
}

fn to_json<T: serde::Serialize + ?Sized>(v: &T) -> Result<Vec<u8>, HlsError> {
    let mut s = serde_json::to_vec_pretty(v).map_err(|e| HlsError::Parse {
        what: "json serialisation".into(),
        message: e.to_string(),
    })?;
    s.push(b'\n');
    Ok(s)
}

pub(crate) fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, HlsError> {
    let bytes = std::fs::read(path).map_err(io_err(path))?;
    serde_json::from_slice(&bytes).map_err(|e| HlsError::Parse {
        what: path.display().to_string(),
        message: e.to_string(),
    })
}

/// Paths of the generated RTL files in `out_dir`, sorted.
pub fn rtl_files(out_dir: &Path) -> Result<Vec<PathBuf>, HlsError> {
    if let Some(listed) = bt_output::manifest_files(out_dir) {
        return Ok(listed
            .iter()
            .filter(|f| f.starts_with("rtl/") && f.ends_with(".v"))
            .map(|f| out_dir.join(f))
            .collect());
    }
    let dir = out_dir.join("rtl");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(io_err(&dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "v"))
        .collect();
    files.sort();
    Ok(files)
}

pub(crate) fn recompute(out_dir: &Path) -> Result<(Vec<BusOp>, Vec<VectorExpectation>), HlsError> {
    let platform: Platform = read_json(&out_dir.join("platform.json"))?;
    let work: Vec<StepWork> = read_json(&out_dir.join("work.json"))?;
    let d = Design::new(&platform, &work)?;
    host_program(&d)
}
