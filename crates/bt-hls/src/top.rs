//! `bt_top`: PE matrix, job memory, ready queue and dispatcher, slot buffer, coordinate
//! updater-buffer, convergence flags and the Avalon-MM slave. Twin of
//! `bt_fixed::FixedIpc::run_fixed` with each path's own stop (no budgets), and of
//! `crate::dispatch::predict` cycle for cycle.

use crate::input::{Layout, bits_for, pe_latency, sched_entry_bits};
use crate::pe::{pe_module_name, point_bits, port, sext_slice, sum_bits};
use crate::verilog::{BinaryOp, Direction, Expr, Item, Module, Signal, Stmt, UnaryOp};

/// FSM state encodings.
const S_IDLE: u128 = 0;
const S_DISP: u128 = 1;
const S_LOAD: u128 = 2;
const S_EXEC: u128 = 3;
const S_WB: u128 = 4;
const STATE_BITS: u32 = 3;

/// Register-map version reported in `INFO[15:8]`.
pub const MAP_VERSION: u32 = 6;

/// Dispatcher state encodings (`dstate`): idle, read the queue's head once, pop a queued
/// group (reading its first job), examine its jobs, publish the slot's length.
const D_OFF: u128 = 0;
const D_POP: u128 = 1;
const D_WARM: u128 = 2;
const D_JOB: u128 = 3;
const D_FIN: u128 = 4;
const DSTATE_BITS: u32 = 3;

/// Width of the early-stopping comparisons (`bt_fixed::FineBox::outside`): a 40-bit point
/// plus or minus `(L1 move) << 4` and the ±2^41 box bounds fit in 48 signed bits.
const BOX_BITS: u32 = 48;

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
        "{} PE instances, capacity {} paths, {} points, {} groups; 2 x (jobs + 2) + max({}, dispatch + 1) cycles per slot, threshold {} fine LSB",
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
        ("ld_q_en", 1),
        ("ld_q_tail", 1),
        ("ld_q_first", 1),
        ("ld_q_last", 1),
        ("ld_q_inst", ib),
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
            sum: Signal::wire(items, format!("pe_sum_{j}"), sum_bits(t.wd)),
            zs: Signal::wire(items, format!("pe_zs_{j}"), 1),
        })
        .collect()
}

/// The ready queue's pointers and head word, and the dispatcher's registers.
fn declare_dispatch_state(t: &Dims<'_>, items: &mut Vec<Item>) {
    let (pb, ptb, ib, eb) = (t.pb, t.ptb, t.ib, t.eb);
    for (n, w) in [
        ("rq_head", pb),
        ("rq_tail", pb),
        ("rq_count", pb + 1),
        ("rq_q", 2 * eb),
        ("job_q", sched_entry_bits(pb, ptb, ib)),
        ("dstate", DSTATE_BITS),
        ("d_scan", pb + 1),
        ("d_used", 1 << ib),
        ("d_save", 1 << ib),
        ("d_nsl", ib + 1),
        ("d_gi", ib + 1),
        ("d_conf", 1),
        ("d_gbase", eb),
        ("d_gptr", eb),
    ] {
        items.push(Item::Reg(n.into(), w));
    }
    // The ready queue (one entry per queued path: {first group, next group}, entry indices of
    // the job memory) and the slot buffer (two slots: the running one and the next, each job
    // with {its job-memory entry, its path's first group}).
    items.push(Item::Memory("rq".into(), 2 * eb, t.np2));
    items.push(Item::Memory(
        "sbuf".into(),
        sched_entry_bits(pb, ptb, ib) + 2 * eb,
        2 << ib,
    ));
}

/// The Avalon-MM address decode: which region a bus access hits, and the host's write strobes.
struct Decode {
    /// Control registers (`avs_address < 16`).
    is_ctrl: Signal,
    /// Per-path status words.
    is_status: Signal,
    /// Point memory window.
    is_point: Signal,
    /// Schedule memory window.
    is_sched: Signal,
    /// The point index of a point-window address.
    bus_point: Signal,
    /// A host write while idle.
    host_wr: Signal,
    /// The host writes a point's last word (fractions): the point memory write strobe.
    pt_we: Signal,
}

/// Bus address decode.
fn bus_decode(t: &Dims<'_>, items: &mut Vec<Item>) -> Decode {
    let l = &t.p.layout;
    let ab = t.ab;
    let hi = ab - 1;
    let window = |items: &mut Vec<Item>, name: &str, base: u32| {
        let bits = base.trailing_zeros();
        Signal::assigned(
            items,
            name,
            1,
            Expr::slice("avs_address", hi, bits).eq(lit(ab - bits, 1)),
        )
    };
    let idle = Signal::assigned(items, "idle", 1, state_is(S_IDLE));
    let is_ctrl = Signal::assigned(
        items,
        "is_ctrl",
        1,
        Expr::slice("avs_address", hi, 4).eq(lit(ab - 4, 0)),
    );
    let is_status = window(items, "is_status", l.map.status_base);
    let is_point = window(items, "is_point", l.map.point_base);
    let is_sched = window(items, "is_sched", l.map.sched_base);
    let bus_point = Signal::assigned(
        items,
        "bus_point",
        t.ptb,
        Expr::slice("avs_address", t.ptb + 2, 3),
    );
    let host_wr = Signal::assigned(items, "host_wr", 1, id("avs_write").and(idle.e()));
    let pt_we = Signal::assigned(
        items,
        "pt_we",
        1,
        host_wr
            .e()
            .and(is_point.e())
            .and(Expr::slice("avs_address", 1, 0).eq(lit(2, 3))),
    );
    Decode {
        is_ctrl,
        is_status,
        is_point,
        is_sched,
        bus_point,
        host_wr,
        pt_we,
    }
}

/// The fields of the slot-buffer entry read this cycle (`sched_q`, gated by `sq_ok`).
struct ScheduleRead {
    /// The entry is a job of the running slot.
    valid: Signal,
    /// The slot's last entry.
    tail: Signal,
    /// Path, point (global index) and PE column of the job.
    path: Signal,
    point: Signal,
    inst: Signal,
    /// The job's previous point is the transmitter.
    first: Signal,
    /// The job's next point is the receiver.
    last: Signal,
    /// The job closes its path's round.
    end: Signal,
    /// The job runs after its round's first phase (red-black): its neighbours' points are
    /// read from the bank the round writes, not the committed one.
    late: Signal,
    /// The job is its group's last: its write-back queues the path's next group.
    gtail: Signal,
    /// The job's entry in the job memory, and its path's first group's.
    src: Signal,
    gbase: Signal,
}

/// The bit of the job word that marks a group's last job.
fn gtail_bit(t: &Dims<'_>) -> u32 {
    5 + t.pb + t.ptb
}

/// Job memory (M9K), written by the host per step: one round of every path as groups
/// (`{column, tail, late, end, last, first, point, path, valid}`, `tail` on a group's last
/// job), path after path. Read by the dispatcher only (`job_q`, one cycle after the address).
fn job_memory(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
    let (pb, ptb, ib, eb) = (t.pb, t.ptb, t.ib, t.eb);
    let sw = sched_entry_bits(pb, ptb, ib);
    items.push(Item::Comment(format!(
        "job memory, written per step by the host: one round of every path as groups, entry -> {{column, group tail, late, end, last, first, point, path, valid}} ({sw} bits)"
    )));
    let gi = zero_extend("d_gi", ib + 1, eb);
    let job_ra = Signal::assigned(
        items,
        "job_ra",
        eb,
        Expr::mux(
            dstate_is(D_POP),
            Expr::slice("rq_q", eb - 1, 0),
            id("d_gptr").plus(gi).plus(lit(eb, 1)),
        ),
    );
    items.push(Item::Memory("sched".into(), sw, 1 << eb));
    let entry = if sw > 32 {
        Expr::concat(vec![id("sched_hi"), id("avs_writedata")])
    } else {
        Expr::slice("avs_writedata", sw - 1, 0)
    };
    items.push(Item::AlwaysFf(vec![
        Stmt::If(
            bus.host_wr.e().and(bus.is_sched.e()),
            vec![nb(
                Expr::id("sched").at(Expr::slice("avs_address", eb - 1, 0)),
                entry,
            )],
            vec![],
        ),
        nb(id("job_q"), Expr::id("sched").at(job_ra.e())),
    ]));
}

