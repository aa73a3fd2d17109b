//! Yosys 0.23 `synth_intel -family cycloneive`: cells, registers and M9K bits, per block on
//! request.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use super::{failure, rel_rtl, run};
use crate::HlsError;
use crate::error::io_err;

/// Result of [`synthesize`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SynthReport {
    /// `cycloneive_lcell_comb` cells (4-input LUTs, one per logic element).
    pub logic_cells: u64,
    /// `dffeas` cells (logic-element registers).
    pub registers: u64,
    /// Bits of the memories inferred into M9K blocks (width × depth as written in the RTL).
    pub memory_bits: u64,
    /// M9K blocks (`altsyncram` cells, 9,216 bits each; the EP4CE115 has 432).
    pub m9k_blocks: u64,
    /// 18 × 18 embedded multipliers (`cycloneive_mac_mult` cells, `bt_mul_map.v`; the
    /// EP4CE115 has 266).
    #[serde(default)]
    pub multipliers: u64,
    /// Logic elements estimate `max(logic_cells, registers)` (each LE holds one LUT and one
    /// register; Quartus packing can only add to this) as a percentage of the EP4CE115's 114,480.
    pub percent_of_ep4ce115: f64,
    /// Every cell type and count of the final `stat` (summed over the modules with
    /// [`SynthOptions::per_block`]).
    pub cells: BTreeMap<String, u64>,
    /// One row per module with [`SynthOptions::per_block`] (`bt_top`, then each PE), else empty.
    pub blocks: Vec<BlockArea>,
}

/// Cells of one module of a hierarchical synthesis ([`SynthOptions::per_block`]), per
/// instance: a module's own cells, without those of the modules it instantiates.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct BlockArea {
    /// Module name (`bt_top`: controller, memories, write-back; `bt_pe_core`: the registers,
    /// Algorithm 3 and sequencer every PE holds; `bt_pe_<i>`: plane i's constant networks).
    pub module: String,
    /// Instances in the design (PE copies and the core in every PE count).
    pub instances: u64,
    /// `cycloneive_lcell_comb` cells of one instance.
    pub logic_cells: u64,
    /// `dffeas` cells of one instance.
    pub registers: u64,
    /// `altsyncram` cells (M9K blocks) of one instance.
    pub m9k_blocks: u64,
    /// `cycloneive_mac_mult` cells (18 × 18 multipliers) of one instance.
    #[serde(default)]
    pub multipliers: u64,
}

/// Logic elements of the EP4CE115 (paper's Cyclone IV E device).
pub const EP4CE115_LES: u64 = 114_480;

/// How [`synthesize_with`] builds adders, subtractors and comparisons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AdderMapping {
    /// On the logic elements' carry chain in arithmetic mode, one logic cell per bit, as
    /// Quartus does (`bt_alu_map.v` + `bt_carry_map.v`; the default).
    #[default]
    CarryChain,
    /// Yosys 0.23's own mapping: carry-lookahead logic in plain LUTs, about two cells per bit
    /// (kept to compare with).
    Luts,
}

/// Options of [`synthesize_with`].
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SynthOptions {
    /// How adders are mapped.
    pub adders: AdderMapping,
    /// Also write the mapped netlist to `synth/netlist.v` (Yosys `write_verilog -noattr`;
    /// simulates with the Cyclone IV E cell models, see [`cell_models`]).
    pub netlist: bool,
    /// Keep the module hierarchy (`synth_intel -noflatten`) and report each module's cells in
    /// [`SynthReport::blocks`]; the totals are then their sum, without the optimisations across
    /// a PE's ports that the flat run makes.
    pub per_block: bool,
}

/// [`synthesize_with`] the default options (carry chains, no netlist).
pub fn synthesize(out_dir: &Path) -> Result<SynthReport, HlsError> {
    synthesize_with(out_dir, &SynthOptions::default())
}

