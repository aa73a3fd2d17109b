//! Driving the external tools: Verilator (lint, co-simulation), Icarus Verilog (co-simulation), Yosys
//! (synthesis). A missing tool is [`HlsError::ToolMissing`], never a panic.

use std::path::Path;
use std::process::{Command, Output};

use crate::error::io_err;
use crate::{BusOp, CyclePrediction, HlsError, VectorExpectation, recompute, rtl_files};

mod icarus;
mod verilator;
mod yosys;

pub use verilator::{LintReport, lint};
pub use yosys::{
    AdderMapping, BlockArea, EP4CE115_LES, SynthOptions, SynthReport, area_markdown, cell_models,
    synthesize, synthesize_rtl, synthesize_with,
};

/// Runs `tool args` in `dir`; maps "not found" to [`HlsError::ToolMissing`].
fn run(tool: &str, package: &str, args: &[String], dir: &Path) -> Result<Output, HlsError> {
    Command::new(tool)
        .args(args)
        .current_dir(dir)
        .output()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                HlsError::ToolMissing {
                    tool: tool.into(),
                    package: package.into(),
                }
            } else {
                HlsError::ToolFailed {
                    tool: tool.into(),
                    message: e.to_string(),
                }
            }
        })
}

fn failure(tool: &str, out: &Output) -> HlsError {
    let mut message = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let tail: Vec<&str> = stdout.lines().rev().take(30).collect();
    message.push_str(&tail.into_iter().rev().collect::<Vec<_>>().join("\n"));
    HlsError::ToolFailed {
        tool: tool.into(),
        message,
    }
}

fn rel_rtl(out_dir: &Path) -> Result<Vec<String>, HlsError> {
    Ok(rtl_files(out_dir)?
        .iter()
        .map(|p| {
            format!(
                "rtl/{}",
                p.file_name().unwrap_or_default().to_string_lossy()
            )
        })
        .collect())
}

/// Which simulator runs the testbench.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Simulator {
    /// Verilator 5 (`--binary --timing`): compiles the design to C++, fast enough for
    /// room-scale designs (the default).
    #[default]
    Verilator,
    /// Icarus Verilog (`iverilog -g2005`, `vvp`): an interpreter, for small designs.
    Icarus,
}

impl Simulator {
    /// Name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Simulator::Verilator => "verilator",
            Simulator::Icarus => "icarus",
        }
    }
}

/// Progress of [`simulate_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimProgress {
    /// Compiling the design and testbench.
    Compiling,
    /// `done` of `total` accelerator runs finished in simulation.
    Runs {
        /// Runs finished.
        done: u64,
        /// Runs in the program.
        total: u64,
    },
}

/// Result of [`simulate`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SimReport {
    /// The simulator used.
    pub simulator: Simulator,
    /// `CYCLES` register read back after the first run.
    pub cycles: u64,
    /// Testbench-measured edges from start to `ins_irq`, per run.
    pub irq_cycles: Vec<u64>,
    /// Testbench edges of the whole bus program.
    pub tb_cycles: u64,
    /// What the formulas predict for the measured counts above (the same as the generator's
    /// [`crate::Report`]).
    #[serde(flatten)]
    pub predicted: CyclePrediction,
    /// Words that differ from the `bt-fixed` model (plus protocol errors).
    pub mismatches: usize,
    /// The first 50 mismatches, described.
    pub mismatch_details: Vec<String>,
    /// Words read and compared.
    pub words_compared: usize,
    /// Accelerator runs (every vector of every step).
    pub vectors: usize,
    /// Time steps loaded.
    pub steps: usize,
    /// The time step of each run (`irq_cycles[i]` is a run of step `run_steps[i]`).
    #[serde(default)]
    pub run_steps: Vec<usize>,
}