/// Slot buffer, read side: entry `cnt` of the running slot (`rsel`) one cycle after the
/// address, valid below the slot's length; its fields.
fn slot_buffer_read(t: &Dims<'_>, items: &mut Vec<Item>) -> ScheduleRead {
    let (pb, ptb, ib, eb, cnt_bits) = (t.pb, t.ptb, t.ib, t.eb, t.cnt_bits);
    let sw = sched_entry_bits(pb, ptb, ib);
    items.push(Item::Comment(
        "slot buffer: the running slot's jobs (rsel), the next slot's written by the dispatcher"
            .into(),
    ));
    let slen = Signal::assigned(
        items,
        "slen_cur",
        ib + 1,
        Expr::mux(id("rsel"), id("slen_1"), id("slen_0")),
    );
    let w = cnt_bits.max(ib + 1);
    let cnt_w = zero_extend("cnt", cnt_bits, w);
    let len_w = zero_extend(slen.name(), ib + 1, w);
    let in_slot = Expr::bin(BinaryOp::Lt, cnt_w.clone(), len_w.clone());
    let is_last = cnt_w.plus(lit(w, 1)).eq(len_w);
    let sb_ra = Signal::assigned(
        items,
        "sb_ra",
        ib + 1,
        Expr::concat(vec![id("rsel"), zero_extend("cnt", cnt_bits, ib)]),
    );
    items.push(Item::AlwaysFf(vec![
        nb(id("sched_q"), Expr::id("sbuf").at(sb_ra.e())),
        nb(
            id("sq_ok"),
            or(state_is(S_LOAD), state_is(S_WB)).and(in_slot),
        ),
        nb(id("sq_tail"), is_last),
    ]));
    let field = |items: &mut Vec<Item>, n: &str, w: u32, lo: u32| {
        Signal::assigned(items, n, w, Expr::slice("sched_q", lo + w - 1, lo))
    };
    let valid = Signal::assigned(items, "rom_valid", 1, id("sq_ok"));
    let tail = Signal::assigned(items, "rom_tail", 1, id("sq_ok").and(id("sq_tail")));
    ScheduleRead {
        valid,
        tail,
        path: field(items, "rom_path", pb, 1),
        point: field(items, "rom_point", ptb, 1 + pb),
        inst: field(items, "rom_inst", ib, 6 + pb + ptb),
        first: field(items, "rom_first", 1, 1 + pb + ptb),
        last: field(items, "rom_last", 1, 2 + pb + ptb),
        end: field(items, "rom_end", 1, 3 + pb + ptb),
        late: field(items, "rom_late", 1, 4 + pb + ptb),
        gtail: field(items, "rom_gtail", 1, gtail_bit(t)),
        src: field(items, "rom_src", eb, sw + eb),
        gbase: field(items, "rom_gbase", eb, sw),
    }
}

/// The dispatcher's view of the job in `job_q`: its column, whether it ends its group, and
/// whether its group cannot run in the slot being built (a column taken).
struct DispatchJob {
    gtail: Signal,
    conflict: Signal,
    /// Pop the queue's head this cycle.
    pop: Signal,
    /// Put the examined group back at the queue's tail this cycle.
    push_back: Signal,
}

/// The dispatcher's combinational signals.
fn dispatch_signals(t: &Dims<'_>, items: &mut Vec<Item>) -> DispatchJob {
    let (pb, ptb, ib) = (t.pb, t.ptb, t.ib);
    let col = Signal::assigned(
        items,
        "j_col",
        ib,
        Expr::slice("job_q", 6 + pb + ptb + ib - 1, 6 + pb + ptb),
    );
    let gtail = Signal::assigned(items, "j_gtail", 1, Expr::bit("job_q", gtail_bit(t)));
    let conflict = Signal::assigned(
        items,
        "j_conf",
        1,
        or(id("d_conf"), Expr::id("d_used").at(col.e())),
    );
    let all_used = Expr::slice("d_used", t.k - 1, 0).eq(lit(t.k, (1u128 << t.k) - 1));
    let stop = Signal::assigned(
        items,
        "d_stop",
        1,
        or(id("d_scan").eq(lit(pb + 1, 0)), all_used),
    );
    let pop = Signal::assigned(items, "d_pop", 1, dstate_is(D_POP).and(stop.e().lnot()));
    let push_back = Signal::assigned(
        items,
        "d_push",
        1,
        dstate_is(D_JOB).and(gtail.e()).and(conflict.e()),
    );
    DispatchJob {
        gtail,
        conflict,
        pop,
        push_back,
    }
}

/// The dispatcher (twin of `crate::dispatch::predict`): on `d_go` it builds the next slot in
/// the buffer the running slot does not use, examining up to `SCAN_LIMIT` queued groups, each
/// put into the slot when all its columns are free (else back to the queue), then publishes
/// the slot's length. `rq_q` always holds the queue's head: it is read every cycle, and a
/// pop is at least one job after the last (`D_WARM` reads it after a start or a push).
fn dispatcher(t: &Dims<'_>, d: &DispatchJob, go: &Signal, scan_init: &Signal) -> Item {
    let (ib, eb) = (t.ib, t.eb);
    let n = 1u32 << ib;
    let gi_plus = |k: u128| id("d_gi").plus(lit(ib + 1, k));
    let on_tail = vec![Stmt::If(
        d.conflict.e().lnot(),
        vec![nb(id("d_nsl"), id("d_nsl").plus(gi_plus(1)))],
        vec![nb(id("d_used"), id("d_save"))],
    )];
    let job = vec![
        nb(Expr::id("d_used").at(id("j_col")), lit(1, 1)),
        Stmt::If(
            d.gtail.e(),
            on_tail
                .into_iter()
                .chain([nb(id("dstate"), lit(DSTATE_BITS, D_POP))])
                .collect(),
            vec![nb(id("d_gi"), gi_plus(1)), nb(id("d_conf"), d.conflict.e())],
        ),
    ];
    let arms = vec![
        (
            lit(DSTATE_BITS, D_OFF),
            vec![Stmt::If(
                go.e(),
                vec![
                    nb(id("dstate"), lit(DSTATE_BITS, D_WARM)),
                    nb(id("d_scan"), scan_init.e()),
                    nb(id("d_used"), lit(n, 0)),
                    nb(id("d_nsl"), lit(ib + 1, 0)),
                ],
                vec![],
            )],
        ),
        (
            lit(DSTATE_BITS, D_WARM),
            vec![nb(id("dstate"), lit(DSTATE_BITS, D_POP))],
        ),
        (
            lit(DSTATE_BITS, D_POP),
            vec![Stmt::If(
                d.pop.e(),
                vec![
                    nb(id("dstate"), lit(DSTATE_BITS, D_JOB)),
                    nb(id("d_scan"), id("d_scan").minus(lit(t.pb + 1, 1))),
                    nb(id("d_gbase"), Expr::slice("rq_q", 2 * eb - 1, eb)),
                    nb(id("d_gptr"), Expr::slice("rq_q", eb - 1, 0)),
                    nb(id("d_gi"), lit(ib + 1, 0)),
                    nb(id("d_conf"), lit(1, 0)),
                    nb(id("d_save"), id("d_used")),
                ],
                vec![nb(id("dstate"), lit(DSTATE_BITS, D_FIN))],
            )],
        ),
        (lit(DSTATE_BITS, D_JOB), job),
        (
            lit(DSTATE_BITS, D_FIN),
            vec![
                Stmt::If(
                    id("rsel"),
                    vec![nb(id("slen_0"), id("d_nsl"))],
                    vec![nb(id("slen_1"), id("d_nsl"))],
                ),
                nb(id("dstate"), lit(DSTATE_BITS, D_OFF)),
            ],
        ),
    ];
    Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![
            nb(id("dstate"), lit(DSTATE_BITS, D_OFF)),
            nb(id("slen_0"), lit(ib + 1, 0)),
            nb(id("slen_1"), lit(ib + 1, 0)),
        ],
        vec![Stmt::Case(
            id("dstate"),
            arms,
            vec![nb(id("dstate"), lit(DSTATE_BITS, D_OFF))],
        )],
    )])
}