/// Runs Yosys `synth_intel -family cycloneive -top bt_top` (the EP4CE115 is a Cyclone IV E)
/// on the generated `rtl/*.v` of `out_dir`, logging to `synth/yosys.log`, and parses the final
/// cell counts.
///
/// Block RAM: synth_intel's own M9K mapping aborts in Yosys 0.23 ("Can't find object for
/// defparam `INIT`": its techmap module declares no `INIT` parameter, so every memory fails, and
/// it would also tie the write data to the read port). The script therefore maps memories with
/// this crate's rules (`bt_m9k.txt`: simple dual-port M9K, no initial contents) onto
/// `altsyncram` cells where synth_intel's `map_bram` step would, then resumes at `map_ffram`.
/// Adders: see [`AdderMapping`].
/// The "Area" section of `report.md` is replaced by this run's ([`area_markdown`]).
pub fn synthesize_with(out_dir: &Path, options: &SynthOptions) -> Result<SynthReport, HlsError> {
    let report = synthesize_rtl(out_dir, &rel_rtl(out_dir)?, "bt_top", options)?;
    let path = out_dir.join("report.md");
    let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
    let kept = text.split("\n## Area (Yosys").next().unwrap_or_default();
    let md = format!("{}\n\n{}", kept.trim_end(), area_markdown(&report, options));
    bt_output::write_atomic(&path, md.as_bytes())?;
    Ok(report)
}

/// The flow of [`synthesize_with`] on any Verilog `files` (relative to `work_dir`) with top
/// module `top`: writes `work_dir/synth/` (maps, `yosys.log`, `stat.txt`, optionally
/// `netlist.v`). Used on the generated design and, by the tests, on small arithmetic modules.
pub fn synthesize_rtl(
    work_dir: &Path,
    files: &[String],
    top: &str,
    options: &SynthOptions,
) -> Result<SynthReport, HlsError> {
    let synth = work_dir.join("synth");
    std::fs::create_dir_all(&synth).map_err(io_err(&synth))?;
    for (name, text) in [
        ("bt_m9k.txt", include_str!("../bt_m9k.txt")),
        ("bt_m9k_map.v", include_str!("../bt_m9k_map.v")),
        ("bt_alu_map.v", include_str!("../bt_alu_map.v")),
        ("bt_carry_map.v", include_str!("../bt_carry_map.v")),
        ("bt_mul_map.v", include_str!("../bt_mul_map.v")),
        ("bt_cells_sim.v", include_str!("../bt_cells_sim.v")),
    ] {
        let path = synth.join(name);
        std::fs::write(&path, text).map_err(io_err(&path))?;
    }
    let script = yosys_script(files, top, options);
    let out = run(
        "yosys",
        "yosys",
        &[
            "-q".into(),
            "-l".into(),
            "synth/yosys.log".into(),
            "-p".into(),
            script,
        ],
        work_dir,
    )?;
    if !out.status.success() {
        return Err(failure("yosys", &out));
    }
    let stat_path = synth.join("stat.txt");
    let stat = std::fs::read_to_string(&stat_path).map_err(io_err(&stat_path))?;
    let log_path = synth.join("yosys.log");
    let log = std::fs::read_to_string(&log_path).map_err(io_err(&log_path))?;
    if !options.per_block {
        return Ok(synth_report(parse_stat(&stat), parse_bram_bits(&log)));
    }
    let modules = parse_module_stats(&stat);
    let is_module = |k: &str| modules.iter().any(|(name, _)| name == k);
    let mut cells = BTreeMap::new();
    let mut blocks = Vec::new();
    for (module, m) in &modules {
        let instances = instance_count(&modules, top, module);
        for (k, v) in m.iter().filter(|(k, _)| !is_module(k)) {
            *cells.entry(k.clone()).or_insert(0) += v * instances;
        }
        let r = synth_report(m.clone(), 0);
        blocks.push(BlockArea {
            module: module.clone(),
            instances,
            logic_cells: r.logic_cells,
            registers: r.registers,
            m9k_blocks: r.m9k_blocks,
            multipliers: r.multipliers,
        });
    }
    let mut report = synth_report(cells, parse_bram_bits(&log));
    report.blocks = blocks;
    Ok(report)
}

/// How many times `module` is instantiated below `top` in a hierarchical `stat` (`top`
/// itself: once): a module's section lists the modules it instantiates among its cells.
fn instance_count(modules: &[(String, BTreeMap<String, u64>)], top: &str, module: &str) -> u64 {
    if module == top {
        return 1;
    }
    modules
        .iter()
        .filter_map(|(parent, cells)| {
            let n = cells.get(module)?;
            Some(n * instance_count(modules, top, parent))
        })
        .sum()
}

