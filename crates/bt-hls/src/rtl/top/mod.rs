//! `bt_top`: PE matrix, job memory, ready queue and dispatcher, slot buffer, coordinate
//! updater-buffer, convergence flags and the Avalon-MM slave. Twin of
//! `bt_fixed::FixedIpc::run_fixed` with each path's own stop (no budgets), and of
//! `crate::dispatch::predict` cycle for cycle.

use crate::input::{Layout, bits_for, pe_latency, sched_entry_bits};
use crate::rtl::pe::{pe_module_name, point_bits, port, sext_slice, sum_bits};
use crate::rtl::verilog::{BinaryOp, Direction, Expr, Item, Module, Signal, Stmt, UnaryOp};

mod bus;
mod controller;
mod updater;
mod writeback;

use bus::*;
use controller::*;
use updater::*;
use writeback::*;

/// FSM state encodings.
const S_IDLE: u128 = 0;
const S_DISP: u128 = 1;
const S_LOAD: u128 = 2;
const S_EXEC: u128 = 3;
const S_WB: u128 = 4;
const STATE_BITS: u32 = 3;

/// Register-map version reported in `INFO[15:8]`.
pub const MAP_VERSION: u32 = 6;

fn nb(l: Expr, r: Expr) -> Stmt {
    Stmt::NonBlocking(l, r)
}
fn id(n: &str) -> Expr {
    Expr::id(n)
}
fn lit(w: u32, v: u128) -> Expr {
    Expr::lit(w, v)
}
fn state_is(s: u128) -> Expr {
    id("state").eq(lit(STATE_BITS, s))
}
fn dstate_is(s: u128) -> Expr {
    id("dstate").eq(lit(DSTATE_BITS, s))
}
fn or(a: Expr, b: Expr) -> Expr {
    Expr::bin(BinaryOp::Or, a, b)
}
/// The per-axis `terms` or-ed left to right, `(a | b) | c ...` (at least one per axis).
fn or_all(terms: Vec<Expr>) -> Expr {
    terms.into_iter().reduce(or).expect("a term per axis")
}

/// The platform-derived sizes `bt_top` is built from.
pub(crate) struct TopParams<'a> {
    pub platform: &'a crate::Platform,
    pub model: &'a bt_fixed::FixedIpc,
    pub layout: Layout,
}

impl<'a> TopParams<'a> {
    pub fn of(
        platform: &'a crate::Platform,
        model: &'a bt_fixed::FixedIpc,
    ) -> Result<Self, crate::HlsError> {
        Ok(TopParams {
            platform,
            model,
            layout: Layout::of(platform)?,
        })
    }
}

/// How many bits of a 32-bit millimetre bus word a fine coordinate of widths `wd` keeps.
fn mm_width(wd: bt_fixed::Widths) -> u32 {
    (wd.coord - bt_fixed::POINT_FRAC).min(32)
}

/// The low bits of the 32-bit millimetre bus word `name` that a fine coordinate of the
/// design's width keeps above its 8 fraction bits (all 32 in the full 40-bit design; the host
/// writes only values that fit, [`bt_fixed::FixedIpc::check_terminal`]).
fn mm_bits(name: &str, wd: bt_fixed::Widths) -> Expr {
    let keep = mm_width(wd);
    if keep >= 32 {
        id(name)
    } else {
        Expr::slice(name, keep - 1, 0)
    }
}

/// `name` (`from` bits) as an `to`-bit unsigned value: zero-extended or truncated.
fn zero_extend(name: &str, from: u32, to: u32) -> Expr {
    match from.cmp(&to) {
        std::cmp::Ordering::Less => Expr::concat(vec![lit(to - from, 0), id(name)]),
        std::cmp::Ordering::Equal => id(name),
        std::cmp::Ordering::Greater => Expr::slice(name, to - 1, 0),
    }
}