/// Slot buffer, write side: a job of the group being examined, while no column of it is
/// taken, at `{~rsel, d_nsl + d_gi}` with its job-memory entry and its path's first group.
fn slot_buffer_write(t: &Dims<'_>, d: &DispatchJob, items: &mut Vec<Item>) {
    let (ib, eb) = (t.ib, t.eb);
    let we = dstate_is(D_JOB).and(d.conflict.e().lnot());
    // Below the PE count while no column of the group is taken: ib bits.
    let wi = Signal::assigned(
        items,
        "sb_wi",
        ib,
        Expr::slice("d_nsl", ib - 1, 0).plus(Expr::slice("d_gi", ib - 1, 0)),
    );
    let at = Expr::concat(vec![id("rsel").inv(), wi.e()]);
    let src = id("d_gptr").plus(zero_extend("d_gi", ib + 1, eb));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        we,
        vec![nb(
            Expr::id("sbuf").at(at),
            Expr::concat(vec![src, id("d_gbase"), id("job_q")]),
        )],
        vec![],
    )]));
}

/// Write-back's queue push: a group's last job queues the path's next group, or after the
/// round's last group the path's first group again, unless the path converged, froze or
/// reached the round cap (`cap_r`).
fn writeback_push(t: &Dims<'_>, f: &WritebackFlags, items: &mut Vec<Item>) -> (Signal, Signal) {
    let eb = t.eb;
    let mut goes_on = f
        .any_big
        .e()
        .and(f.any_dz.e().lnot())
        .and(f.any_ov.e().lnot());
    if let Some(lb) = &f.any_lb {
        goes_on = goes_on.and(lb.e().lnot());
    }
    let below_cap = Expr::bin(BinaryOp::Lt, id("rounds_cur").plus(lit(16, 1)), id("cap_r"));
    let again = Signal::assigned(items, "wb_again", 1, goes_on.and(below_cap));
    let push = Signal::assigned(
        items,
        "wb_push",
        1,
        f.go.e()
            .and(id("wb_q_gtail"))
            .and(or(id("wb_q_end").lnot(), again.e())),
    );
    let next = Expr::mux(
        id("wb_q_end"),
        id("wb_q_gbase"),
        id("wb_q_src").plus(lit(eb, 1)),
    );
    let data = Signal::assigned(
        items,
        "wb_push_data",
        2 * eb,
        Expr::concat(vec![id("wb_q_gbase"), next]),
    );
    (push, data)
}

/// The ready queue (`rq`): a circular buffer of `{first group, next group}` per queued
/// path, written by the host while idle (PATH_BASE[p] = path p's entry), then by the
/// dispatcher's push-backs and write-back's pushes (never in the same cycle); read at the head.
fn ready_queue(
    t: &Dims<'_>,
    bus: &Decode,
    d: &DispatchJob,
    (wb_push, wb_data): (&Signal, &Signal),
    start: &Signal,
    items: &mut Vec<Item>,
) {
    let (pb, eb) = (t.pb, t.eb);
    let push = Signal::assigned(items, "rq_push", 1, or(d.push_back.e(), wb_push.e()));
    let host = bus.host_wr.e().and(bus.is_status.e());
    let data = Expr::mux(
        bus.host_wr.e(),
        Expr::slice("avs_writedata", 2 * eb - 1, 0),
        Expr::mux(
            d.push_back.e(),
            Expr::concat(vec![id("d_gbase"), id("d_gptr")]),
            wb_data.e(),
        ),
    );
    let addr = Expr::mux(
        bus.host_wr.e(),
        Expr::slice("avs_address", pb - 1, 0),
        id("rq_tail"),
    );
    items.push(Item::AlwaysFf(vec![
        Stmt::If(
            or(host, push.e()),
            vec![nb(Expr::id("rq").at(addr), data)],
            vec![],
        ),
        nb(id("rq_q"), Expr::id("rq").at(id("rq_head"))),
    ]));
    let inc = |n: &str, w: u32| id(n).plus(lit(w, 1));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![
            nb(id("rq_head"), lit(pb, 0)),
            nb(id("rq_tail"), lit(pb, 0)),
            nb(id("rq_count"), lit(pb + 1, 0)),
        ],
        vec![Stmt::If(
            start.e(),
            vec![
                nb(id("rq_head"), lit(pb, 0)),
                nb(id("rq_tail"), Expr::slice("paths_r", pb - 1, 0)),
                nb(id("rq_count"), id("paths_r")),
            ],
            vec![
                Stmt::If(
                    d.pop.e(),
                    vec![nb(id("rq_head"), inc("rq_head", pb))],
                    vec![],
                ),
                Stmt::If(
                    push.e(),
                    vec![nb(id("rq_tail"), inc("rq_tail", pb))],
                    vec![],
                ),
                Stmt::If(
                    push.e(),
                    vec![nb(id("rq_count"), inc("rq_count", pb + 1))],
                    vec![Stmt::If(
                        d.pop.e(),
                        vec![nb(id("rq_count"), id("rq_count").minus(lit(pb + 1, 1)))],
                        vec![],
                    )],
                ),
            ],
        )],
    )]));
}

/// The ports of the coordinate updater-buffer (the two point memory copies).
struct UpdaterPorts {
    /// Read addresses of the two copies (port a: previous or own point, port b: next point).
    ra_addr: Signal,
    rb_addr: Signal,
    /// Write enable, address `{point, bank}` and data of the common write port.
    wr_en: Signal,
    wr_addr: Signal,
    wr_data: Signal,
}

/// `{bus_point, avs_address[2]}`: the memory cell a point-window bus access addresses.
fn bus_cell(bus: &Decode) -> Expr {
    Expr::concat(vec![bus.bus_point.e(), Expr::bit("avs_address", 2)])
}

/// Rounds memory, read side: `rounds_q` <= rounds[addr] every cycle, the address being the
/// schedule entry's path at write-back (so `rounds_q` holds rounds[wb_q_path] when the entry
/// commits: a path's jobs in a slot belong to one round, so no commit of the same path sits
/// between) and the bus address otherwise (a PATH_STATUS read while idle).
/// `rounds_cur` = the rounds `wb_q_path` has committed since the start.
fn rounds_read(t: &Dims<'_>, rom: &ScheduleRead, items: &mut Vec<Item>) {
    items.push(Item::Comment(
        "rounds memory (M9K): read at the write-back entry's path, or the bus address".into(),
    ));
    let addr = Signal::assigned(
        items,
        "rounds_ra",
        t.pb,
        Expr::mux(
            state_is(S_WB),
            rom.path.e(),
            Expr::slice("avs_address", t.pb - 1, 0),
        ),
    );
    items.push(Item::AlwaysFf(vec![nb(
        id("rounds_q"),
        Expr::id("rounds").at(addr.e()),
    )]));
    Signal::assigned(
        items,
        "rounds_cur",
        16,
        Expr::mux(
            Expr::id("rvalid").at(id("wb_q_path")),
            id("rounds_q"),
            lit(16, 0),
        ),
    );
}

