//! `bt_top`: PE matrix, job memory, ready queue and dispatcher, slot buffer, coordinate
//! updater-buffer, convergence flags and the Avalon-MM slave. Twin of
//! `bt_fixed::FixedIpc::run_fixed` with each path's own stop (no budgets), and of
//! `crate::dispatch::predict` cycle for cycle.

use crate::input::{Layout, bits_for, pe_latency, sched_entry_bits};
use crate::rtl::pe::{pe_module_name, point_bits, port, sext_slice, sum_bits};
use crate::rtl::verilog::{BinaryOp, Direction, Expr, Item, Module, Signal, Stmt, UnaryOp};

mod bus;
mod controller;
mod planes;
mod regs;
mod updater;
mod writeback;

use bus::*;
use controller::*;
use planes::*;
use regs::*;
use updater::*;
use writeback::*;

/// FSM state encodings.
const S_IDLE: u128 = 0;
const S_DISP: u128 = 1;
const S_LOAD: u128 = 2;
const S_EXEC: u128 = 3;
/// The last slot's write-back runs with no slot loading (the write-back engine, `wb_on`, runs
/// beside LOAD and EXEC too).
const S_WB: u128 = 4;
const STATE_BITS: u32 = 3;

/// Register-map version reported in `INFO[15:8]`.
pub const MAP_VERSION: u32 = 6;