impl SimReport {
    /// The measured latency of each step at [`crate::CLOCK_HZ`], seconds: the longest of its
    /// runs' cycles from the start command to the interrupt (= the `CYCLES` register).
    pub fn step_latency_s(&self) -> Vec<f64> {
        let mut worst = vec![0u64; self.steps];
        for (&step, &c) in self.run_steps.iter().zip(&self.irq_cycles) {
            if let Some(w) = worst.get_mut(step) {
                *w = (*w).max(c);
            }
        }
        worst.iter().map(|&c| c as f64 / crate::CLOCK_HZ).collect()
    }

    /// No mismatch, and every run's cycles and the program's edges as predicted.
    pub fn passed(&self) -> bool {
        self.mismatches == 0
            && self.irq_cycles == self.predicted.run_cycles
            && self.tb_cycles == self.predicted.tb_cycles
    }

    /// The predicted `CYCLES` of the first run (what [`SimReport::cycles`] should read).
    pub fn predicted_cycles(&self) -> u64 {
        self.predicted.run_cycles.first().copied().unwrap_or(0)
    }
}

/// [`simulate_with`] Verilator, without progress.
pub fn simulate(out_dir: &Path) -> Result<SimReport, HlsError> {
    simulate_with(out_dir, Simulator::Verilator, &mut |_| {})
}

/// Builds and runs the testbench with `simulator`, then compares every word read with the
/// `bt-fixed` model recomputed from `platform.json` and `work.json`, and the cycle counts
/// with their exact formulas. `progress` hears of the compilation and of every finished run.
pub fn simulate_with(
    out_dir: &Path,
    simulator: Simulator,
    progress: &mut dyn FnMut(SimProgress),
) -> Result<SimReport, HlsError> {
    simulate_sources(out_dir, &rel_rtl(out_dir)?, simulator, progress)
}

/// [`simulate_with`] on the netlist of [`synthesize_with`] (run with
/// [`SynthOptions::netlist`]) instead of the RTL: `synth/netlist.v` with the cell models of
/// [`cell_models`] (written to `synth/cells_sim.v`), the same testbench and the same comparison
/// with the `bt-fixed` model.
pub fn simulate_netlist(
    out_dir: &Path,
    simulator: Simulator,
    progress: &mut dyn FnMut(SimProgress),
) -> Result<SimReport, HlsError> {
    let models = out_dir.join("synth/cells_sim.v");
    std::fs::write(&models, cell_models()?).map_err(io_err(&models))?;
    let sources = [
        "synth/netlist.v".to_string(),
        "synth/cells_sim.v".to_string(),
    ];
    simulate_sources(out_dir, &sources, simulator, progress)
}

/// Builds the testbench with `sources` (relative to `out_dir`) as the design, runs it and
/// compares (see [`simulate_with`]).
fn simulate_sources(
    out_dir: &Path,
    sources: &[String],
    simulator: Simulator,
    progress: &mut dyn FnMut(SimProgress),
) -> Result<SimReport, HlsError> {
    let (ops, runs) = recompute(out_dir)?;
    let tb = out_dir.join("tb");
    let result = tb.join("sim_out.txt");
    let _ = std::fs::remove_file(&result);
    progress(SimProgress::Compiling);
    let total = runs.len() as u64;
    let (exe, args) = match simulator {
        Simulator::Icarus => icarus::compile(out_dir, sources)?,
        Simulator::Verilator => verilator::compile(out_dir, sources)?,
    };
    progress(SimProgress::Runs { done: 0, total });
    run_streaming(&exe, simulator, &args, &tb, &mut |done| {
        progress(SimProgress::Runs { done, total })
    })?;
    let text = std::fs::read_to_string(&result).map_err(io_err(&result))?;
    compare(simulator, &text, &ops, &runs)
}