/// Rounds memory, write side: a committed round's end writes rounds_cur + 1.
fn rounds_write(f: &WritebackFlags, items: &mut Vec<Item>) {
    items.push(Item::AlwaysFf(vec![Stmt::If(
        f.go.e().and(id("wb_q_end")),
        vec![nb(
            Expr::id("rounds").at(id("wb_q_path")),
            id("rounds_cur").plus(lit(16, 1)),
        )],
        vec![],
    )]));
}

/// Coordinate updater-buffer, read side: two banks per point, bank = cur[path] holds the last
/// committed round. Port a reads the job's previous point at load and its own point at
/// write-back (the old value, for the displacement); port b reads the next point.
fn updater_read_ports(
    t: &Dims<'_>,
    bus: &Decode,
    rom: &ScheduleRead,
    items: &mut Vec<Item>,
) -> UpdaterPorts {
    let ptb = t.ptb;
    items.push(Item::Comment(
        "coordinate updater-buffer: address {point, bank}; cur[path] = bank of the committed round"
            .into(),
    ));
    let rom_bank = Expr::id("cur").at(rom.path.e());
    // Neighbours: the committed bank, or for a late job the bank its round writes.
    let nb_bank = Expr::bin(BinaryOp::Xor, rom_bank.clone(), rom.late.e());
    let ra_addr = Signal::reg(items, "ra_addr", ptb + 1);
    let rb_addr = Signal::reg(items, "rb_addr", ptb + 1);
    let wr_addr = Signal::reg(items, "wr_addr", ptb + 1);
    let wr_en = Signal::reg(items, "wr_en", 1);
    let wr_data = Signal::reg(items, "wr_data", point_bits(t.wd));
    let one_pt = lit(ptb, 1);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(ra_addr.e(), bus_cell(bus)),
        Stmt::If(
            state_is(S_LOAD),
            vec![Stmt::Blocking(
                ra_addr.e(),
                Expr::concat(vec![rom.point.e().minus(one_pt.clone()), nb_bank.clone()]),
            )],
            vec![Stmt::If(
                state_is(S_WB),
                vec![Stmt::Blocking(
                    ra_addr.e(),
                    Expr::concat(vec![rom.point.e(), rom_bank.clone()]),
                )],
                vec![],
            )],
        ),
        Stmt::Blocking(
            rb_addr.e(),
            Expr::concat(vec![rom.point.e().plus(one_pt), nb_bank]),
        ),
    ]));
    UpdaterPorts {
        ra_addr,
        rb_addr,
        wr_en,
        wr_addr,
        wr_data,
    }
}

/// The selected PE's result at write-back, saturated once for all PEs.
struct Selected {
    /// The saturated point `{z, y, x}`.
    point: Signal,
    /// Some axis saturated.
    ov: Signal,
    /// The PE reported a zero distance sum.
    zs: Signal,
}

/// Write-back, PE output select and saturation (twin of the model's `saturate`).
fn pe_output_select(t: &Dims<'_>, pe: &[PeWires], items: &mut Vec<Item>) -> Selected {
    let cw = t.wd.coord;
    let sel_sum = Signal::reg(items, "pe_sel_sum", sum_bits(t.wd));
    let zs = Signal::reg(items, "pe_sel_zs", 1);
    let sel_arms = pe
        .iter()
        .enumerate()
        .map(|(j, w)| {
            (
                lit(t.ib, j as u128),
                vec![
                    Stmt::Blocking(sel_sum.e(), w.sum.e()),
                    Stmt::Blocking(zs.e(), w.zs.e()),
                ],
            )
        })
        .collect();
    let sel_default = vec![
        Stmt::Blocking(sel_sum.e(), lit(sum_bits(t.wd), 0)),
        Stmt::Blocking(zs.e(), lit(1, 0)),
    ];
    items.push(Item::AlwaysComb(vec![Stmt::Case(
        id("wb_q_inst"),
        sel_arms,
        sel_default,
    )]));
    let spw = t.wd.sum_point;
    let mut sat_parts = Vec::new();
    let mut ovf_terms = Vec::new();
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let sum = Signal::assigned(
            items,
            format!("sum_{axis}"),
            spw,
            sel_sum.slice(spw * (a as u32 + 1) - 1, spw * a as u32),
        );
        let top = sum.slice(spw - 1, cw - 1);
        let topw = spw - cw + 1;
        let ovf = Signal::assigned(
            items,
            format!("ovf_{axis}"),
            1,
            Expr::bin(
                BinaryOp::LogicAnd,
                Expr::bin(BinaryOp::Ne, top.clone(), lit(topw, 0)),
                Expr::bin(BinaryOp::Ne, top, lit(topw, (1u128 << topw) - 1)),
            ),
        );
        let sat = Signal::assigned(
            items,
            format!("sat_{axis}"),
            cw,
            Expr::mux(
                ovf.e(),
                Expr::mux(
                    sum.bit(spw - 1),
                    lit(cw, 1 << (cw - 1)),
                    lit(cw, (1 << (cw - 1)) - 1),
                ),
                sum.slice(cw - 1, 0),
            ),
        );
        sat_parts.insert(0, sat.e());
        ovf_terms.push(ovf.e());
    }
    let point = Signal::assigned(items, "pe_sel", point_bits(t.wd), Expr::concat(sat_parts));
    let ov = Signal::assigned(items, "pe_sel_ov", 1, or_all(ovf_terms));
    Selected { point, ov, zs }
}

/// The move of the written point against its stored value.
struct Displacement {
    /// `new_<axis>`: the written coordinate.
    new: Vec<Signal>,
    /// `adiff_<axis>`: |new − old| per axis.
    adiff: Vec<Signal>,
    /// `wb_big`: the L∞ move exceeds the threshold.
    big: Signal,
}

/// Write-back displacement: per-axis |new − old| and the threshold test.
fn displacement(t: &Dims<'_>, sel: &Selected, items: &mut Vec<Item>) -> Displacement {
    let cw = t.wd.coord;
    let dispw = cw + 1;
    let (mut new, mut adiff, mut big_terms) = (Vec::new(), Vec::new(), Vec::new());
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let (hi, lo) = (cw * (a as u32 + 1) - 1, cw * a as u32);
        let nw = Signal::assigned(items, format!("new_{axis}"), cw, sel.point.slice(hi, lo));
        let old = Expr::slice("rd_a", hi, lo);
        let ow = Signal::assigned(items, format!("old_{axis}"), cw, old);
        let wide = |s: &Signal| crate::pe::sext(s.name(), cw, dispw);
        let delta = wide(&nw).minus(wide(&ow));
        let diff = Signal::assigned(items, format!("diff_{axis}"), dispw, delta);
        let abs = Signal::assigned(
            items,
            format!("adiff_{axis}"),
            dispw,
            Expr::mux(
                diff.bit(dispw - 1),
                diff.e().inv().plus(lit(dispw, 1)),
                diff.e(),
            ),
        );
        big_terms.push(Expr::bin(
            BinaryOp::Gt,
            abs.e(),
            lit(dispw, t.p.platform.threshold_lsb.into()),
        ));
        new.push(nw);
        adiff.push(abs);
    }
    items.push(Item::Comment(
        "wb_big: L-infinity displacement of the written point exceeds the threshold".into(),
    ));
    let big = Signal::assigned(items, "wb_big", 1, or_all(big_terms));
    Displacement { new, adiff, big }
}