/// The sizes every block of `bt_top` is built from, derived once from the layout.
struct Dims<'a> {
    /// The platform, its model and layout.
    p: &'a TopParams<'a>,
    /// PE instances.
    k: u32,
    /// Path, point, instance, slot and schedule-entry address bits.
    pb: u32,
    ptb: u32,
    ib: u32,
    eb: u32,
    /// Path slots (`2^pb`): the width of the per-path flag vectors.
    np2: u32,
    /// Width of the step counter `cnt`.
    cnt_bits: u32,
    /// Word address bits of the Avalon-MM slave.
    ab: u32,
    /// Early stopping rule and the widened box of every plane, when enabled.
    early: Option<(bt_fixed::EarlyStop, Vec<bt_fixed::FineBox>)>,
    /// Datapath widths (the model's coordinate word).
    wd: bt_fixed::Widths,
}

impl<'a> Dims<'a> {
    /// Cycles of one PE evaluation in this design.
    fn latency(&self) -> u32 {
        pe_latency(self.wd.coord)
    }

    fn of(p: &'a TopParams<'a>) -> Self {
        let l = &p.layout;
        Dims {
            p,
            k: l.num_instances,
            pb: l.path_bits,
            ptb: l.point_bits,
            ib: l.inst_bits,
            eb: l.entry_bits,
            np2: 1u32 << l.path_bits,
            cnt_bits: bits_for(
                u64::from((l.num_instances + 2).max(pe_latency(p.model.coord_bits()))) + 1,
            ),
            ab: l.address_bits,
            early: p.model.early_stop().map(|(s, b)| (*s, b.to_vec())),
            wd: bt_fixed::Widths::for_coord(p.model.coord_bits()),
        }
    }
}

/// The per-instance wires of the PE matrix.
struct PeWires {
    /// `pe_load_<j>`: latch the broadcast operands.
    load: Signal,
    /// `pe_start_<j>`: start the evaluation (the cycle after the PE's own load).
    start: Signal,
    /// `pe_sum_<j>`: the unsaturated result.
    sum: Signal,
    /// `pe_zs_<j>`: zero distance sum (degenerate path).
    zs: Signal,
}

