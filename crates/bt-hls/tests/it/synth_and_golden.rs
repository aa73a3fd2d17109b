//! Golden files, determinism and a synthesis smoke test.

use std::path::PathBuf;

use crate::common::*;
use bt_hls::{HlsInput, PlaneSpec, Platform, StepWork};
use bt_schedule::round_template;

#[test]
fn golden_cycle_count() {
    let g = generated();
    let r = &g.report;
    let pinned = serde_json::json!({
        "instances": r.num_instances,
        "makespans": r.makespans,
        "run_cycles": r.predicted.run_cycles,
        "predicted_tb_cycles": r.predicted.tb_cycles,
        "status_base": r.address_map.status_base,
        "point_base": r.address_map.point_base,
        "sched_base": r.address_map.sched_base,
    });
    golden(
        "small_scene_cycles.json",
        &(serde_json::to_string_pretty(&pinned).unwrap() + "\n"),
    );
}

#[test]
fn generation_is_deterministic() {
    let g = generated();
    let work = [bt_hls::StepWork {
        input: g.input.clone(),
        schedule: g.schedule.clone(),
    }];
    let again = bt_hls::rtl_modules(&bt_hls::Platform::fitting(&work).unwrap()).unwrap();
    for (name, text) in again {
        let on_disk = std::fs::read_to_string(g.dir.join(format!("rtl/{name}.v"))).unwrap();
        assert_eq!(on_disk, text, "{name} differs between two generations");
    }
    assert!(g.report.docs.contains("PATH_STATUS"));
}

#[test]
fn invalid_input_is_reported_not_panicked() {
    let g = generated();
    let mut bad = g.input.clone();
    bad.paths[0] = vec![99];
    assert!(matches!(
        bt_hls::generate(&bad, &g.schedule, &g.dir.join("never")),
        Err(bt_hls::HlsError::InvalidInput { .. } | bt_hls::HlsError::Fixed(_))
    ));
    let mut short = g.schedule.clone();
    short.slots.truncate(1);
    assert!(matches!(
        bt_hls::generate(&g.input, &short, &g.dir.join("never")),
        Err(bt_hls::HlsError::Schedule(_))
    ));
}

/// A tiny scene (tilted wall + floor, 3 paths) keeps the Yosys run short.
pub(crate) fn tiny_scene() -> HlsInput {
    let mut s = small_scene();
    let keep = [0usize, 4];
    s.planes = keep
        .iter()
        .map(|&i| s.planes[i].clone())
        .collect::<Vec<PlaneSpec>>();
    s.paths = vec![vec![0], vec![1], vec![0, 1]];
    s.init_points = vec![
        vec![[0.0, 2.0, 1.5]],
        vec![[2.5, 2.0, 0.0]],
        vec![[0.0, 2.0, 1.5], [2.5, 2.0, 0.0]],
    ];
    s.max_rounds = 8;
    s.test_vectors.clear();
    s
}

#[test]
fn synthesis_reports_cell_counts_and_its_netlist_is_bit_exact() {
    let input = tiny_scene();
    let schedule = round_template(&input.one_round_problem(), &[]).unwrap();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_tiny_scene");
    let _ = std::fs::remove_dir_all(&dir);
    bt_hls::generate(&input, &schedule, &dir).unwrap();
    // Icarus stays an option (`hls sim --simulator icarus`): it runs the same testbench.
    let sim = bt_hls::simulate_with(&dir, bt_hls::Simulator::Icarus, &mut |_| {}).unwrap();
    assert_eq!(sim.mismatches, 0, "{:#?}", sim.mismatch_details);
    assert_eq!(sim.cycles, sim.predicted_cycles());
    assert!(sim.passed());
    let options = bt_hls::SynthOptions {
        netlist: true,
        ..Default::default()
    };
    let synth = bt_hls::synthesize_with(&dir, &options).unwrap();
    eprintln!("tiny scene: {synth:#?}");
    // The mapped netlist (carry chains, M9K, registers) runs the same bus program bit-exactly.
    let gates = bt_hls::simulate_netlist(&dir, bt_hls::Simulator::Icarus, &mut |_| {}).unwrap();
    assert!(gates.passed(), "{:#?}", gates.mismatch_details);
    assert!(gates.words_compared > 0);
    assert!(synth.logic_cells > 100, "{synth:?}");
    assert!(synth.registers > 100, "{synth:?}");
    assert!(synth.percent_of_ep4ce115 > 0.0 && synth.percent_of_ep4ce115 < 100.0);
    // The point memory (three copies of 8 points of three 24-bit words: the room's narrowed
    // coordinate word) is inferred into M9K, not registers. The dispatch memories of this tiny
    // design (job memory 4 x 11 bits, slot buffer 4 x 15, ready queue 4 x 4) are below what
    // the M9K rules take and stay in logic.
    assert!(synth.m9k_blocks > 0, "{synth:?}");
    assert_eq!(input.coord_bits, 24);
    assert_eq!(synth.memory_bits, 3 * 8 * (3 * 24), "{synth:?}");
    per_block_counts_every_instance(&input, &schedule, &dir, &synth);
}