/// The write-back decision and the round's accumulated flags of the written path.
struct WritebackFlags {
    /// Commit the PE's result (write-back state, a job, path not frozen).
    go: Signal,
    /// Some point of the path moved more than the threshold this round.
    any_big: Signal,
    /// Some point of the path had a zero distance sum this round.
    any_dz: Signal,
    /// Some point of the path saturated this round.
    any_ov: Signal,
    /// Some point of the path left its box this round (early stopping only).
    any_lb: Option<Signal>,
}

/// Write-back flags: a path is frozen once converged, degenerate, saturated or (early
/// stopping) left its box; the `any_*` flags fold this job into its round's flags.
fn writeback_flags(
    sel: &Selected,
    disp: &Displacement,
    wb_lb: Option<Signal>,
    items: &mut Vec<Item>,
) -> WritebackFlags {
    let at_wb = |v: &str| Expr::id(v).at(id("wb_q_path"));
    let frozen_sig = Signal::wire(items, "wb_frozen", 1);
    let mut frozen = or(or(at_wb("conv"), at_wb("dz")), at_wb("ov"));
    let any_lb = wb_lb.map(|lb| {
        frozen = or(frozen.clone(), at_wb("lb"));
        Signal::assigned(items, "any_lb", 1, or(at_wb("plb"), lb.e()))
    });
    items.push(Item::Assign(frozen_sig.e(), frozen));
    let go = Signal::assigned(
        items,
        "wb_go",
        1,
        state_is(S_WB).and(id("wb_q_en")).and(frozen_sig.e().lnot()),
    );
    let any_big = Signal::assigned(items, "any_big", 1, or(at_wb("pbig"), disp.big.e()));
    let any_dz = Signal::assigned(items, "any_dz", 1, or(at_wb("pdz"), sel.zs.e()));
    let any_ov = Signal::assigned(items, "any_ov", 1, or(at_wb("pov"), sel.ov.e()));
    WritebackFlags {
        go,
        any_big,
        any_dz,
        any_ov,
        any_lb,
    }
}

/// Coordinate updater-buffer, write side: the host's point writes while idle, the selected
/// PE's result into the other bank at write-back; both memory copies take every write.
fn updater_write_port(
    bus: &Decode,
    ports: &UpdaterPorts,
    sel: &Selected,
    flags: &WritebackFlags,
    items: &mut Vec<Item>,
) {
    // `st_<axis>` hold the millimetre words' kept bits already (`mm_width`).
    let host_point = Expr::concat(vec![
        id("st_z"),
        Expr::slice("avs_writedata", 23, 16),
        id("st_y"),
        Expr::slice("avs_writedata", 15, 8),
        id("st_x"),
        Expr::slice("avs_writedata", 7, 0),
    ]);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(ports.wr_en.e(), bus.pt_we.e().or(flags.go.e())),
        Stmt::Blocking(ports.wr_addr.e(), bus_cell(bus)),
        Stmt::Blocking(ports.wr_data.e(), host_point),
        Stmt::If(
            state_is(S_WB),
            vec![
                Stmt::Blocking(
                    ports.wr_addr.e(),
                    Expr::concat(vec![
                        id("wb_q_point"),
                        Expr::id("cur").at(id("wb_q_path")).inv(),
                    ]),
                ),
                Stmt::Blocking(ports.wr_data.e(), sel.point.e()),
            ],
            vec![],
        ),
    ]));
    for (mem, rd, addr) in [
        ("pm_a", "rd_a", &ports.ra_addr),
        ("pm_b", "rd_b", &ports.rb_addr),
    ] {
        items.push(Item::AlwaysFf(vec![
            Stmt::If(
                ports.wr_en.e(),
                vec![nb(Expr::id(mem).at(ports.wr_addr.e()), ports.wr_data.e())],
                vec![],
            ),
            nb(id(rd), Expr::id(mem).at(addr.e())),
        ]));
    }
}

/// PE matrix and operand load: one instance per platform instance; the operands (previous and
/// next point, or the transmitter/receiver at a path's ends) are broadcast one instance per
/// cycle, memory data one cycle after the address, and the addressed PE latches them.
fn pe_matrix(t: &Dims<'_>, pe: &[PeWires], items: &mut Vec<Item>) {
    let start = Signal::assigned(
        items,
        "pe_start",
        1,
        state_is(S_EXEC).and(id("cnt").eq(lit(t.cnt_bits, 0))),
    );
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
                ("start".into(), start.e()),
                ("s_prev".into(), prev.e()),
                ("s_next".into(), next.e()),
                ("s_sum".into(), w.sum.e()),
                ("zero_sum".into(), w.zs.e()),
            ],
        });
        operands.push(Item::Assign(
            w.load.e(),
            state_is(S_LOAD)
                .and(id("ld_q_en"))
                .and(id("ld_q_inst").eq(lit(t.ib, j as u128))),
        ));
    }
    items.extend(operands);
}

/// `cnt + 1`.
fn cnt_inc(t: &Dims<'_>) -> Expr {
    id("cnt").plus(lit(t.cnt_bits, 1))
}

/// IDLE on a start request: clear the counters and every path's flags and rounds and let the
/// dispatcher build the first slot (the queue holds every path's first group); with no path,
/// report done at once.
fn fsm_on_start(t: &Dims<'_>) -> Vec<Stmt> {
    let all_zero = lit(t.np2, 0);
    let no_path = id("paths_r").eq(lit(t.pb + 1, 0));
    let mut on_start = vec![
        nb(
            id("state"),
            Expr::mux(
                no_path.clone(),
                lit(STATE_BITS, S_IDLE),
                lit(STATE_BITS, S_DISP),
            ),
        ),
        nb(id("cnt"), lit(t.cnt_bits, 0)),
        nb(id("rsel"), lit(1, 0)),
        nb(id("cycles"), lit(32, 0)),
        nb(id("done"), no_path),
    ];
    for v in ["cur", "conv", "dz", "ov", "pbig", "pdz", "pov"] {
        on_start.push(nb(id(v), all_zero.clone()));
    }
    if t.early.is_some() {
        on_start.push(nb(id("lb"), all_zero.clone()));
        on_start.push(nb(id("plb"), all_zero.clone()));
    }
    on_start.push(nb(id("rvalid"), all_zero));
    on_start
}

/// The next slot's length (the buffer the dispatcher wrote: not `rsel`).
fn next_len(t: &Dims<'_>) -> Expr {
    Expr::mux(id("rsel"), id("slen_0"), id("slen_1")).eq(lit(t.ib + 1, 0))
}

/// DISP: wait for the dispatcher; run the slot it built, or report done if it found none
/// (nothing queued, nothing running).
fn fsm_disp(t: &Dims<'_>) -> Vec<Stmt> {
    vec![Stmt::If(
        dstate_is(D_OFF),
        vec![Stmt::If(
            next_len(t),
            vec![
                nb(id("state"), lit(STATE_BITS, S_IDLE)),
                nb(id("done"), lit(1, 1)),
            ],
            vec![
                nb(id("state"), lit(STATE_BITS, S_LOAD)),
                nb(id("rsel"), id("rsel").inv()),
                nb(id("cnt"), lit(t.cnt_bits, 0)),
            ],
        )],
        vec![],
    )]
}