/// Header comment, the controller's registers, the per-path flag vectors, the `rounds` and
/// point memories and the PE wires. All state is declared first, as the golden files show it.
fn declare_state(t: &Dims<'_>, items: &mut Vec<Item>) -> Vec<PeWires> {
    let (k, pb, ptb, ib, eb, np2) = (t.k, t.pb, t.ptb, t.ib, t.eb, t.np2);
    let cap = t.p.platform.capacity;
    items.push(Item::Comment(format!(
        "{} PE instances, capacity {} paths, {} points, {} groups; load (jobs, or jobs + 2 after a dispatch wait) + max({} - jobs - 1, 1, dispatch + 1 - load) + write-back (jobs + 2) cycles per slot (each PE starts after its own load), threshold {} fine LSB",
        k,
        cap.paths,
        cap.points,
        cap.slots,
        t.latency(),
        t.p.platform.threshold_lsb
    )));
    for (n, w) in [
        ("state", STATE_BITS),
        ("cnt", t.cnt_bits),
        ("paths_r", pb + 1),
        ("cap_r", 16),
        ("rsel", 1),
        ("slen_0", ib + 1),
        ("slen_1", ib + 1),
        ("cycles", 32),
        ("done", 1),
        ("tx_x", 32),
        ("tx_y", 32),
        ("tx_z", 32),
        ("rx_x", 32),
        ("rx_y", 32),
        ("rx_z", 32),
        ("st_x", mm_width(t.wd)),
        ("st_y", mm_width(t.wd)),
        ("st_z", mm_width(t.wd)),
        ("cur", np2),
        ("conv", np2),
        ("dz", np2),
        ("ov", np2),
        ("pbig", np2),
        ("pdz", np2),
        ("pov", np2),
        ("rd_a", point_bits(t.wd)),
        ("rd_b", point_bits(t.wd)),
        ("sched_q", sched_entry_bits(pb, ptb, ib) + 2 * eb),
        ("sq_ok", 1),
        ("sq_tail", 1),
        ("sq_ld", 1),
        ("ld_q_en", 1),
        ("ld_q_tail", 1),
        ("ld_q_first", 1),
        ("ld_q_last", 1),
        ("ld_q_inst", ib),
        ("ld_go", 1),
        ("ld_go_inst", ib),
        ("wb_q_en", 1),
        ("wb_q_tail", 1),
        ("wb_q_end", 1),
        ("wb_q_path", pb),
        ("wb_q_point", ptb),
        ("wb_q_inst", ib),
        ("wb_q_gtail", 1),
        ("wb_q_src", eb),
        ("wb_q_gbase", eb),
        ("rq_valid", 1),
        ("rq_kind", 2),
        ("rq_reg", 4),
        ("rq_word", 2),
        ("rq_path", pb),
        ("rounds_q", 16),
        ("rvalid", np2),
    ] {
        items.push(Item::Reg(n.into(), w));
    }
    declare_dispatch_state(t, items);
    let sw = sched_entry_bits(pb, ptb, ib);
    if sw > 32 {
        // Entries wider than the bus word: the host writes their high bits first.
        items.push(Item::Reg("sched_hi".into(), sw - 32));
    }
    if t.early.is_some() {
        items.push(Item::Reg("lb".into(), np2));
        items.push(Item::Reg("plb".into(), np2));
    }
    // Rounds per path in a RAM (M9K), not 16 registers a path: `rvalid` marks the paths that
    // committed a round since the start (the RAM cannot be cleared in one cycle).
    items.push(Item::Memory("rounds".into(), 16, np2));
    // Two copies of the point memory (one per read port, both written): each is a plain
    // 1-write 1-read array with a registered read, which Yosys maps to M9K blocks.
    let depth = 1u32 << (ptb + 1);
    items.push(Item::Memory("pm_a".into(), point_bits(t.wd), depth));
    items.push(Item::Memory("pm_b".into(), point_bits(t.wd), depth));
    (0..k)
        .map(|j| PeWires {
            load: Signal::wire(items, format!("pe_load_{j}"), 1),
            start: Signal::wire(items, format!("pe_start_{j}"), 1),
            sum: Signal::wire(items, format!("pe_sum_{j}"), sum_bits(t.wd)),
            zs: Signal::wire(items, format!("pe_zs_{j}"), 1),
        })
        .collect()
}

/// PE matrix and operand load: one instance per platform instance; the operands (previous and
/// next point, or the transmitter/receiver at a path's ends) are broadcast one instance per
/// cycle, memory data one cycle after the address, and the addressed PE latches them. Each PE
/// starts the cycle after its own load (`ld_go`, `ld_go_inst`), so a slot's first PEs compute
/// while its later jobs load, and write-back (job after job, in load order) follows them.
fn pe_matrix(t: &Dims<'_>, pe: &[PeWires], items: &mut Vec<Item>) {
    let loading = state_is(S_LOAD).and(id("ld_q_en"));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![nb(id("ld_go"), lit(1, 0))],
        vec![
            nb(id("ld_go"), loading.clone()),
            nb(id("ld_go_inst"), id("ld_q_inst")),
        ],
    )]));
    // The operand wires follow the instances in the file: build them aside first.
    let mut operands = Vec::new();
    let fine = |n: &str| Expr::concat(vec![mm_bits(n, t.wd), lit(8, 0)]);
    let tx_fine = Expr::concat(vec![fine("tx_z"), fine("tx_y"), fine("tx_x")]);
    let rx_fine = Expr::concat(vec![fine("rx_z"), fine("rx_y"), fine("rx_x")]);
    let pw = point_bits(t.wd);
    // A path's first point reads TX as its previous point, its last RX as its next.
    let prev_or_tx = Expr::mux(id("ld_q_first"), tx_fine, id("rd_a"));
    let prev = Signal::assigned(&mut operands, "opnd_prev", pw, prev_or_tx);
    let next_or_rx = Expr::mux(id("ld_q_last"), rx_fine, id("rd_b"));
    let next = Signal::assigned(&mut operands, "opnd_next", pw, next_or_rx);
    for (j, (inst, w)) in t.p.platform.instances.iter().zip(pe).enumerate() {
        items.push(Item::Instance {
            module: pe_module_name(inst.plane as usize),
            name: format!("u_pe_{j}"),
            ports: vec![
                ("clk".into(), id("clk")),
                ("rst_n".into(), id("rst_n")),
                ("load".into(), w.load.e()),
                ("start".into(), w.start.e()),
                ("s_prev".into(), prev.e()),
                ("s_next".into(), next.e()),
                ("s_sum".into(), w.sum.e()),
                ("zero_sum".into(), w.zs.e()),
            ],
        });
        operands.push(Item::Assign(
            w.load.e(),
            loading
                .clone()
                .and(id("ld_q_inst").eq(lit(t.ib, j as u128))),
        ));
        operands.push(Item::Assign(
            w.start.e(),
            id("ld_go").and(id("ld_go_inst").eq(lit(t.ib, j as u128))),
        ));
    }
    items.extend(operands);
}

