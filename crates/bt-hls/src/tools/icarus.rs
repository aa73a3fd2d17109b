//! Icarus Verilog (`iverilog -g2005`, `vvp`): the interpreter for small designs.

use std::path::Path;

use super::{failure, run};
use crate::HlsError;

/// Compiles the testbench with `sources` (paths relative to `out_dir`) into `tb/sim.vvp`;
/// returns the program and arguments that run it inside `tb/`.
pub(super) fn compile(
    out_dir: &Path,
    sources: &[String],
) -> Result<(String, Vec<String>), HlsError> {
    let mut args: Vec<String> = vec![
        "-g2005".into(),
        "-o".into(),
        "tb/sim.vvp".into(),
        "-s".into(),
        "bt_tb".into(),
    ];
    args.extend(sources.iter().cloned());
    args.push("tb/bt_tb.v".into());
    let out = run("iverilog", "iverilog", &args, out_dir)?;
    if !out.status.success() {
        return Err(failure("iverilog", &out));
    }
    Ok((
        "vvp".to_string(),
        vec!["-n".to_string(), "sim.vvp".to_string()],
    ))
}