/// LOAD: register the slot's entries for the operand broadcast until its tail, then EXEC
/// (the dispatcher starts on the next slot at the same edge).
fn fsm_load(t: &Dims<'_>, rom: &ScheduleRead) -> Vec<Stmt> {
    let mut stmts = register_entry(&[
        ("ld_q_en", &rom.valid),
        ("ld_q_tail", &rom.tail),
        ("ld_q_first", &rom.first),
        ("ld_q_last", &rom.last),
        ("ld_q_inst", &rom.inst),
    ]);
    stmts.push(Stmt::If(
        id("ld_q_tail"),
        vec![
            nb(id("state"), lit(STATE_BITS, S_EXEC)),
            nb(id("cnt"), lit(t.cnt_bits, 0)),
        ],
        vec![nb(id("cnt"), cnt_inc(t))],
    ));
    stmts
}

/// Registers the schedule entry's fields: one `register <= field` per pair, in order.
fn register_entry(pairs: &[(&str, &Signal)]) -> Vec<Stmt> {
    pairs
        .iter()
        .map(|(reg, field)| nb(id(reg), field.e()))
        .collect()
}

/// EXEC: wait the PE latency ([`pe_latency`]) and for the dispatcher, then WB.
fn fsm_exec(t: &Dims<'_>) -> Vec<Stmt> {
    vec![Stmt::If(
        id("cnt").eq(lit(t.cnt_bits, u128::from(t.latency() - 1))),
        vec![Stmt::If(
            dstate_is(D_OFF),
            vec![
                nb(id("state"), lit(STATE_BITS, S_WB)),
                nb(id("cnt"), lit(t.cnt_bits, 0)),
            ],
            vec![],
        )],
        vec![nb(id("cnt"), cnt_inc(t))],
    )]
}

/// A committed job's effect on its path's flags: at the round's end, flip the bank, count the
/// round and decide convergence; inside the round, accumulate the flags.
fn path_commit(f: &WritebackFlags) -> Vec<Stmt> {
    let wbp = |v: &str| Expr::id(v).at(id("wb_q_path"));
    let mut conv_next = f
        .any_big
        .e()
        .lnot()
        .and(f.any_dz.e().lnot())
        .and(f.any_ov.e().lnot());
    let mut at_end = Vec::new();
    let mut in_round = Vec::new();
    if let Some(any_lb) = &f.any_lb {
        conv_next = conv_next.and(any_lb.e().lnot());
        at_end.push(nb(
            wbp("lb"),
            any_lb.e().and(f.any_dz.e().lnot()).and(f.any_ov.e().lnot()),
        ));
        at_end.push(nb(wbp("plb"), lit(1, 0)));
        in_round.push(nb(wbp("plb"), any_lb.e()));
    }
    vec![Stmt::If(
        id("wb_q_end"),
        vec![
            nb(wbp("cur"), wbp("cur").inv()),
            nb(wbp("rvalid"), lit(1, 1)),
            nb(wbp("dz"), f.any_dz.e()),
            nb(wbp("ov"), f.any_ov.e()),
            nb(wbp("conv"), conv_next),
            nb(wbp("pbig"), lit(1, 0)),
            nb(wbp("pdz"), lit(1, 0)),
            nb(wbp("pov"), lit(1, 0)),
        ]
        .into_iter()
        .chain(at_end)
        .collect(),
        vec![
            nb(wbp("pbig"), f.any_big.e()),
            nb(wbp("pdz"), f.any_dz.e()),
            nb(wbp("pov"), f.any_ov.e()),
        ]
        .into_iter()
        .chain(in_round)
        .collect(),
    )]
}

/// WB: register the entry for the write-back, commit, and at the slot's tail run the slot
/// the dispatcher built, or dispatch now if it found none while paths are queued, or stop.
fn fsm_writeback(
    t: &Dims<'_>,
    rom: &ScheduleRead,
    f: &WritebackFlags,
    queue_empty: &Signal,
) -> Vec<Stmt> {
    let mut stmts = register_entry(&[
        ("wb_q_en", &rom.valid),
        ("wb_q_tail", &rom.tail),
        ("wb_q_end", &rom.end),
        ("wb_q_path", &rom.path),
        ("wb_q_point", &rom.point),
        ("wb_q_inst", &rom.inst),
        ("wb_q_gtail", &rom.gtail),
        ("wb_q_src", &rom.src),
        ("wb_q_gbase", &rom.gbase),
    ]);
    let after = Stmt::If(
        next_len(t),
        vec![Stmt::If(
            queue_empty.e(),
            vec![
                nb(id("state"), lit(STATE_BITS, S_IDLE)),
                nb(id("done"), lit(1, 1)),
            ],
            vec![nb(id("state"), lit(STATE_BITS, S_DISP))],
        )],
        vec![
            nb(id("state"), lit(STATE_BITS, S_LOAD)),
            nb(id("rsel"), id("rsel").inv()),
        ],
    );
    stmts.extend([
        Stmt::If(f.go.e(), path_commit(f), vec![]),
        Stmt::If(
            id("wb_q_tail"),
            vec![nb(id("cnt"), lit(t.cnt_bits, 0)), after],
            vec![nb(id("cnt"), cnt_inc(t))],
        ),
    ]);
    stmts
}

/// The start request and the dispatcher's trigger: at a start, when a slot's PEs start
/// (LOAD's tail) and when a slot ends with no next slot while paths are queued. Returns
/// `(start_req, d_go, d_scan_init, queue_empty)`.
fn dispatch_triggers(t: &Dims<'_>, wb_push: &Signal, items: &mut Vec<Item>) -> [Signal; 4] {
    let pb = t.pb;
    let start_req = Signal::assigned(
        items,
        "start_req",
        1,
        id("avs_write")
            .and(id("avs_address").eq(lit(t.ab, 0)))
            .and(Expr::bit("avs_writedata", 0))
            .and(state_is(S_IDLE)),
    );
    let queued = Signal::assigned(
        items,
        "rq_after",
        pb + 1,
        Expr::mux(
            wb_push.e(),
            id("rq_count").plus(lit(pb + 1, 1)),
            id("rq_count"),
        ),
    );
    let empty = Signal::assigned(items, "rq_empty", 1, queued.e().eq(lit(pb + 1, 0)));
    let at_wb_tail = state_is(S_WB)
        .and(id("wb_q_tail"))
        .and(next_len(t))
        .and(empty.e().lnot());
    let go = Signal::assigned(
        items,
        "d_go",
        1,
        or(
            or(
                start_req.e().and(id("paths_r").eq(lit(pb + 1, 0)).lnot()),
                state_is(S_LOAD).and(id("ld_q_tail")),
            ),
            at_wb_tail,
        ),
    );
    let limit = u128::from(crate::dispatch::SCAN_LIMIT.min(1 << pb));
    let count = Expr::mux(start_req.e(), id("paths_r"), queued.e());
    let scan = Signal::assigned(items, "d_scan_init", pb + 1, count);
    let capped = Signal::assigned(
        items,
        "d_scan_cap",
        pb + 1,
        Expr::mux(
            Expr::bin(BinaryOp::Gt, scan.e(), lit(pb + 1, limit)),
            lit(pb + 1, limit),
            scan.e(),
        ),
    );
    [start_req, go, capped, empty]
}