/// Each module's section (`=== name ===`) of a hierarchical `stat`, `bt_top` first.
fn parse_module_stats(stat: &str) -> Vec<(String, BTreeMap<String, u64>)> {
    let mut out: Vec<(String, BTreeMap<String, u64>)> = stat
        .split("=== ")
        .skip(1)
        .filter_map(|section| {
            let (name, body) = section.split_once(" ===")?;
            (name != "design hierarchy").then(|| (name.to_string(), parse_stat(body)))
        })
        .collect();
    // bt_top, the PEs' core, then the PEs in plane order (bt_pe_2 before bt_pe_10).
    out.sort_by_key(|(name, _)| {
        (
            name != "bt_top",
            name != crate::PE_CORE_MODULE,
            name.len(),
            name.clone(),
        )
    });
    out
}

/// The "Area" section `hls synth` writes into a generated directory's `report.md`: totals
/// and, with [`SynthOptions::per_block`], one row per module.
pub fn area_markdown(r: &SynthReport, options: &SynthOptions) -> String {
    let adders = match options.adders {
        AdderMapping::CarryChain => "adders on the carry chain",
        AdderMapping::Luts => "adders in LUTs",
    };
    let flat = if options.per_block {
        "hierarchy kept"
    } else {
        "flattened"
    };
    let mut md = format!(
        "## Area (Yosys synth_intel -family cycloneive, {adders}, {flat})\n\n\
         * logic cells {}, registers {}, M9K blocks {} ({} memory bits), 18 x 18 multipliers {} (of {})\n\
         * {:.1} % of the EP4CE115 (max(logic cells, registers) / {EP4CE115_LES})\n",
        r.logic_cells,
        r.registers,
        r.m9k_blocks,
        r.memory_bits,
        r.multipliers,
        crate::EP4CE115_MULTIPLIERS,
        r.percent_of_ep4ce115
    );
    if !r.blocks.is_empty() {
        md.push_str(
            "\n| block | instances | logic cells (each) | registers (each) | M9K (each) | multipliers (each) | share of logic cells |\n\
             |---|---:|---:|---:|---:|---:|---:|\n",
        );
        for b in &r.blocks {
            let all = b.logic_cells * b.instances;
            let share = 100.0 * all as f64 / r.logic_cells.max(1) as f64;
            md.push_str(&format!(
                "| `{}` | {} | {} | {} | {} | {} | {share:.1} % |\n",
                b.module, b.instances, b.logic_cells, b.registers, b.m9k_blocks, b.multipliers
            ));
        }
    }
    md
}

/// The Yosys script: synth_intel's steps, with its `coarse` step spelled out (Yosys 0.23's
/// `synth -run coarse`) so that `bt_alu_map.v` runs before `alumacc`, the M9K mapping in place
/// of `map_bram`, and `bt_carry_map.v` before the generic `techmap` of `map_ffram`;
/// `bt_mul_map.v` maps products of at most 18 × 18 bits onto the embedded multipliers (Yosys
/// 0.23's synth_intel has no DSP step) before `alumacc` would turn them into `$macc`. The cell
/// models of `bt_cells_sim.v`, read as blackboxes after synth_intel's `begin`, replace Yosys
/// 0.23's `altsyncram` blackbox, whose fixed 8-bit addresses and 36-bit data cut every wider
/// M9K address in the netlist ("Resizing cell port ... address_a from 13 bits to 8 bits").
fn yosys_script(files: &[String], top: &str, options: &SynthOptions) -> String {
    let chain = options.adders == AdderMapping::CarryChain;
    let hierarchy = if options.per_block { " -noflatten" } else { "" };
    let synth_intel = format!("synth_intel -family cycloneive -top {top}{hierarchy}");
    let mut steps = vec![
        format!("read_verilog {}", files.join(" ")),
        format!("{synth_intel} -run :coarse"),
        "read_verilog -lib synth/bt_cells_sim.v".to_string(),
        "proc; opt_expr; opt_clean; check; opt -nodffe -nosdff; fsm; opt; wreduce; peepopt; \
         opt_clean"
            .to_string(),
    ];
    // Products up to 18 x 18 onto the embedded multipliers, before alumacc makes them `$macc`.
    steps.push("techmap -map synth/bt_mul_map.v".into());
    if chain {
        steps.push("techmap -map synth/bt_alu_map.v".into());
    }
    steps.push("alumacc; share; opt; memory -nomap; opt_clean".into());
    steps.push("memory_bram -rules synth/bt_m9k.txt; techmap -map synth/bt_m9k_map.v".into());
    if chain {
        steps.push("techmap -map synth/bt_carry_map.v".into());
    }
    steps.push(format!("{synth_intel} -run map_ffram:"));
    steps.push("tee -o synth/stat.txt stat".into());
    if options.netlist {
        steps.push("write_verilog -noattr synth/netlist.v".into());
    }
    steps.join("; ")
}

