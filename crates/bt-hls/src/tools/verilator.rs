//! Verilator 5: lint of every emitted file and the compiled co-simulation binary.

use std::path::Path;

use super::{failure, rel_rtl, run};
use crate::HlsError;
use crate::error::io_err;

/// Result of [`lint`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct LintReport {
    /// Modules linted as top (every generated module, then the testbench).
    pub modules: Vec<String>,
    /// Every `%Warning`/`%Error` line Verilator printed (empty = clean).
    pub warnings: Vec<String>,
}

/// Runs `verilator --lint-only -Wall` with each generated module as top (all RTL files given,
/// so instances resolve), and the testbench with `--timing`.
pub fn lint(out_dir: &Path) -> Result<LintReport, HlsError> {
    let files = rel_rtl(out_dir)?;
    let mut report = LintReport {
        modules: Vec::new(),
        warnings: Vec::new(),
    };
    let mut tops: Vec<(String, Vec<String>)> = files
        .iter()
        .map(|f| {
            let name = Path::new(f)
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            (name, vec![])
        })
        .collect();
    tops.push(("bt_tb".into(), vec!["--timing".into(), "tb/bt_tb.v".into()]));
    for (top, extra) in tops {
        let mut args: Vec<String> = vec![
            "--lint-only".into(),
            "-Wall".into(),
            "--top-module".into(),
            top.clone(),
        ];
        args.extend(files.iter().cloned());
        args.extend(extra);
        let out = run("verilator", "verilator", &args, out_dir)?;
        let text = String::from_utf8_lossy(&out.stderr);
        report.warnings.extend(
            text.lines()
                .filter(|l| l.starts_with("%Warning") || l.starts_with("%Error"))
                .map(|l| format!("{top}: {l}")),
        );
        if !out.status.success() && report.warnings.is_empty() {
            return Err(failure("verilator", &out));
        }
        report.modules.push(top);
    }
    Ok(report)
}

/// Compiles the testbench with `sources` (paths relative to `out_dir`) into
/// `tb/obj_dir/bt_sim`; returns the binary (absolute) and its arguments.
pub(super) fn compile(
    out_dir: &Path,
    sources: &[String],
) -> Result<(String, Vec<String>), HlsError> {
    let mut args: Vec<String> = [
        "--binary",
        "--timing",
        "-Wno-fatal",
        "-Wno-lint",
        "-Wno-style",
        "--top-module",
        "bt_tb",
        "-Mdir",
        "tb/obj_dir",
        "-o",
        "bt_sim",
        "-j",
        "2",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.extend(sources.iter().cloned());
    args.push("tb/bt_tb.v".into());
    let out = run("verilator", "verilator", &args, out_dir)?;
    if !out.status.success() {
        return Err(failure("verilator", &out));
    }
    // Absolute: the binary runs inside `tb/`, where a path relative to the caller's
    // directory (`hls sim hw` gives `hw/tb/obj_dir/bt_sim`) names nothing.
    let exe = out_dir.join("tb/obj_dir/bt_sim");
    let exe = std::path::absolute(&exe).map_err(io_err(&exe))?;
    Ok((exe.display().to_string(), Vec::new()))
}