/// Runs the simulation binary in `dir`, reporting each `P <n>` line of its stdout.
fn run_streaming(
    exe: &str,
    simulator: Simulator,
    args: &[String],
    dir: &Path,
    on_run: &mut dyn FnMut(u64),
) -> Result<(), HlsError> {
    use std::io::BufRead;
    let package = match simulator {
        Simulator::Icarus => "iverilog",
        Simulator::Verilator => "verilator",
    };
    let mut child = Command::new(exe)
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| HlsError::ToolFailed {
            tool: format!("{exe} ({package})"),
            message: e.to_string(),
        })?;
    let mut tail = Vec::new();
    if let Some(stdout) = child.stdout.take() {
        for line in std::io::BufReader::new(stdout).lines() {
            let line = line.map_err(io_err(dir))?;
            match line.strip_prefix("P ").and_then(|n| n.trim().parse().ok()) {
                Some(n) => on_run(n),
                None => {
                    tail.push(line);
                    if tail.len() > 30 {
                        tail.remove(0);
                    }
                }
            }
        }
    }
    let out = child.wait_with_output().map_err(io_err(dir))?;
    if !out.status.success() {
        let mut message = String::from_utf8_lossy(&out.stderr).into_owned();
        message.push_str(&tail.join("\n"));
        return Err(HlsError::ToolFailed {
            tool: exe.to_string(),
            message,
        });
    }
    Ok(())
}

/// Compares the testbench's `sim_out.txt` with the model's expectations.
fn compare(
    simulator: Simulator,
    text: &str,
    ops: &[BusOp],
    runs: &[VectorExpectation],
) -> Result<SimReport, HlsError> {
    let expected: Vec<(u32, u32)> = ops
        .iter()
        .filter_map(|o| match *o {
            BusOp::Read(a, v) => Some((a, v)),
            _ => None,
        })
        .collect();
    let mut report = SimReport {
        simulator,
        cycles: 0,
        irq_cycles: Vec::new(),
        tb_cycles: 0,
        predicted: CyclePrediction::of(ops, runs),
        mismatches: 0,
        mismatch_details: Vec::new(),
        words_compared: 0,
        vectors: runs.len(),
        steps: runs.last().map_or(0, |r| r.step + 1),
        run_steps: runs.iter().map(|r| r.step).collect(),
    };
    let note = |r: &mut SimReport, s: String| {
        r.mismatches += 1;
        if r.mismatch_details.len() < 50 {
            r.mismatch_details.push(s);
        }
    };
    let parse = |s: Option<&str>, radix: u32| -> Result<u64, HlsError> {
        s.and_then(|v| u64::from_str_radix(v, radix).ok())
            .ok_or_else(|| HlsError::Parse {
                what: "sim_out.txt".into(),
                message: format!("bad field {s:?}"),
            })
    };
    // Run index of each read, for the messages.
    let mut run_of_read = Vec::with_capacity(expected.len());
    let mut run = 0usize;
    for o in ops {
        match o {
            BusOp::Start(_) => run += 1,
            BusOp::Read(..) => run_of_read.push(run.saturating_sub(1)),
            BusOp::Write(..) => {}
        }
    }
    let mut reads = 0usize;
    for line in text.lines() {
        let mut f = line.split_whitespace();
        match f.next() {
            Some("R") => {
                let (addr, data) = (parse(f.next(), 16)? as u32, parse(f.next(), 16)? as u32);
                match expected.get(reads) {
                    Some(&(ea, ed)) if ea == addr => {
                        if ed != data {
                            let v = run_of_read[reads];
                            let step = runs.get(v).map_or(0, |r| r.step);
                            note(
                                &mut report,
                                format!(
                                    "run {v} (step {step}) addr 0x{addr:04x}: rtl 0x{data:08x}, model 0x{ed:08x}"
                                ),
                            );
                        }
                        if reads == 0 {
                            report.cycles = data.into();
                        }
                    }
                    other => note(
                        &mut report,
                        format!("read #{reads} at 0x{addr:04x}, expected {other:?}"),
                    ),
                }
                reads += 1;
            }
            Some("C") => report.irq_cycles.push(parse(f.next(), 10)?),
            Some("T") => report.tb_cycles = parse(f.next(), 10)?,
            Some("E") => note(&mut report, format!("testbench: {line}")),
            _ => {}
        }
    }
    report.words_compared = reads;
    if reads != expected.len() {
        note(
            &mut report,
            format!("{reads} words read, {} expected", expected.len()),
        );
    }
    Ok(report)
}