/// The main FSM (controller): IDLE -> DISP -> per slot LOAD, EXEC, WB -> ... -> IDLE with
/// done, and the cycle counter.
fn controller(
    t: &Dims<'_>,
    rom: &ScheduleRead,
    f: &WritebackFlags,
    [start_req, empty]: [&Signal; 2],
    items: &mut Vec<Item>,
) {
    let cnt_bits = t.cnt_bits;
    items.push(Item::Comment(format!(
        "main FSM: IDLE -> DISP -> per slot LOAD (jobs + 2) EXEC (max({}, dispatch + 1)) WB (jobs + 2) -> IDLE with done when no path is queued",
        t.latency()
    )));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![
            nb(id("state"), lit(STATE_BITS, S_IDLE)),
            nb(id("cnt"), lit(cnt_bits, 0)),
            nb(id("rsel"), lit(1, 0)),
            nb(id("cycles"), lit(32, 0)),
            nb(id("done"), lit(1, 0)),
            nb(id("ld_q_en"), lit(1, 0)),
            nb(id("ld_q_tail"), lit(1, 0)),
            nb(id("wb_q_en"), lit(1, 0)),
            nb(id("wb_q_tail"), lit(1, 0)),
            nb(id("rvalid"), lit(t.np2, 0)),
        ],
        vec![
            Stmt::If(
                Expr::bin(BinaryOp::Ne, id("state"), lit(STATE_BITS, S_IDLE)),
                vec![nb(id("cycles"), id("cycles").plus(lit(32, 1)))],
                vec![],
            ),
            Stmt::Case(
                id("state"),
                vec![
                    (
                        lit(STATE_BITS, S_IDLE),
                        vec![Stmt::If(start_req.e(), fsm_on_start(t), vec![])],
                    ),
                    (lit(STATE_BITS, S_DISP), fsm_disp(t)),
                    (lit(STATE_BITS, S_LOAD), fsm_load(t, rom)),
                    (lit(STATE_BITS, S_EXEC), fsm_exec(t)),
                    (lit(STATE_BITS, S_WB), fsm_writeback(t, rom, f, empty)),
                ],
                vec![nb(id("state"), lit(STATE_BITS, S_IDLE))],
            ),
        ],
    )]));
}

/// Avalon-MM slave, writes: the transmitter, receiver and slot-count registers and the
/// staging words of a point (its last word, the fractions, goes to the point memory).
fn register_writes(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
    let (ab, pb) = (t.ab, t.pb);
    let wr = |addr: u32, reg: &str| {
        Stmt::If(
            id("avs_address").eq(lit(ab, addr.into())),
            vec![nb(id(reg), id("avs_writedata"))],
            vec![],
        )
    };
    items.push(Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![
            nb(id("tx_x"), lit(32, 0)),
            nb(id("tx_y"), lit(32, 0)),
            nb(id("tx_z"), lit(32, 0)),
            nb(id("rx_x"), lit(32, 0)),
            nb(id("rx_y"), lit(32, 0)),
            nb(id("rx_z"), lit(32, 0)),
            nb(id("paths_r"), lit(pb + 1, 0)),
            nb(id("cap_r"), lit(16, 0)),
        ],
        vec![Stmt::If(
            bus.host_wr.e(),
            vec![
                wr(4, "tx_x"),
                wr(5, "tx_y"),
                wr(6, "tx_z"),
                wr(8, "rx_x"),
                wr(9, "rx_y"),
                wr(10, "rx_z"),
                Stmt::If(
                    id("avs_address").eq(lit(ab, crate::regs::PATHS.into())),
                    vec![nb(id("paths_r"), Expr::slice("avs_writedata", pb, 0))],
                    vec![],
                ),
                Stmt::If(
                    id("avs_address").eq(lit(ab, crate::regs::ROUND_CAP.into())),
                    vec![nb(id("cap_r"), Expr::slice("avs_writedata", 15, 0))],
                    vec![],
                ),
                Stmt::If(
                    bus.is_point.e(),
                    vec![Stmt::Case(
                        Expr::slice("avs_address", 1, 0),
                        vec![
                            (
                                lit(2, 0),
                                vec![nb(id("st_x"), mm_bits("avs_writedata", t.wd))],
                            ),
                            (
                                lit(2, 1),
                                vec![nb(id("st_y"), mm_bits("avs_writedata", t.wd))],
                            ),
                            (
                                lit(2, 2),
                                vec![nb(id("st_z"), mm_bits("avs_writedata", t.wd))],
                            ),
                        ],
                        vec![],
                    )],
                    vec![],
                ),
            ],
            vec![],
        )],
    )]));
}

/// Avalon-MM slave, pipelined reads with a fixed latency of 2 (address -> registered select ->
/// readdata). Returns the read multiplexer's register, declared after the pipeline.
fn read_pipeline(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) -> Signal {
    let mut mux_decl = Vec::new();
    let read_mux = Signal::reg(&mut mux_decl, "read_mux", 32);
    items.push(Item::AlwaysFf(vec![Stmt::If(
        id("rst_n").lnot(),
        vec![
            nb(id("rq_valid"), lit(1, 0)),
            nb(id("avs_readdatavalid"), lit(1, 0)),
            nb(id("avs_readdata"), lit(32, 0)),
        ],
        vec![
            nb(id("rq_valid"), id("avs_read")),
            nb(
                id("rq_kind"),
                Expr::mux(
                    bus.is_ctrl.e(),
                    lit(2, 1),
                    Expr::mux(
                        bus.is_status.e(),
                        lit(2, 2),
                        Expr::mux(bus.is_point.e(), lit(2, 3), lit(2, 0)),
                    ),
                ),
            ),
            nb(id("rq_reg"), Expr::slice("avs_address", 3, 0)),
            nb(id("rq_word"), Expr::slice("avs_address", 1, 0)),
            nb(id("rq_path"), Expr::slice("avs_address", t.pb - 1, 0)),
            nb(id("avs_readdatavalid"), id("rq_valid")),
            nb(id("avs_readdata"), read_mux.e()),
        ],
    )]));
    items.extend(mux_decl);
    read_mux
}

/// SCHED_HI: the high bits of wide schedule entries, written by the host before the entries
/// (only in designs whose entries exceed 32 bits).
fn sched_hi_register(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
    let sw = sched_entry_bits(t.pb, t.ptb, t.ib);
    if sw <= 32 {
        return;
    }
    items.push(Item::AlwaysFf(vec![Stmt::If(
        bus.host_wr
            .e()
            .and(id("avs_address").eq(lit(t.ab, crate::regs::SCHED_HI.into()))),
        vec![nb(id("sched_hi"), Expr::slice("avs_writedata", sw - 33, 0))],
        vec![],
    )]));
}

/// The control registers' read values by word address (register map in `docs/hardware.md`).
fn control_read_arms(t: &Dims<'_>, mux: &Signal) -> Vec<(Expr, Vec<Stmt>)> {
    let platform = t.p.platform;
    let info = (t.k << 24) | (MAP_VERSION << 16) | (platform.capacity.paths & 0xffff);
    let read = |addr: u128, value: Expr| (lit(4, addr), vec![Stmt::Blocking(mux.e(), value)]);
    vec![
        read(
            0,
            Expr::concat(vec![
                lit(30, 0),
                id("done"),
                Expr::bin(BinaryOp::Ne, id("state"), lit(STATE_BITS, S_IDLE)),
            ]),
        ),
        read(1, id("cycles")),
        read(2, lit(32, info.into())),
        read(3, lit(32, platform.threshold_lsb.into())),
        read(4, id("tx_x")),
        read(5, id("tx_y")),
        read(6, id("tx_z")),
        read(8, id("rx_x")),
        read(9, id("rx_y")),
        read(10, id("rx_z")),
        read(12, Expr::concat(vec![lit(31 - t.pb, 0), id("paths_r")])),
        read(14, Expr::concat(vec![lit(16, 0), id("cap_r")])),
    ]
}

