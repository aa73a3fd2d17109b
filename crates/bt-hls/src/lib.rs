//! RTL generation, co-simulation and synthesis of the beamtrace IPC accelerator (paper
//! sections IV-V): one PE per plane with its constants as shift-add networks, the PE
//! scheduler as a ROM, the coordinate updater-buffer, per-path convergence flags and an
//! Avalon-MM register interface.
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

mod error;
mod input;
mod pe;
mod plan;
mod tools;
mod top;
pub mod verilog;

use std::path::{Path, PathBuf};

use bt_fixed::FixedPoint;
pub use bt_output::OutputDir;
use bt_schedule::Schedule;

pub use bt_fixed::{BoundsM, EarlyStop, FixedOutcome, PathResult};
pub use error::HlsError;
pub use input::{ADDRESS_BITS, HlsInput, PE_LATENCY, PlaneSpec, check_capacity};
pub use pe::{POINT_BITS, pe_module_name};
pub use plan::{Plan, PlanOptions, ScheduleKind, cycles_per_slot, plan, run_cycles};
pub use tools::{LintReport, SimReport, SynthReport, lint, simulate, synthesize};
pub use top::MAP_VERSION;

use error::io_err;
use input::Design;

/// Word addresses of the control registers (Avalon-MM, 32-bit words).
pub mod regs {
    /// W: bit 0 = start (ignored while busy). R: bit 0 = busy, bit 1 = done.
    pub const CTRL: u32 = 0;
    /// R: clock cycles of the last run (start command to done).
    pub const CYCLES: u32 = 1;
    /// R: `{instances[7:0], version[7:0], paths[15:0]}`.
    pub const INFO: u32 = 2;
    /// R: convergence threshold, fine LSB.
    pub const THRESHOLD: u32 = 3;
    /// RW: TX x, y, z (millimetre words) at 4, 5, 6.
    pub const TX: u32 = 4;
    /// RW: RX x, y, z (millimetre words) at 8, 9, 10.
    pub const RX: u32 = 8;
}

/// What [`generate`] produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// Written files, relative to the output directory, sorted.
    pub files: Vec<String>,
    /// PE instances (columns of the schedule).
    pub num_instances: u32,
    /// Schedule makespan, slots.
    pub makespan: u32,
    /// Cycles per slot: `2·(instances + 1) + PE_LATENCY`.
    pub cycles_per_slot: u32,
    /// Predicted `CYCLES` register value: `points + makespan · cycles_per_slot`.
    pub predicted_cycles: u64,
    /// Predicted testbench clock edges for the whole bus program (see [`bus_cycles_formula`]).
    pub predicted_tb_cycles: u64,
    /// Word address of path 0's status word.
    pub status_base: u32,
    /// Word address of point 0's first word.
    pub point_base: u32,
    /// Register map and cycle formulas (markdown), also in `report.md`.
    pub docs: String,
}

/// The exact testbench cost of one vector, in clock edges: 6 single-cycle writes (TX, RX),
/// the start write plus `cycles`, and 2 edges per read (`1 + paths + 4·points` reads).
pub fn bus_cycles_formula(cycles: u64, num_paths: u64, num_points: u64) -> u64 {
    6 + 1 + cycles + 2 * (1 + num_paths + 4 * num_points)
}

/// Expected bus words of one vector, from the fixed-point model.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VectorExpectation {
    /// TX, millimetre words.
    pub tx: FixedPoint,
    /// RX, millimetre words.
    pub rx: FixedPoint,
    /// `(word address, expected data)` of every read, in program order.
    pub reads: Vec<(u32, u32)>,
    /// Model outcome per path.
    pub paths: Vec<PathResult>,
}

/// The status word of a path:
/// `{rounds[15:0], 12'b0, left_bounds, overflow, zero_sum, converged}`.
pub fn status_word(r: &PathResult) -> u32 {
    (r.rounds.min(0xffff) << 16)
        | (u32::from(r.left_bounds) << 3)
        | (u32::from(r.overflow) << 2)
        | (u32::from(r.zero_sum) << 1)
        | u32::from(r.converged)
}

fn expectations(d: &Design) -> Result<Vec<VectorExpectation>, HlsError> {
    let predicted = d.predicted_cycles() as u32;
    d.input
        .vectors()?
        .into_iter()
        .map(|[tx, rx]| {
            let paths = d.model.run_fixed(tx, rx, Some(&d.budgets));
            let mut reads = vec![(regs::CYCLES, predicted)];
            for (p, r) in paths.iter().enumerate() {
                reads.push((d.status_base + p as u32, status_word(r)));
            }
            for (p, r) in paths.iter().enumerate() {
                for (i, pt) in r.points.iter().enumerate() {
                    let base = d.point_base + 4 * (d.first_point[p] + i as u32);
                    for (k, c) in pt.iter().enumerate() {
                        reads.push((base + k as u32, c.floor_mm().0 as u32));
                    }
                    let frac = u32::from(pt[0].frac())
                        | u32::from(pt[1].frac()) << 8
                        | u32::from(pt[2].frac()) << 16;
                    reads.push((base + 3, frac));
                }
            }
            Ok(VectorExpectation {
                tx,
                rx,
                reads,
                paths,
            })
        })
        .collect()
}