/// Totals of a final `stat` and the bits mapped into M9K.
fn synth_report(cells: BTreeMap<String, u64>, memory_bits: u64) -> SynthReport {
    let count = |suffix: &str| {
        cells
            .iter()
            .filter(|(k, _)| k.ends_with(suffix))
            .map(|(_, v)| v)
            .sum::<u64>()
    };
    let logic_cells = count("lcell_comb");
    let registers = count("dffeas");
    SynthReport {
        logic_cells,
        registers,
        memory_bits,
        m9k_blocks: count("altsyncram"),
        multipliers: count("cycloneive_mac_mult"),
        percent_of_ep4ce115: 100.0 * logic_cells.max(registers) as f64 / EP4CE115_LES as f64,
        cells,
        blocks: Vec::new(),
    }
}

/// Simulation models of a netlist from [`synthesize_rtl`]: `cycloneive_lcell_comb` from
/// Yosys's `intel/cycloneive/cells_sim.v` (found through `yosys-config --datdir`, else in
/// `/usr/share/yosys`) with one fix, and this crate's `dffeas`, `altsyncram` and multiplier
/// cells (`cycloneive_mac_mult`, `cycloneive_mac_out`)
/// (`bt_cells_sim.v`). Yosys 0.23's `cycloneive_lcell_comb` never drives its internal `cin_w`,
/// so every carry-chain cell would simulate as X (the fix adds `assign cin_w = cin;`); its
/// `dffeas` ignores the clock enable and the clear, and it has no `altsyncram` model.
pub fn cell_models() -> Result<String, HlsError> {
    let datdir = Command::new("yosys-config")
        .arg("--datdir")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "/usr/share/yosys".into());
    let path = Path::new(&datdir).join("intel/cycloneive/cells_sim.v");
    let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
    let missing = |what: &str| HlsError::Parse {
        what: path.display().to_string(),
        message: format!("no `{what}` in cycloneive_lcell_comb"),
    };
    let (begin, end) = ("module cycloneive_lcell_comb", "endmodule");
    let from = text.find(begin).ok_or_else(|| missing(begin))?;
    let to = from + text[from..].find(end).ok_or_else(|| missing(end))? + end.len();
    let mut lcell = text[from..to].to_string();
    let anchor = "assign datad_w = datad;";
    if !lcell.contains("assign cin_w") {
        if !lcell.contains(anchor) {
            return Err(missing(anchor));
        }
        lcell = lcell.replacen(anchor, &format!("{anchor}\n   assign cin_w = cin;"), 1);
    }
    Ok(format!("{lcell}\n\n{}", include_str!("../bt_cells_sim.v")))
}

/// Bits (`Properties: ... bits=N`) of every memory that `memory_bram` mapped onto
/// `$__BT_M9K_SDP` cells, from the Yosys log.
fn parse_bram_bits(log: &str) -> u64 {
    let mut total = 0;
    let mut current: Option<u64> = None;
    let mut mapped = false;
    let mut flush = |bits: Option<u64>, mapped: bool| {
        if mapped {
            total += bits.unwrap_or(0);
        }
    };
    for line in log.lines() {
        let l = line.trim_start();
        if l.starts_with("Processing ") && l.ends_with(':') {
            flush(current.take(), mapped);
            mapped = false;
        } else if let Some(rest) = l.strip_prefix("Properties:") {
            current = rest
                .split_whitespace()
                .find_map(|f| f.strip_prefix("bits=")?.parse().ok());
        } else if l.starts_with("Creating $__BT_M9K_SDP cell") {
            mapped = true;
        } else if l.starts_with("Executing") || l.contains(". Executing ") {
            flush(current.take(), mapped);
            mapped = false;
        }
    }
    flush(current, mapped);
    total
}

