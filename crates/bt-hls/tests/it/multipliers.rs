//! The tilted wall's products on the Cyclone IV E's 18 x 18 multipliers: the PE built with
//! multipliers, synthesised (`bt_mul_map.v`) and simulated as a netlist with the multiplier
//! cell models, gives every cycle the same bits as the same PE built with CSD networks (RTL),
//! on random operands through all four uses of each network.

use std::path::PathBuf;

use bt_hls::{Platform, StepWork};
use bt_schedule::round_template;

use crate::synth_and_golden::tiny_scene;

/// Random loads and starts on both PEs, outputs compared on every cycle.
fn testbench(point_bits: u32, sum_bits: u32, latency: u32, runs: u32) -> String {
    format!(
        "`timescale 1ns/1ps
module bt_pe_tb;
  reg clk = 0, rst_n = 0, load = 0, start = 0;
  reg [{pw}:0] s_prev, s_next;
  wire [{sw}:0] sum_ref, sum_net;
  wire zero_ref, zero_net;
  integer i, k, bad, seed;
  ref_pe_0 ref_ (clk, rst_n, load, start, s_prev, s_next, sum_ref, zero_ref);
  bt_pe_0 net_ (clk, rst_n, load, start, s_prev, s_next, sum_net, zero_net);
  always #5 clk = !clk;
  always @(negedge clk) if (rst_n && i > 0 && (sum_ref !== sum_net || zero_ref !== zero_net)) begin
    bad = bad + 1;
    if (bad <= 10) $display(\"MISMATCH %h %h: csd %h multipliers %h\", s_prev, s_next, sum_ref, sum_net);
  end
  initial begin
    bad = 0;
    seed = 32;
    s_prev = 0;
    s_next = 0;
    @(posedge clk); @(posedge clk); #1 rst_n = 1;
    for (i = 0; i < {runs}; i = i + 1) begin
      for (k = 0; k < {pw} + 1; k = k + 32) begin
        s_prev = {{s_prev, $random(seed)}};
        s_next = {{s_next, $random(seed)}};
      end
      if (i % 4 == 0) s_next = s_prev;
      #1 load = 1; @(posedge clk); #1 load = 0; start = 1; @(posedge clk); #1 start = 0;
      for (k = 0; k < {latency}; k = k + 1) @(posedge clk);
    end
    $display(\"RUNS %0d MISMATCHES %0d\", i, bad); $finish;
  end
endmodule
",
        pw = point_bits - 1,
        sw = sum_bits - 1,
    )
}

#[test]
fn products_on_multipliers_equal_the_csd_networks_bit_for_bit() {
    let input = tiny_scene();
    let schedule = round_template(&input.one_round_problem(), &[]).unwrap();
    let work = [StepWork {
        input: input.clone(),
        schedule,
    }];
    let fitting = Platform::fitting(&work).unwrap();
    assert_eq!(fitting.multiplier_budget, bt_hls::EP4CE115_MULTIPLIERS);
    let csd = bt_hls::rtl_modules(&Platform {
        multiplier_budget: 0,
        ..fitting.clone()
    })
    .unwrap();
    let mul = bt_hls::rtl_modules(&fitting).unwrap();
    let text = |m: &[(String, String)], name: &str| -> String {
        m.iter().find(|(n, _)| n == name).unwrap().1.clone()
    };
    // The tilted wall (plane 0, x and y components of 8 and 11 CSD digits) takes multipliers,
    // the floor's one-digit network stays.
    assert!(text(&mul, "bt_pe_0").contains("pp_x_0_0"));
    assert!(!text(&csd, "bt_pe_0").contains("pp_"));
    assert!(!text(&mul, "bt_pe_1").contains("pp_"));
    assert_eq!(text(&mul, "bt_pe_core"), text(&csd, "bt_pe_core"));

    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bt_hls_multipliers");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("rtl")).unwrap();
    for name in ["bt_pe_0", "bt_pe_core"] {
        std::fs::write(dir.join(format!("rtl/{name}.v")), text(&mul, name)).unwrap();
    }
    let files = ["rtl/bt_pe_0.v".to_string(), "rtl/bt_pe_core.v".to_string()];
    let options = bt_hls::SynthOptions {
        netlist: true,
        ..Default::default()
    };
    let synth = bt_hls::synthesize_rtl(&dir, &files, "bt_pe_0", &options).unwrap();
    let csd_synth = {
        let d = dir.join("csd");
        std::fs::create_dir_all(d.join("rtl")).unwrap();
        for name in ["bt_pe_0", "bt_pe_core"] {
            std::fs::write(d.join(format!("rtl/{name}.v")), text(&csd, name)).unwrap();
        }
        bt_hls::synthesize_rtl(&d, &files, "bt_pe_0", &Default::default()).unwrap()
    };
    eprintln!(
        "tilted PE: {} cells, {} multipliers; with CSD networks {} cells",
        synth.logic_cells, synth.multipliers, csd_synth.logic_cells
    );
    // Two networks of a 32-bit coefficient on a 24-bit coordinate's 22-bit input: 2 x 2
    // blocks each.
    assert_eq!(synth.multipliers, 8, "{synth:#?}");
    assert_eq!(csd_synth.multipliers, 0);
    assert!(synth.logic_cells < csd_synth.logic_cells);

    let reference = text(&csd, "bt_pe_0").replace("bt_pe_core", "ref_pe_core");
    let reference = reference.replacen("module bt_pe_0", "module ref_pe_0", 1);
    let core = text(&csd, "bt_pe_core").replacen("module bt_pe_core", "module ref_pe_core", 1);
    std::fs::write(dir.join("ref.v"), format!("{reference}\n{core}")).unwrap();
    let latency = input.pe_latency();
    let wd = bt_fixed::Widths::for_coord(input.coord_bits);
    std::fs::write(dir.join("cells.v"), bt_hls::cell_models().unwrap()).unwrap();
    let bench = |runs: u32| {
        testbench(
            bt_hls::point_bits(wd),
            bt_hls::sum_bits(wd),
            latency + 2,
            runs,
        )
    };
    // The split into 18 x 18 products in RTL, on many operands (Icarus runs the RTL fast) ...
    let rtl = ["rtl/bt_pe_0.v", "rtl/bt_pe_core.v"];
    assert_eq!(
        simulate(&dir, &bench(1_000), &rtl),
        "RUNS 1000 MISMATCHES 0"
    );
    // ... and the netlist with the multiplier cells (about a second a run in Icarus).
    let netlist = ["synth/netlist.v", "cells.v"];
    assert_eq!(simulate(&dir, &bench(20), &netlist), "RUNS 20 MISMATCHES 0");
}

/// Runs `tb` (Icarus) against `ref.v` and `dut` in `dir`; returns its last line.
fn simulate(dir: &std::path::Path, tb: &str, dut: &[&str]) -> String {
    std::fs::write(dir.join("tb.v"), tb).unwrap();
    let build = std::process::Command::new("iverilog")
        .args(["-g2005", "-o", "tb.vvp", "tb.v", "ref.v"])
        .args(dut)
        .current_dir(dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&build.stderr);
    assert!(build.status.success(), "{stderr}");
    let run = std::process::Command::new("vvp")
        .args(["-n", "tb.vvp"])
        .current_dir(dir)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&run.stdout);
    eprintln!("{out}");
    out.lines().last().unwrap_or_default().to_string()
}