/// The hierarchical run (`--per-block`) of the tiny design: one row per module with its
/// instance count taken from the platform (the shared `bt_pe_core` once per PE), totals that
/// count every instance, and those totals near the flat run's (the hierarchy only forgoes
/// optimisation across the PE ports; counting the core once would lose most of the PEs).
fn per_block_counts_every_instance(
    input: &HlsInput,
    schedule: &bt_schedule::Schedule,
    dir: &std::path::Path,
    flat: &bt_hls::SynthReport,
) {
    let work = [StepWork {
        input: input.clone(),
        schedule: schedule.clone(),
    }];
    let platform = Platform::fitting(&work).unwrap();
    let options = bt_hls::SynthOptions {
        per_block: true,
        ..Default::default()
    };
    let tree = bt_hls::synthesize_with(dir, &options).unwrap();
    let names: Vec<&str> = tree.blocks.iter().map(|b| b.module.as_str()).collect();
    assert_eq!(names[..2], ["bt_top", bt_hls::PE_CORE_MODULE], "{names:?}");
    let pes = platform.instances.len() as u64;
    assert_eq!(tree.blocks[0].instances, 1);
    assert_eq!(tree.blocks[1].instances, pes, "{tree:#?}");
    for b in &tree.blocks[2..] {
        let plane: u32 = b.module.strip_prefix("bt_pe_").unwrap().parse().unwrap();
        let copies = platform
            .instances
            .iter()
            .filter(|i| i.plane == plane)
            .count();
        assert_eq!(b.instances, copies as u64, "{}", b.module);
    }
    let sum = |f: fn(&bt_hls::BlockArea) -> u64| -> u64 {
        tree.blocks.iter().map(|b| b.instances * f(b)).sum()
    };
    assert_eq!(tree.logic_cells, sum(|b| b.logic_cells));
    assert_eq!(tree.registers, sum(|b| b.registers));
    let core = &tree.blocks[1];
    assert!(core.registers * pes > tree.registers / 2, "{tree:#?}");
    let ratio = tree.logic_cells as f64 / flat.logic_cells as f64;
    assert!(
        (0.9..1.2).contains(&ratio),
        "hierarchical {tree:#?} vs flat {flat:#?}"
    );
}