fn nb(l: Expr, r: Expr) -> Stmt {
    Stmt::NonBlocking(l, r)
}
/// `s <= 0;` at the register's declared width.
fn clear(s: &Signal) -> Stmt {
    nb(s.e(), lit(s.width(), 0))
}
fn lit(w: u32, v: u128) -> Expr {
    Expr::lit(w, v)
}
fn state_is(t: &Dims<'_>, s: u128) -> Expr {
    t.r.state.e().eq(lit(STATE_BITS, s))
}
fn dstate_is(t: &Dims<'_>, s: u128) -> Expr {
    t.r.dstate.e().eq(lit(DSTATE_BITS, s))
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

/// The low bits of the 32-bit millimetre bus word `word` that a fine coordinate of the
/// design's width keeps above its 8 fraction bits (all 32 in the full 40-bit design; the host
/// writes only values that fit, [`bt_fixed::FixedIpc::check_terminal`]).
fn mm_bits(word: &Signal, wd: bt_fixed::Widths) -> Expr {
    let keep = mm_width(wd);
    if keep >= 32 {
        word.e()
    } else {
        word.slice(keep - 1, 0)
    }
}

/// `s` as an `to`-bit unsigned value: zero-extended or truncated.
fn zero_extend(s: &Signal, to: u32) -> Expr {
    let from = s.width();
    match from.cmp(&to) {
        std::cmp::Ordering::Less => Expr::concat(vec![lit(to - from, 0), s.e()]),
        std::cmp::Ordering::Equal => s.e(),
        std::cmp::Ordering::Greater => s.slice(to - 1, 0),
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
    /// Bits of a job's plane field (generic PEs; 0 otherwise).
    plb: u32,
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
    /// The ports.
    io: Ports,
    /// Every register and memory, declared once.
    r: Regs,
}

impl<'a> Dims<'a> {
    /// Bits of a job-memory entry.
    fn sw(&self) -> u32 {
        sched_entry_bits(self.pb, self.ptb, self.ib, self.plb)
    }

    /// Cycles of one PE evaluation in this design.
    fn latency(&self) -> u32 {
        pe_latency(self.wd.coord)
    }

    /// The sizes of `p`'s design, its ports, and its registers and memories declared in
    /// `items` after the header comment.
    fn of(p: &'a TopParams<'a>, items: &mut Vec<Item>) -> Self {
        let l = &p.layout;
        let wd = bt_fixed::Widths::for_coord(p.model.coord_bits());
        let latency = pe_latency(p.model.coord_bits());
        let cap = p.platform.capacity;
        let sizes = RegSizes {
            pb: l.path_bits,
            ptb: l.point_bits,
            ib: l.inst_bits,
            eb: l.entry_bits,
            plb: l.plane_bits,
            np2: 1u32 << l.path_bits,
            cnt_bits: bits_for(u64::from((l.num_instances + 2).max(latency)) + 1),
            wd,
            early: p.model.early_stop().is_some(),
        };
        items.push(Item::Comment(format!(
            "{} PE instances, capacity {} paths, {} points, {} groups; per slot load (delay + jobs + 2, beside the previous slot's write-back) + max({} - jobs - 1, 1) + write-back (jobs + 2) cycles (each PE starts after its own load), threshold {} fine LSB",
            l.num_instances,
            cap.paths,
            cap.points,
            cap.slots,
            latency,
            p.platform.threshold_lsb
        )));
        let r = Regs::declare(&sizes, items);
        Dims {
            p,
            k: l.num_instances,
            pb: sizes.pb,
            ptb: sizes.ptb,
            ib: sizes.ib,
            eb: sizes.eb,
            plb: sizes.plb,
            np2: sizes.np2,
            cnt_bits: sizes.cnt_bits,
            ab: l.address_bits,
            early: p.model.early_stop().map(|(s, b)| (*s, b.to_vec())),
            wd,
            io: Ports::new(l.address_bits),
            r,
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

/// The PE wires (the header comment and every register and memory are declared by
/// [`Dims::of`] before them, as the golden files show).
fn declare_pe_wires(t: &Dims<'_>, items: &mut Vec<Item>) -> Vec<PeWires> {
    (0..t.k)
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
fn pe_matrix(t: &Dims<'_>, pe: &[PeWires], coefficients: Option<Vec<Expr>>, items: &mut Vec<Item>) {
    let loading = state_is(t, S_LOAD).and(t.r.ld_q_en.e());
    items.push(Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![clear(&t.r.ld_go)],
        vec![
            nb(t.r.ld_go.e(), loading.clone()),
            nb(t.r.ld_go_inst.e(), t.r.ld_q_inst.e()),
        ],
    )]));
    // The operand wires follow the instances in the file: build them aside first.
    let mut operands = Vec::new();
    let r = &t.r;
    let fine = |n: &Signal| Expr::concat(vec![mm_bits(n, t.wd), lit(8, 0)]);
    let tx_fine = Expr::concat(vec![fine(&r.tx_z), fine(&r.tx_y), fine(&r.tx_x)]);
    let rx_fine = Expr::concat(vec![fine(&r.rx_z), fine(&r.rx_y), fine(&r.rx_x)]);
    let pw = point_bits(t.wd);
    // A path's first point reads TX as its previous point, its last RX as its next.
    let prev_or_tx = Expr::mux(t.r.ld_q_first.e(), tx_fine, t.r.rd_a.e());
    let prev = Signal::assigned(&mut operands, "opnd_prev", pw, prev_or_tx);
    let next_or_rx = Expr::mux(t.r.ld_q_last.e(), rx_fine, t.r.rd_b.e());
    let next = Signal::assigned(&mut operands, "opnd_next", pw, next_or_rx);
    let coefficient_ports: Vec<(String, Expr)> = match coefficients {
        Some(c) => crate::rtl::generic::coefficient_ports(t.wd)
            .into_iter()
            .map(|(name, _)| name)
            .zip(c)
            .collect(),
        None => Vec::new(),
    };
    for (j, (inst, w)) in t.p.platform.instances.iter().zip(pe).enumerate() {
        let mut ports = vec![
            ("clk".into(), t.io.clk.e()),
            ("rst_n".into(), t.io.rst_n.e()),
            ("load".into(), w.load.e()),
            ("start".into(), w.start.e()),
            ("s_prev".into(), prev.e()),
            ("s_next".into(), next.e()),
            ("s_sum".into(), w.sum.e()),
            ("zero_sum".into(), w.zs.e()),
        ];
        ports.extend(coefficient_ports.iter().cloned());
        items.push(Item::Instance {
            module: if inst.is_generic() {
                crate::rtl::generic::GENERIC_PE_MODULE.into()
            } else {
                pe_module_name(inst.plane as usize)
            },
            name: format!("u_pe_{j}"),
            ports,
        });
        operands.push(Item::Assign(
            w.load.e(),
            loading
                .clone()
                .and(t.r.ld_q_inst.e().eq(lit(t.ib, j as u128))),
        ));
        operands.push(Item::Assign(
            w.start.e(),
            t.r.ld_go
                .e()
                .and(t.r.ld_go_inst.e().eq(lit(t.ib, j as u128))),
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
        ports: t.io.list(),
        items,
    }
}

/// Builds `bt_top`: an outline that calls one builder per block, in the order the blocks
/// appear in the emitted file.
pub(crate) fn top_module(d: &TopParams<'_>) -> Module {
    let mut items = Vec::new();
    let t = Dims::of(d, &mut items);
    let pe = declare_pe_wires(&t, &mut items);
    let bus = bus_decode(&t, &mut items);
    let lrom = slot_buffer_load(&t, &mut items);
    let coefficients = plane_table(&t, &bus, &lrom, &mut items);
    let rom = slot_buffer_writeback(&t, &mut items);
    let dj = dispatch_signals(&t, &mut items);
    job_memory(&t, &bus, &dj, &mut items);
    slot_buffer_write(&t, &dj, &mut items);
    let rounds_cur = rounds_read(&t, &rom, &mut items);
    let ports = updater_read_ports(&t, &bus, (&rom, &lrom), &mut items);
    let sel = pe_output_select(&t, &pe, &mut items);
    let disp = displacement(&t, &sel, &mut items);
    let wb_lb = t
        .early
        .as_ref()
        .map(|(stop, boxes)| early_stop_logic(&t, (stop, boxes), (&disp, &rounds_cur), &mut items));
    let flags = writeback_flags(&t, (&sel, &disp), wb_lb, rounds_cur, &mut items);
    let (push, push_data) = writeback_push(&t, &flags, &mut items);
    let [start_req, go, scan, front, empty] = dispatch_triggers(&t, &push, &mut items);
    ready_queue(&t, &bus, &dj, (&push, &push_data), &start_req, &mut items);
    items.push(dispatcher(&t, &dj, [&go, &scan, &front]));
    rounds_write(&t, &flags, &mut items);
    updater_write_port(&t, &bus, &ports, &sel, &flags, &mut items);
    pe_matrix(&t, &pe, coefficients, &mut items);
    controller(&t, (&rom, &lrom), &flags, [&start_req, &empty], &mut items);
    register_writes(&t, &bus, &mut items);
    sched_hi_register(&t, &bus, &mut items);
    let mux = read_pipeline(&t, &bus, &mut items);
    read_mux(&t, &mux, &mut items);
    interrupt_and_unused(&t, &mut items);
    top_shell(&t, items)
}