/// The read multiplexer: control registers, a path's status word, or a point's words (three
/// integer words, then the packed fractions).
fn read_mux(t: &Dims<'_>, mux: &Signal, items: &mut Vec<Item>) {
    let cw = t.wd.coord;
    let set = |value: Expr| vec![Stmt::Blocking(mux.e(), value)];
    let rqp = |v: &str| Expr::id(v).at(id("rq_path"));
    let point_arms = vec![
        (lit(2, 0), set(sext_slice("rd_a", cw - 1, 8, 32))),
        (lit(2, 1), set(sext_slice("rd_a", 2 * cw - 1, cw + 8, 32))),
        (
            lit(2, 2),
            set(sext_slice("rd_a", 3 * cw - 1, 2 * cw + 8, 32)),
        ),
    ];
    let frac_word = Expr::concat(vec![
        lit(8, 0),
        Expr::slice("rd_a", 2 * cw + 7, 2 * cw),
        Expr::slice("rd_a", cw + 7, cw),
        Expr::slice("rd_a", 7, 0),
    ]);
    let status_word = Expr::concat(vec![
        // `rounds_q` holds rounds[rq_path]: read with the request's address while idle.
        Expr::mux(
            Expr::id("rvalid").at(id("rq_path")),
            id("rounds_q"),
            lit(16, 0),
        ),
        lit(12, 0),
        if t.early.is_some() {
            rqp("lb")
        } else {
            lit(1, 0)
        },
        rqp("ov"),
        rqp("dz"),
        rqp("conv"),
    ]);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(mux.e(), lit(32, 0)),
        Stmt::Case(
            id("rq_kind"),
            vec![
                (
                    lit(2, 1),
                    vec![Stmt::Case(
                        id("rq_reg"),
                        control_read_arms(t, mux),
                        set(lit(32, 0)),
                    )],
                ),
                (lit(2, 2), set(status_word)),
                (
                    lit(2, 3),
                    vec![Stmt::Case(id("rq_word"), point_arms, set(frac_word))],
                ),
            ],
            set(lit(32, 0)),
        ),
    ]));
}

/// The interrupt (`ins_irq = done`) and `bt_unused_ok`, which reads the bits no block uses so
/// the linter sees them consumed on purpose.
fn interrupt_and_unused(items: &mut Vec<Item>) {
    items.push(Item::Assign(id("ins_irq"), id("done")));
    // The slot buffer's `valid` bit: every entry below the slot's length is a job.
    let unused = vec![
        lit(1, 0),
        Expr::slice("avs_writedata", 31, 1),
        Expr::bit("sched_q", 0),
    ];
    items.push(Item::Wire("bt_unused_ok".into(), 1));
    items.push(Item::Assign(
        id("bt_unused_ok"),
        Expr::Unary(UnaryOp::ReduceAnd, Box::new(Expr::concat(unused))),
    ));
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

/// The widened polygon box of the written instance's plane, per axis (sign bit flipped).
struct InstanceBox {
    /// `box_lo_<axis>`.
    lo: Vec<Signal>,
    /// `box_hi_<axis>`.
    hi: Vec<Signal>,
}

/// Early stopping, box table: the box of the instance being written (`wb_q_inst`), its
/// constants biased by 2^47 so that signed comparisons become unsigned ones.
fn instance_box(
    d: &TopParams<'_>,
    boxes: &[bt_fixed::FineBox],
    items: &mut Vec<Item>,
) -> InstanceBox {
    let w = BOX_BITS;
    let bias = 1i128 << (w - 1);
    let biased = |v: i64| lit(w, ((i128::from(v) + bias) as u128) & ((1u128 << w) - 1));
    let (mut lo, mut hi, mut defaults) = (Vec::new(), Vec::new(), Vec::new());
    for axis in ["x", "y", "z"] {
        lo.push(Signal::reg(items, format!("box_lo_{axis}"), w));
        hi.push(Signal::reg(items, format!("box_hi_{axis}"), w));
    }
    for (l, h) in lo.iter().zip(&hi) {
        defaults.push(Stmt::Blocking(l.e(), lit(w, 0)));
        defaults.push(Stmt::Blocking(h.e(), lit(w, 0)));
    }
    let arms = d
        .platform
        .instances
        .iter()
        .enumerate()
        .map(|(j, inst)| {
            let b = &boxes[inst.plane as usize];
            let mut stmts = Vec::new();
            for a in 0..3 {
                stmts.push(Stmt::Blocking(lo[a].e(), biased(b.lo[a])));
                stmts.push(Stmt::Blocking(hi[a].e(), biased(b.hi[a])));
            }
            (lit(d.layout.inst_bits, j as u128), stmts)
        })
        .collect();
    items.push(Item::Comment(
        "early stopping: widened polygon box of the written instance's plane (sign bit flipped)"
            .into(),
    ));
    items.push(Item::AlwaysComb(vec![Stmt::Case(
        id("wb_q_inst"),
        arms,
        defaults,
    )]));
    InstanceBox { lo, hi }
}

/// Early stopping at write-back (twin of `bt_fixed::FineBox::outside` and the `min_rounds`
/// rule of `FixedIpc::run_path`): `wb_lb` = the written point lies outside its instance's
/// widened box by more than `(L1 move) << shift`, in a round ≥ `min_rounds`. Signed 48-bit
/// comparisons are unsigned ones with the sign bit flipped (the box constants are flipped
/// when generated).
fn early_stop_logic(
    d: &TopParams<'_>,
    stop: &bt_fixed::EarlyStop,
    boxes: &[bt_fixed::FineBox],
    disp: &Displacement,
    items: &mut Vec<Item>,
) -> Signal {
    let w = BOX_BITS;
    let axes = ["x", "y", "z"];
    let bx = instance_box(d, boxes, items);
    let cw = d.model.coord_bits();
    let dispw = cw + 1;
    let mvw = w - bt_fixed::EarlyStop::MAX_SHIFT;
    let zext = |s: &Signal| Expr::concat(vec![lit(mvw - dispw, 0), s.e()]);
    items.push(Item::Wire("mv_l1".into(), mvw));
    items.push(Item::Assign(
        id("mv_l1"),
        zext(&disp.adiff[0])
            .plus(zext(&disp.adiff[1]))
            .plus(zext(&disp.adiff[2])),
    ));
    let shift = stop.displacement_shift;
    items.push(Item::Wire("slack".into(), w));
    let mut parts = vec![lit(w - mvw - shift, 0), id("mv_l1")];
    if shift > 0 {
        parts.push(lit(shift, 0));
    }
    items.push(Item::Assign(id("slack"), Expr::concat(parts)));
    let mut terms = Vec::new();
    for (a, (axis, new)) in axes.iter().zip(&disp.new).enumerate() {
        let pw = format!("bp_{axis}");
        items.push(Item::Wire(pw.clone(), w));
        items.push(Item::Assign(id(&pw), crate::pe::sext(new.name(), cw, w)));
        for (side, expr) in [
            ("lo", id(&pw).plus(id("slack"))),
            ("hi", id(&pw).minus(id("slack"))),
        ] {
            let n = format!("bq_{side}_{axis}");
            items.push(Item::Wire(n.clone(), w));
            items.push(Item::Assign(id(&n), expr));
            let flipped = Expr::concat(vec![Expr::bit(&n, w - 1).inv(), Expr::slice(&n, w - 2, 0)]);
            let op = if side == "lo" {
                BinaryOp::Lt
            } else {
                BinaryOp::Gt
            };
            let bound = if side == "lo" { &bx.lo[a] } else { &bx.hi[a] };
            terms.push(Expr::bin(op, flipped, bound.e()));
        }
    }
    let outside = or_all(terms);
    let late = if stop.min_rounds >= 2 {
        Expr::bin(
            BinaryOp::Gt,
            id("rounds_cur"),
            lit(16, u128::from(stop.min_rounds - 2)),
        )
    } else {
        lit(1, 1)
    };
    items.push(Item::Comment(format!(
        "wb_lb: outside the box by more than (L1 move) << {shift}, in round >= {}",
        stop.min_rounds
    )));
    Signal::assigned(items, "wb_lb", 1, late.and(outside))
}