/// The `bt_top` module around `items`: header and the Avalon-MM ports.
fn top_shell(t: &Dims<'_>, items: Vec<Item>) -> Module {
    let ab = t.ab;
    Module {
        name: "bt_top".into(),
        header: vec![
            "bt_top: IPC ray-tracing accelerator generated by bt-hls (register map in report.md)."
                .into(),
            format!(
                "Avalon-MM slave, 32-bit words, word address {ab} bits, fixed read latency 2, irq = done."
            ),
        ],
        ports: vec![
            port("clk", Direction::Input, 1),
            port("rst_n", Direction::Input, 1),
            port("avs_address", Direction::Input, ab),
            port("avs_read", Direction::Input, 1),
            port("avs_write", Direction::Input, 1),
            port("avs_writedata", Direction::Input, 32),
            port("avs_readdata", Direction::OutputReg, 32),
            port("avs_readdatavalid", Direction::OutputReg, 1),
            port("ins_irq", Direction::Output, 1),
        ],
        items,
    }
}

/// Builds `bt_top`: an outline that calls one builder per block, in the order the blocks
/// appear in the emitted file.
pub(crate) fn top_module(d: &TopParams<'_>) -> Module {
    let t = Dims::of(d);
    let mut items = Vec::new();
    let pe = declare_state(&t, &mut items);
    let bus = bus_decode(&t, &mut items);
    job_memory(&t, &bus, &mut items);
    let rom = slot_buffer_read(&t, &mut items);
    let dj = dispatch_signals(&t, &mut items);
    slot_buffer_write(&t, &dj, &mut items);
    rounds_read(&t, &rom, &mut items);
    let ports = updater_read_ports(&t, &bus, &rom, &mut items);
    let sel = pe_output_select(&t, &pe, &mut items);
    let disp = displacement(&t, &sel, &mut items);
    let wb_lb = t
        .early
        .as_ref()
        .map(|(stop, boxes)| early_stop_logic(d, stop, boxes, &disp, &mut items));
    let flags = writeback_flags(&sel, &disp, wb_lb, &mut items);
    let (push, push_data) = writeback_push(&t, &flags, &mut items);
    let [start_req, go, scan, empty] = dispatch_triggers(&t, &push, &mut items);
    ready_queue(&t, &bus, &dj, (&push, &push_data), &start_req, &mut items);
    items.push(dispatcher(&t, &dj, &go, &scan));
    rounds_write(&flags, &mut items);
    updater_write_port(&bus, &ports, &sel, &flags, &mut items);
    pe_matrix(&t, &pe, &mut items);
    controller(&t, &rom, &flags, [&start_req, &empty], &mut items);
    register_writes(&t, &bus, &mut items);
    sched_hi_register(&t, &bus, &mut items);
    let mux = read_pipeline(&t, &bus, &mut items);
    read_mux(&t, &mux, &mut items);
    interrupt_and_unused(&mut items);
    top_shell(&t, items)
}