/// Arithmetic the accelerator uses, each output one case of the carry-chain map: unsigned and
/// signed add and subtract, add/subtract chosen at run time, a carry-in signal, comparisons of
/// both signednesses and orders (also against a constant), mixed widths, negation, a sum of
/// shifted terms (zero low bits, as in the CSD networks), a narrow adder left to LUTs and the
/// negation of an unsigned operand into a wider result.
const ARITH_RTL: &str = "module bt_arith (
  input [31:0] a, input [19:0] b, input signed [23:0] sa, input signed [9:0] sb,
  input s, input ci, input [1:0] n2,
  output [32:0] add_u, output [31:0] sub_u, output signed [24:0] add_s, output signed [23:0] sub_s,
  output [31:0] addsub, output [31:0] add_ci, output lt_u, output ge_u, output gt_u, output le_u,
  output lt_s, output ge_s, output gt_s, output le_s, output lt_k, output neg_s_sign,
  output signed [24:0] neg_s, output [39:0] csd, output [31:0] mixed, output [2:0] narrow,
  output [23:0] neg_u
);
  assign add_u = a + b;
  assign sub_u = a - b;
  assign add_s = sa + sb;
  assign sub_s = sa - sb;
  assign addsub = s ? a + b : a - b;
  assign add_ci = a + b + ci;
  assign lt_u = a < b;
  assign ge_u = a >= b;
  assign gt_u = b > a[19:0];
  assign le_u = a[19:0] <= b;
  assign lt_s = sa < sb;
  assign ge_s = sa >= sb;
  assign gt_s = sa > sb;
  assign le_s = sa <= sb;
  assign lt_k = a < 32'd1000;
  assign neg_s_sign = sa < 0;
  assign neg_s = -sa;
  assign csd = (a << 7) + (b << 3) - {a, 8'h80};
  assign mixed = $signed({1'b0, a[30:0]}) + sb;
  assign narrow = n2 + {1'b0, s};
  assign neg_u = -b;
endmodule
";

/// The same ports as one word each way, for the testbench.
const ARITH_IN_BITS: usize = 32 + 20 + 24 + 10 + 1 + 1 + 2;

/// Seeded vectors: corners (zero, all ones, the signed extremes, one) crossed, then random.
fn arith_vectors(random: usize) -> Vec<u128> {
    let fields = [32u32, 20, 24, 10, 1, 1, 2];
    let corners = |w: u32| -> Vec<u128> {
        let all = (1u128 << w) - 1;
        let mut v = vec![0, 1, all, all >> 1, (all >> 1) + 1];
        v.dedup();
        v
    };
    let pack = |vals: &[u128]| -> u128 {
        let mut word = 0u128;
        let mut at = 0;
        for (v, w) in vals.iter().zip(fields) {
            word |= (v & ((1u128 << w) - 1)) << at;
            at += w;
        }
        word
    };
    let mut out = Vec::new();
    for (i, &x) in corners(32).iter().enumerate() {
        for &y in &corners(20) {
            for (j, &z) in corners(24).iter().enumerate() {
                for &w in &corners(10) {
                    let flag = ((i + j) & 1) as u128;
                    out.push(pack(&[x, y, z, w, flag, 1 - flag, (i % 4) as u128]));
                }
            }
        }
    }
    let mut state = 0x9e37_79b9_7f4a_7c15_u64; // splitmix64, seed printed on failure
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for _ in 0..random {
        out.push((u128::from(next()) << 64 | u128::from(next())) & ((1u128 << ARITH_IN_BITS) - 1));
    }
    out
}

/// Testbench: the behavioural module (renamed) and the mapped netlist side by side.
fn arith_testbench(vectors: usize) -> String {
    format!(
        "`timescale 1ns/1ps
module bt_arith_tb;
  reg [{w}:0] mem [0:{last}];
  reg [{w}:0] v;
  wire [311:0] r, n;
  integer i, bad;
  bt_arith_ref ref_ (v[31:0], v[51:32], v[75:52], v[85:76], v[86], v[87], v[89:88],
    r[32:0], r[64:33], r[89:65], r[113:90], r[145:114], r[177:146], r[178], r[179], r[180],
    r[181], r[182], r[183], r[184], r[185], r[186], r[187], r[212:188], r[252:213], r[284:253],
    r[287:285], r[311:288]);
  bt_arith net_ (v[31:0], v[51:32], v[75:52], v[85:76], v[86], v[87], v[89:88],
    n[32:0], n[64:33], n[89:65], n[113:90], n[145:114], n[177:146], n[178], n[179], n[180],
    n[181], n[182], n[183], n[184], n[185], n[186], n[187], n[212:188], n[252:213], n[284:253],
    n[287:285], n[311:288]);
  initial begin
    $readmemh(\"vectors.hex\", mem);
    bad = 0;
    for (i = 0; i <= {last}; i = i + 1) begin
      v = mem[i];
      #1;
      if (r !== n) begin
        bad = bad + 1;
        if (bad <= 10) $display(\"MISMATCH %h: rtl %h netlist %h\", v, r, n);
      end
    end
    $display(\"VECTORS %0d MISMATCHES %0d\", i, bad);
    $finish;
  end
endmodule
",
        w = ARITH_IN_BITS - 1,
        last = vectors - 1
    )
}

#[test]
fn carry_chain_adders_are_bit_exact_and_smaller_than_luts() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_carry_chain");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("rtl")).unwrap();
    std::fs::write(dir.join("rtl/bt_arith.v"), ARITH_RTL).unwrap();
    let files = ["rtl/bt_arith.v".to_string()];
    let luts = bt_hls::synthesize_rtl(
        &dir,
        &files,
        "bt_arith",
        &bt_hls::SynthOptions {
            adders: bt_hls::AdderMapping::Luts,
            ..Default::default()
        },
    )
    .unwrap();
    let chain = bt_hls::synthesize_rtl(
        &dir,
        &files,
        "bt_arith",
        &bt_hls::SynthOptions {
            adders: bt_hls::AdderMapping::CarryChain,
            netlist: true,
            ..Default::default()
        },
    )
    .unwrap();
    eprintln!(
        "bt_arith: {} logic cells with LUT adders, {} on the carry chain",
        luts.logic_cells, chain.logic_cells
    );
    let netlist = std::fs::read_to_string(dir.join("synth/netlist.v")).unwrap();
    let chain_cells = netlist.matches("sum_lutc_input(\"cin\")").count() as u64;
    // Every wide operation is on the chain, and the chain cells are counted as logic cells.
    assert!(chain_cells > 300, "{chain_cells} chain cells");
    assert!(chain.logic_cells >= chain_cells);
    assert!(
        chain.logic_cells < luts.logic_cells,
        "{chain:?} vs {luts:?}"
    );

    let vectors = arith_vectors(1_000);
    let hex: String = vectors.iter().map(|v| format!("{v:023x}\n")).collect();
    std::fs::write(dir.join("vectors.hex"), hex).unwrap();
    std::fs::write(dir.join("tb.v"), arith_testbench(vectors.len())).unwrap();
    std::fs::write(
        dir.join("ref.v"),
        ARITH_RTL.replacen("module bt_arith", "module bt_arith_ref", 1),
    )
    .unwrap();
    std::fs::write(dir.join("cells.v"), bt_hls::cell_models().unwrap()).unwrap();
    let build = std::process::Command::new("iverilog")
        .args([
            "-g2005",
            "-o",
            "tb.vvp",
            "tb.v",
            "ref.v",
            "synth/netlist.v",
            "cells.v",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        build.status.success(),
        "{}",
        String::from_utf8_lossy(&build.stderr)
    );
    let run = std::process::Command::new("vvp")
        .args(["-n", "tb.vvp"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&run.stdout);
    assert!(
        out.contains(&format!("VECTORS {} MISMATCHES 0", vectors.len())),
        "{out}"
    );
}