/// Cell lines of a Yosys `stat` ("     <type>   <count>") after "Number of cells".
fn parse_stat(stat: &str) -> BTreeMap<String, u64> {
    let mut cells = BTreeMap::new();
    let mut in_cells = false;
    for line in stat.lines() {
        if line.contains("Number of cells") {
            in_cells = true;
            continue;
        }
        if in_cells {
            let f: Vec<&str> = line.split_whitespace().collect();
            match f.as_slice() {
                [name, n] => {
                    if let Ok(n) = n.parse::<u64>() {
                        *cells.entry((*name).to_string()).or_insert(0) += n;
                    }
                }
                [] => {}
                _ => in_cells = false,
            }
        }
    }
    cells
}

#[cfg(test)]
mod tests {
    #[test]
    fn parses_yosys_stat() {
        let stat = "=== bt_top ===\n\n   Number of wires: 10\n   Number of cells:   7\n     cycloneive_lcell_comb    5\n     dffeas    2\n\n";
        let c = super::parse_stat(stat);
        assert_eq!(c["cycloneive_lcell_comb"], 5);
        assert_eq!(c["dffeas"], 2);
    }

    #[test]
    fn parses_each_module_of_a_hierarchical_stat() {
        let stat = "=== bt_pe_0 ===\n   Number of cells:   3\n     cycloneive_lcell_comb    2\n     dffeas    1\n\n=== bt_top ===\n   Number of cells:   4\n     bt_pe_0    1\n     cycloneive_lcell_comb    3\n\n=== design hierarchy ===\n   Number of cells:   7\n     cycloneive_lcell_comb    5\n";
        let m = super::parse_module_stats(stat);
        let names: Vec<&str> = m.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["bt_top", "bt_pe_0"]);
        assert_eq!(m[0].1["cycloneive_lcell_comb"], 3);
        assert_eq!(m[1].1["dffeas"], 1);
    }

    #[test]
    fn counts_instances_through_the_hierarchy() {
        // bt_top holds PE 0 twice (a copy) and PE 10 once; every PE holds one core.
        let stat = "=== bt_pe_10 ===\n   Number of cells:   2\n     bt_pe_core    1\n     cycloneive_lcell_comb    1\n\n\
                    === bt_pe_0 ===\n   Number of cells:   2\n     bt_pe_core    1\n     cycloneive_lcell_comb    1\n\n\
                    === bt_pe_core ===\n   Number of cells:   5\n     cycloneive_lcell_comb    4\n     dffeas    1\n\n\
                    === bt_top ===\n   Number of cells:   4\n     bt_pe_0    2\n     bt_pe_10    1\n     dffeas    1\n\n";
        let m = super::parse_module_stats(stat);
        let names: Vec<&str> = m.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["bt_top", "bt_pe_core", "bt_pe_0", "bt_pe_10"]);
        let count = |name| super::instance_count(&m, "bt_top", name);
        assert_eq!(
            [
                count("bt_top"),
                count("bt_pe_core"),
                count("bt_pe_0"),
                count("bt_pe_10")
            ],
            [1, 3, 2, 1]
        );
    }

    #[test]
    fn counts_bits_of_memories_mapped_to_m9k() {
        let log = "23. Executing MEMORY_BRAM pass.\nProcessing bt_top.rom:\n  Properties: ports=1 bits=160 rports=1\n    rejected\nProcessing bt_top.pm_a:\n  Properties: ports=2 bits=7680 rports=1\n      Creating $__BT_M9K_SDP cell at grid position <0 0 0>: pm_a.0.0.0\n24. Executing TECHMAP pass.\n";
        assert_eq!(super::parse_bram_bits(log), 7680);
    }
}
