//! The controller of `bt_top`: job memory, ready queue, dispatcher, slot buffer and the main
//! FSM (twin: `crate::dispatch::predict`).

use super::*;

/// Dispatcher state encodings (`dstate`): idle, read the queue's head once, pop a queued
/// group (reading its first job), examine its jobs, publish the slot's length.
pub(super) const D_OFF: u128 = 0;
pub(super) const D_POP: u128 = 1;
pub(super) const D_WARM: u128 = 2;
pub(super) const D_JOB: u128 = 3;
pub(super) const D_FIN: u128 = 4;
pub(super) const DSTATE_BITS: u32 = 3;

/// The ready queue's pointers and head word, and the dispatcher's registers.
pub(super) fn declare_dispatch_state(t: &Dims<'_>, items: &mut Vec<Item>) {
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

/// The fields of the slot-buffer entry read this cycle (`sched_q`, gated by `sq_ok`).
pub(super) struct ScheduleRead {
    /// The entry is a job of the running slot.
    pub(super) valid: Signal,
    /// The slot's last entry.
    pub(super) tail: Signal,
    /// `valid` and `tail` for write-back: not an entry of the next slot read ahead for its
    /// load.
    pub(super) wb_valid: Signal,
    pub(super) wb_tail: Signal,
    /// The entry is for the load (read in LOAD, or read ahead in write-back's last cycles).
    pub(super) load: Signal,
    /// Path, point (global index) and PE column of the job.
    pub(super) path: Signal,
    pub(super) point: Signal,
    pub(super) inst: Signal,
    /// The job's previous point is the transmitter.
    pub(super) first: Signal,
    /// The job's next point is the receiver.
    pub(super) last: Signal,
    /// The job closes its path's round.
    pub(super) end: Signal,
    /// The job runs after its round's first phase (red-black): its neighbours' points are
    /// read from the bank the round writes, not the committed one.
    pub(super) late: Signal,
    /// The job is its group's last: its write-back queues the path's next group.
    pub(super) gtail: Signal,
    /// The job's entry in the job memory, and its path's first group's.
    pub(super) src: Signal,
    pub(super) gbase: Signal,
}

/// The bit of the job word that marks a group's last job.
pub(super) fn gtail_bit(t: &Dims<'_>) -> u32 {
    5 + t.pb + t.ptb
}

/// Job memory (M9K), written by the host per step: one round of every path as groups
/// (`{column, tail, late, end, last, first, point, path, valid}`, `tail` on a group's last
/// job), path after path. Read by the dispatcher only (`job_q`, one cycle after the address).
pub(super) fn job_memory(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
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
pub(super) fn slot_buffer_read(t: &Dims<'_>, items: &mut Vec<Item>) -> ScheduleRead {
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
    let in_slot = Signal::assigned(
        items,
        "sb_in",
        1,
        Expr::bin(BinaryOp::Lt, cnt_w.clone(), len_w.clone()),
    );
    let is_last = cnt_w.clone().plus(lit(w, 1)).eq(len_w.clone());
    // Write-back's last two cycles leave the buffer's read port free: they read the next
    // slot's first two entries, so its load starts with them in hand (`sq_ld` marks them).
    let next_len = Signal::assigned(
        items,
        "slen_nxt",
        ib + 1,
        Expr::mux(id("rsel"), id("slen_0"), id("slen_1")),
    );
    let prefetch = Signal::assigned(items, "sb_pf", 1, state_is(S_WB).and(in_slot.e().lnot()));
    let pf_idx = Signal::assigned(items, "sb_pf_idx", w, cnt_w.minus(len_w));
    let nlen_w = zero_extend(next_len.name(), ib + 1, w);
    let pf_in = Expr::bin(BinaryOp::Lt, pf_idx.e(), nlen_w.clone());
    let pf_last = pf_idx.e().plus(lit(w, 1)).eq(nlen_w);
    let sb_ra = Signal::assigned(
        items,
        "sb_ra",
        ib + 1,
        Expr::mux(
            prefetch.e(),
            Expr::concat(vec![
                id("rsel").inv(),
                Expr::slice(pf_idx.name(), ib - 1, 0),
            ]),
            Expr::concat(vec![id("rsel"), zero_extend("cnt", cnt_bits, ib)]),
        ),
    );
    items.push(Item::AlwaysFf(vec![
        nb(id("sched_q"), Expr::id("sbuf").at(sb_ra.e())),
        nb(
            id("sq_ok"),
            or(
                or(state_is(S_LOAD), state_is(S_WB)).and(in_slot.e()),
                prefetch.e().and(pf_in),
            ),
        ),
        nb(id("sq_tail"), Expr::mux(prefetch.e(), pf_last, is_last)),
        nb(id("sq_ld"), or(state_is(S_LOAD), prefetch.e())),
    ]));
    let field = |items: &mut Vec<Item>, n: &str, w: u32, lo: u32| {
        Signal::assigned(items, n, w, Expr::slice("sched_q", lo + w - 1, lo))
    };
    let valid = Signal::assigned(items, "rom_valid", 1, id("sq_ok"));
    let tail = Signal::assigned(items, "rom_tail", 1, id("sq_ok").and(id("sq_tail")));
    let wb_valid = Signal::assigned(
        items,
        "rom_wb_valid",
        1,
        id("sq_ok").and(id("sq_ld").lnot()),
    );
    let wb_tail = Signal::assigned(items, "rom_wb_tail", 1, wb_valid.e().and(id("sq_tail")));
    ScheduleRead {
        valid,
        tail,
        wb_valid,
        wb_tail,
        load: Signal::assigned(items, "rom_ld", 1, id("sq_ld")),
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
pub(super) struct DispatchJob {
    pub(super) gtail: Signal,
    pub(super) conflict: Signal,
    /// Pop the queue's head this cycle.
    pub(super) pop: Signal,
    /// Put the examined group back at the queue's tail this cycle.
    pub(super) push_back: Signal,
}

/// The dispatcher's combinational signals.
pub(super) fn dispatch_signals(t: &Dims<'_>, items: &mut Vec<Item>) -> DispatchJob {
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
pub(super) fn dispatcher(t: &Dims<'_>, d: &DispatchJob, go: &Signal, scan_init: &Signal) -> Item {
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
pub(super) fn slot_buffer_write(t: &Dims<'_>, d: &DispatchJob, items: &mut Vec<Item>) {
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

/// The ready queue (`rq`): a circular buffer of `{first group, next group}` per queued
/// path, written by the host while idle (PATH_BASE[p] = path p's entry), then by the
/// dispatcher's push-backs at the tail and write-back's pushes at the head (never in the same
/// cycle); read at the head.
pub(super) fn ready_queue(
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
    // Write-back queues a path's next group at the head (the running paths first: a long
    // chain is not held up behind every waiting path), the dispatcher's push-backs at the tail.
    let head_before = id("rq_head").minus(lit(pb, 1));
    let addr = Expr::mux(
        bus.host_wr.e(),
        Expr::slice("avs_address", pb - 1, 0),
        Expr::mux(wb_push.e(), head_before.clone(), id("rq_tail")),
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
                    vec![Stmt::If(
                        wb_push.e(),
                        vec![nb(id("rq_head"), head_before)],
                        vec![],
                    )],
                ),
                Stmt::If(
                    d.push_back.e(),
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

/// `cnt + 1`.
pub(super) fn cnt_inc(t: &Dims<'_>) -> Expr {
    id("cnt").plus(lit(t.cnt_bits, 1))
}

/// IDLE on a start request: clear the counters and every path's flags and rounds and let the
/// dispatcher build the first slot (the queue holds every path's first group); with no path,
/// report done at once.
pub(super) fn fsm_on_start(t: &Dims<'_>) -> Vec<Stmt> {
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
pub(super) fn next_len(t: &Dims<'_>) -> Expr {
    Expr::mux(id("rsel"), id("slen_0"), id("slen_1")).eq(lit(t.ib + 1, 0))
}

/// DISP: wait for the dispatcher; run the slot it built, or report done if it found none
/// (nothing queued, nothing running).
pub(super) fn fsm_disp(t: &Dims<'_>) -> Vec<Stmt> {
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
/// (the dispatcher has been building the next slot since LOAD began).
pub(super) fn fsm_load(t: &Dims<'_>, rom: &ScheduleRead) -> Vec<Stmt> {
    let mut stmts = register_load_entry(rom);
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

/// Registers the entry's fields for the operand broadcast.
fn register_load_entry(rom: &ScheduleRead) -> Vec<Stmt> {
    register_entry(&[
        ("ld_q_en", &rom.valid),
        ("ld_q_tail", &rom.tail),
        ("ld_q_first", &rom.first),
        ("ld_q_last", &rom.last),
        ("ld_q_inst", &rom.inst),
    ])
}

/// Registers the schedule entry's fields: one `register <= field` per pair, in order.
pub(super) fn register_entry(pairs: &[(&str, &Signal)]) -> Vec<Stmt> {
    pairs
        .iter()
        .map(|(reg, field)| nb(id(reg), field.e()))
        .collect()
}

/// EXEC: wait until the slot's last PE has run the PE latency ([`pe_latency`]) less the
/// slot's other loads and the two cycles write-back takes from reading an entry to taking its
/// PE's result (each PE started after its own load, and write-back reads the jobs in load
/// order, one a cycle: `cnt + jobs + 2 >= latency`, at least one cycle) and for the
/// dispatcher, then WB.
pub(super) fn fsm_exec(t: &Dims<'_>) -> Vec<Stmt> {
    let w = t.cnt_bits.max(t.ib + 1) + 1;
    let ran = zero_extend("cnt", t.cnt_bits, w)
        .plus(zero_extend("slen_cur", t.ib + 1, w))
        .plus(lit(w, 2));
    vec![Stmt::If(
        Expr::bin(BinaryOp::Gt, ran, lit(w, u128::from(t.latency() - 1))),
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

/// WB: register the entry for the write-back, commit, and at the slot's tail run the slot
/// the dispatcher built, or dispatch now if it found none while paths are queued, or stop.
pub(super) fn fsm_writeback(
    t: &Dims<'_>,
    rom: &ScheduleRead,
    f: &WritebackFlags,
    queue_empty: &Signal,
) -> Vec<Stmt> {
    let mut stmts = register_entry(&[
        ("wb_q_en", &rom.wb_valid),
        ("wb_q_tail", &rom.wb_tail),
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
            // Its first two entries were read ahead.
            nb(id("cnt"), lit(t.cnt_bits, 2)),
        ],
    );
    stmts.extend([
        Stmt::If(rom.load.e(), register_load_entry(rom), vec![]),
        Stmt::If(f.go.e(), path_commit(f), vec![]),
        Stmt::If(
            id("wb_q_tail"),
            vec![nb(id("cnt"), lit(t.cnt_bits, 0)), after],
            vec![nb(id("cnt"), cnt_inc(t))],
        ),
    ]);
    stmts
}

/// The start request and the dispatcher's trigger: at a start, when a slot starts loading
/// (so the dispatcher has the load and the PE latency for the slot after it) and when a slot
/// ends with no next slot while paths are queued. Returns
/// `(start_req, d_go, d_scan_init, queue_empty)`.
pub(super) fn dispatch_triggers(
    t: &Dims<'_>,
    wb_push: &Signal,
    items: &mut Vec<Item>,
) -> [Signal; 4] {
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
    // A slot ends with its write-back's last entry; the next one starts loading at once when
    // the dispatcher built it (from DISP when it was built with no slot running).
    let wb_end = Signal::assigned(items, "wb_end", 1, state_is(S_WB).and(id("wb_q_tail")));
    let at_wb_tail = wb_end.e().and(next_len(t)).and(empty.e().lnot());
    let to_load = Signal::assigned(
        items,
        "to_load",
        1,
        or(wb_end.e(), state_is(S_DISP).and(dstate_is(D_OFF))).and(next_len(t).lnot()),
    );
    // The dispatcher builds the slot after next while this one loads and computes.
    let go = Signal::assigned(
        items,
        "d_go",
        1,
        or(
            or(
                start_req.e().and(id("paths_r").eq(lit(pb + 1, 0)).lnot()),
                to_load.e(),
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
pub(super) fn controller(
    t: &Dims<'_>,
    rom: &ScheduleRead,
    f: &WritebackFlags,
    [start_req, empty]: [&Signal; 2],
    items: &mut Vec<Item>,
) {
    let cnt_bits = t.cnt_bits;
    items.push(Item::Comment(format!(
        "main FSM: IDLE -> DISP -> per slot LOAD (jobs + 2, or jobs after a write-back) EXEC (max({} - jobs - 1, 1, dispatch + 1 - load): each PE starts after its own load) WB (jobs + 2) -> IDLE with done when no path is queued",
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