fn bus_program(vectors: &[VectorExpectation]) -> Vec<u32> {
    let mut prog = Vec::new();
    for v in vectors {
        for (k, c) in v.tx.iter().enumerate() {
            prog.extend([1, regs::TX + k as u32, c.0 as u32]);
        }
        for (k, c) in v.rx.iter().enumerate() {
            prog.extend([1, regs::RX + k as u32, c.0 as u32]);
        }
        prog.extend([3, regs::CTRL, 1]);
        for &(addr, _) in &v.reads {
            prog.extend([2, addr, 0]);
        }
    }
    prog.extend([0, 0, 0]);
    prog
}

fn register_map(d: &Design, report_cycles: u64, tb_cycles: u64) -> String {
    let mut s = String::new();
    s.push_str("# bt_top register map (Avalon-MM slave)\n\n");
    s.push_str(
        "32-bit data, word addresses on `avs_address[15:0]`, no waitrequest, single-cycle writes, \
         pipelined reads with a fixed latency of 2 cycles (`avs_readdatavalid` marks the data), \
         interrupt `ins_irq` = done (level, cleared by the next start). Coordinates on the bus \
         are millimetre words (two's complement, metres x 1000).\n\n",
    );
    s.push_str("| address | access | name | content |\n|---|---|---|---|\n");
    s.push_str("| 0x0000 | W | CTRL | bit 0 = 1 starts a run (ignored while busy) |\n");
    s.push_str("| 0x0000 | R | STATUS | bit 0 busy, bit 1 done |\n");
    s.push_str("| 0x0001 | R | CYCLES | clock cycles of the last run |\n");
    s.push_str(&format!(
        "| 0x0002 | R | INFO | `{{instances[7:0], version[7:0], paths[15:0]}}` = 0x{:08x} |\n",
        (d.num_instances << 24) | (MAP_VERSION << 16) | (d.num_paths & 0xffff)
    ));
    s.push_str(&format!(
        "| 0x0003 | R | THRESHOLD | {} fine LSB (1/256 mm) |\n",
        d.input.threshold_lsb
    ));
    s.push_str("| 0x0004-0x0006 | RW | TX_X, TX_Y, TX_Z | transmitter, mm |\n");
    s.push_str("| 0x0008-0x000a | RW | RX_X, RX_Y, RX_Z | receiver, mm |\n");
    s.push_str(&format!(
        "| 0x{:04x} + p | R | PATH_STATUS[p] | `{{rounds[15:0], 12'b0, left_bounds, overflow, zero_sum, converged}}`, p < {} |\n",
        d.status_base, d.num_paths
    ));
    s.push_str(&format!(
        "| 0x{:04x} + 4i + {{0,1,2}} | R | POINT[i].X/Y/Z | floor(mm) of point i, i < {} |\n",
        d.point_base, d.num_points
    ));
    s.push_str(&format!(
        "| 0x{:04x} + 4i + 3 | R | POINT[i].FRAC | `{{8'b0, z_frac, y_frac, x_frac}}` (1/256 mm; value = mm + frac/256) |\n\n",
        d.point_base
    ));
    s.push_str(
        "Point words are valid only while idle (after done). Point i of path p is global index \
                `first_point[p] + i`, paths in input order, points TX side first.\n\n",
    );
    s.push_str(
        "Driver sequence: write TX_X..RX_Z, write CTRL = 1, wait for `ins_irq` (or poll STATUS \
                bit 1), read CYCLES, PATH_STATUS[*], POINT[*].\n\n",
    );
    s.push_str("## Cycle formulas (exact, checked by co-simulation)\n\n");
    s.push_str(&format!(
        "* CYCLES = points + makespan x (2 x (instances + 1) + PE_LATENCY) = {} + {} x (2 x ({} + 1) + {}) = {}\n",
        d.num_points, d.makespan, d.num_instances, PE_LATENCY, report_cycles
    ));
    s.push_str(&format!(
        "* testbench edges per vector = 6 writes + (1 + CYCLES) + 2 x (1 + paths + 4 x points) reads; all vectors: {tb_cycles}\n"
    ));
    s.push_str("* at 50 MHz (the paper's clock) one run takes CYCLES x 20 ns\n");
    s
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

/// The generated modules (PEs of the planes the schedule instantiates, then `bt_top`), as
/// `(module name, Verilog text)`. Pure function of the inputs.
pub fn rtl_modules(
    input: &HlsInput,
    schedule: &Schedule,
) -> Result<Vec<(String, String)>, HlsError> {
    let d = Design::new(input, schedule)?;
    rtl_of(&d)
}

fn rtl_of(d: &Design) -> Result<Vec<(String, String)>, HlsError> {
    let planes: std::collections::BTreeSet<u32> =
        d.schedule.instances.iter().map(|i| i.plane).collect();
    let mut out = Vec::new();
    for p in planes {
        let spec = &d.input.planes[p as usize];
        let m = pe::pe_module(p as usize, &spec.name, &d.model.planes()[p as usize])?;
        out.push((m.name.clone(), verilog::print_module(&m)));
    }
    let top = top::top_module(d);
    out.push((top.name.clone(), verilog::print_module(&top)));
    Ok(out)
}

/// Generates the accelerator for `input` scheduled by `schedule` into `out_dir`:
/// `rtl/<module>.v`, `tb/bt_tb.v`, `tb/stim.hex`, `vectors/vector_<n>.json`,
/// `schedule.json`, `hls_input.json`, `report.md`. Deterministic: same inputs, same bytes.
/// The directory is built aside and swapped in (`bt_output::OutputDir`): files of the user's in
/// `out_dir` are never touched, files of a previous run are replaced.
pub fn generate(input: &HlsInput, schedule: &Schedule, out_dir: &Path) -> Result<Report, HlsError> {
    let mut out = OutputDir::begin(out_dir, &[])?;
    let report = generate_into(input, schedule, &mut out)?;
    out.commit()?;
    Ok(report)
}

/// [`generate`] into an output directory under construction (the caller adds its own files
/// and commits).
pub fn generate_into(
    input: &HlsInput,
    schedule: &Schedule,
    out_dir: &mut OutputDir,
) -> Result<Report, HlsError> {
    let d = Design::new(input, schedule)?;
    let modules = rtl_of(&d)?;
    let vectors = expectations(&d)?;
    let prog = bus_program(&vectors);
    if prog.len() > 262_144 {
        return Err(HlsError::TooLarge(format!(
            "bus program of {} words exceeds the testbench's 262144",
            prog.len()
        )));
    }
    let predicted_cycles = d.predicted_cycles();
    let predicted_tb_cycles: u64 = vectors
        .iter()
        .map(|_| bus_cycles_formula(predicted_cycles, d.num_paths.into(), d.num_points.into()))
        .sum();
    let docs = register_map(&d, predicted_cycles, predicted_tb_cycles);
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
    for (n, v) in vectors.iter().enumerate() {
        write(
            out_dir,
            &format!("vectors/vector_{n}.json"),
            &to_json(v)?,
            &mut files,
        )?;
    }
    write(out_dir, "schedule.json", &to_json(schedule)?, &mut files)?;
    write(out_dir, "hls_input.json", &to_json(input)?, &mut files)?;
    let report = Report {
        files: Vec::new(),
        num_instances: d.num_instances,
        makespan: d.makespan,
        cycles_per_slot: d.cycles_per_slot(),
        predicted_cycles,
        predicted_tb_cycles,
        status_base: d.status_base,
        point_base: d.point_base,
        docs: docs.clone(),
    };
    let mut md = docs;
    md.push_str(&format!(
        "\n## Design\n\n* {} paths, {} points, {} PE instances ({} planes), makespan {} slots\n* PE latency {} cycles\n",
        d.num_paths,
        d.num_points,
        d.num_instances,
        modules.len() - 1,
        d.makespan,
        PE_LATENCY
    ));
    write(out_dir, "report.md", md.as_bytes(), &mut files)?;
    write(out_dir, "report.json", &to_json(&report)?, &mut files)?;
    files.sort();
    Ok(Report { files, ..report })
}

fn to_json<T: serde::Serialize>(v: &T) -> Result<Vec<u8>, HlsError> {
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

/// Paths of the generated RTL files in `out_dir`, sorted: the `rtl/*.v` files the generator
/// listed in the directory's manifest (a user's own files beside them are not ours to
/// simulate), or every `rtl/*.v` of a directory without a manifest.
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

pub(crate) fn recompute(out_dir: &Path) -> Result<(Design, Vec<VectorExpectation>), HlsError> {
    let input: HlsInput = read_json(&out_dir.join("hls_input.json"))?;
    let schedule: Schedule = read_json(&out_dir.join("schedule.json"))?;
    let d = Design::new(&input, &schedule)?;
    let v = expectations(&d)?;
    Ok((d, v))
}
