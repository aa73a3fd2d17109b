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

/// The fields of the slot-buffer entry the write-back reads this cycle (`wsched_q`, gated by
/// `wq_ok`).
pub(super) struct ScheduleRead {
    /// The entry is a job of the slot being written back.
    pub(super) valid: Signal,
    /// The slot's last entry.
    pub(super) tail: Signal,
    /// Path, point (global index) and PE column of the job.
    pub(super) path: Signal,
    pub(super) point: Signal,
    pub(super) inst: Signal,
    /// The job closes its path's round.
    pub(super) end: Signal,
    /// The job is its group's last: its write-back queues the path's next group.
    pub(super) gtail: Signal,
    /// The job's entry in the job memory, and its path's first group's.
    pub(super) src: Signal,
    pub(super) gbase: Signal,
    /// The job's plane (generic PEs only).
    pub(super) plane: Option<Signal>,
}

/// The fields of the slot-buffer entry the load reads this cycle (`sched_q`, gated by
/// `sq_ok`).
pub(super) struct LoadRead {
    /// The front slot's length (`slen_cur`).
    pub(super) slen: Signal,
    /// The entry is a job of the front slot, and its last.
    pub(super) valid: Signal,
    pub(super) tail: Signal,
    /// Path, point (global index) and PE column of the job.
    pub(super) path: Signal,
    pub(super) point: Signal,
    pub(super) inst: Signal,
    /// The job's previous point is the transmitter.
    pub(super) first: Signal,
    /// The job's next point is the receiver.
    pub(super) last: Signal,
    /// The job runs after its round's first phase (red-black): its neighbours' points are
    /// read from the bank the round writes, not the committed one.
    pub(super) late: Signal,
    /// The job's plane (generic PEs only): the plane table's read address.
    pub(super) plane: Option<Signal>,
}

/// The bit of the job word that marks a group's last job.
pub(super) fn gtail_bit(t: &Dims<'_>) -> u32 {
    5 + t.pb + t.ptb
}

/// The lowest bit of the job word's plane field (generic PEs), above the column.
pub(super) fn plane_lo_bit(t: &Dims<'_>) -> u32 {
    6 + t.pb + t.ptb + t.ib
}

/// Job memory (M9K), written by the host per step: one round of every path as groups
/// (`{column, tail, late, end, last, first, point, path, valid}`, `tail` on a group's last
/// job), path after path. Read by the dispatcher only (`job_q`, one cycle after the address:
/// a popped group's first job, else the examined group's next).
pub(super) fn job_memory(t: &Dims<'_>, bus: &Decode, d: &DispatchJob, items: &mut Vec<Item>) {
    let eb = t.eb;
    let sw = t.sw();
    items.push(Item::Comment(format!(
        "job memory, written per step by the host: one round of every path as groups, entry -> {{column, group tail, late, end, last, first, point, path, valid}} ({sw} bits)"
    )));
    let gi = zero_extend(&t.r.d.d_gi, eb);
    let job_ra = Signal::assigned(
        items,
        "job_ra",
        eb,
        Expr::mux(
            or(dstate_is(t, D_POP), d.pop_next.e()),
            t.r.rq_q.slice(eb - 1, 0),
            t.r.d.d_gptr.e().plus(gi).plus(lit(eb, 1)),
        ),
    );
    let sched = Signal::memory(items, "sched", sw, 1 << eb);
    let entry = match &t.r.sched_hi {
        Some(hi) => Expr::concat(vec![hi.e(), t.io.avs_writedata.e()]),
        None => t.io.avs_writedata.slice(sw - 1, 0),
    };
    items.push(Item::AlwaysFf(vec![
        Stmt::If(
            bus.host_wr.e().and(bus.is_sched.e()),
            vec![nb(sched.at(t.io.avs_address.slice(eb - 1, 0)), entry)],
            vec![],
        ),
        nb(t.r.job_q.e(), sched.at(job_ra.e())),
    ]));
}

/// `slen_0` or `slen_1` by a half select.
fn half_len(t: &Dims<'_>, sel: Expr) -> Expr {
    Expr::mux(sel, t.r.slen_1.e(), t.r.slen_0.e())
}

/// The slot-buffer read port `{half, idx}` registered into `(q, ok, tail)`: valid while `on`
/// and `idx` is below `len`, `tail` at the slot's last entry.
fn slot_read_port(
    t: &Dims<'_>,
    (half, idx, len, on): (Expr, &Signal, &Signal, Expr),
    (q, ok, tail): (&Signal, &Signal, &Signal),
    items: &mut Vec<Item>,
) {
    let w = t.cnt_bits.max(t.ib + 1);
    let idx_w = zero_extend(idx, w);
    let len_w = zero_extend(len, w);
    let at = Expr::concat(vec![half, zero_extend(idx, t.ib)]);
    items.push(Item::AlwaysFf(vec![
        nb(q.e(), t.r.sbuf.at(at)),
        nb(
            ok.e(),
            on.and(Expr::bin(BinaryOp::Lt, idx_w.clone(), len_w.clone())),
        ),
        nb(tail.e(), idx_w.plus(lit(w, 1)).eq(len_w)),
    ]));
}

/// Slot buffer, load port: entry `cnt` of the front slot (`rsel`) one cycle after the
/// address, read in LOAD once the load's delay has run out; its fields.
pub(super) fn slot_buffer_load(t: &Dims<'_>, items: &mut Vec<Item>) -> LoadRead {
    let (pb, ptb, ib) = (t.pb, t.ptb, t.ib);
    items.push(Item::Comment(
        "slot buffer: the front slot's jobs (rsel) for the load, the written-back slot's (wsel) for the write-back, the next slot's written by the dispatcher".into(),
    ));
    let slen = Signal::assigned(items, "slen_cur", ib + 1, half_len(t, t.r.rsel.e()));
    let on = state_is(t, S_LOAD).and(t.r.ldly.e().eq(lit(ib, 0)));
    slot_read_port(
        t,
        (t.r.rsel.e(), &t.r.cnt, &slen, on),
        (&t.r.sched_q, &t.r.sq_ok, &t.r.sq_tail),
        items,
    );
    let field = |items: &mut Vec<Item>, n: &str, w: u32, lo: u32| {
        Signal::assigned(items, n, w, t.r.sched_q.slice(lo + w - 1, lo))
    };
    LoadRead {
        slen,
        valid: Signal::assigned(items, "lrom_valid", 1, t.r.sq_ok.e()),
        tail: Signal::assigned(items, "lrom_tail", 1, t.r.sq_ok.e().and(t.r.sq_tail.e())),
        path: field(items, "lrom_path", pb, 1),
        point: field(items, "lrom_point", ptb, 1 + pb),
        inst: field(items, "lrom_inst", ib, 6 + pb + ptb),
        first: field(items, "lrom_first", 1, 1 + pb + ptb),
        last: field(items, "lrom_last", 1, 2 + pb + ptb),
        late: field(items, "lrom_late", 1, 4 + pb + ptb),
        plane: (t.plb > 0).then(|| field(items, "lrom_plane", t.plb, plane_lo_bit(t))),
    }
}

/// Slot buffer, write-back port: entry `wcnt` of the slot being written back (`wsel`) one
/// cycle after the address; its fields.
pub(super) fn slot_buffer_writeback(t: &Dims<'_>, items: &mut Vec<Item>) -> ScheduleRead {
    let (pb, ptb, ib, eb) = (t.pb, t.ptb, t.ib, t.eb);
    let sw = t.sw();
    let wlen = Signal::assigned(items, "slen_wb", ib + 1, half_len(t, t.r.wsel.e()));
    slot_read_port(
        t,
        (t.r.wsel.e(), &t.r.wcnt, &wlen, t.r.wb_on.e()),
        (&t.r.wsched_q, &t.r.wq_ok, &t.r.wq_tail),
        items,
    );
    let field = |items: &mut Vec<Item>, n: &str, w: u32, lo: u32| {
        Signal::assigned(items, n, w, t.r.wsched_q.slice(lo + w - 1, lo))
    };
    let valid = Signal::assigned(items, "rom_valid", 1, t.r.wq_ok.e());
    ScheduleRead {
        tail: Signal::assigned(items, "rom_tail", 1, valid.e().and(t.r.wq_tail.e())),
        valid,
        path: field(items, "rom_path", pb, 1),
        point: field(items, "rom_point", ptb, 1 + pb),
        inst: field(items, "rom_inst", ib, 6 + pb + ptb),
        end: field(items, "rom_end", 1, 3 + pb + ptb),
        gtail: field(items, "rom_gtail", 1, gtail_bit(t)),
        src: field(items, "rom_src", eb, sw + eb),
        gbase: field(items, "rom_gbase", eb, sw),
        plane: (t.plb > 0 && t.early.is_some())
            .then(|| field(items, "rom_plane", t.plb, plane_lo_bit(t))),
    }
}

/// The dispatcher's view of the job in `job_q`: its column, whether it ends its group, and
/// whether its group cannot run in the slot being built (a column taken).
pub(super) struct DispatchJob {
    /// The job's PE column.
    pub(super) col: Signal,
    pub(super) gtail: Signal,
    pub(super) conflict: Signal,
    /// Pop the queue's head this cycle: in D_POP (the first group) or at the last job of a
    /// group (the next group's first job is read while this one's tail is examined).
    pub(super) pop: Signal,
    /// A pop at a group's last job (stay in D_JOB), and the used columns and load delay
    /// after that group (its own, or the saved ones when it is pushed back).
    pub(super) pop_next: Signal,
    pub(super) used_after: Signal,
    pub(super) dly_after: Signal,
    /// Put the examined group back at the queue's tail this cycle.
    pub(super) push_back: Signal,
    /// The job's position in the slot being built.
    pub(super) wi: Signal,
    /// The job's column is in the front slot at a later position: the load must wait
    /// `dly_cand` cycles (at least) for that job's write-back.
    pub(super) dly_take: Signal,
    pub(super) dly_cand: Signal,
}

/// The dispatcher's combinational signals.
pub(super) fn dispatch_signals(t: &Dims<'_>, items: &mut Vec<Item>) -> DispatchJob {
    let (pb, ptb, ib) = (t.pb, t.ptb, t.ib);
    let col = Signal::assigned(
        items,
        "j_col",
        ib,
        t.r.job_q.slice(6 + pb + ptb + ib - 1, 6 + pb + ptb),
    );
    let gtail = Signal::assigned(items, "j_gtail", 1, t.r.job_q.bit(gtail_bit(t)));
    let conflict = Signal::assigned(
        items,
        "j_conf",
        1,
        or(t.r.d.d_conf.e(), t.r.d.d_used.at(col.e())),
    );
    let all_ones = lit(t.k, (1u128 << t.k) - 1);
    let all_used = t.r.d.d_used.slice(t.k - 1, 0).eq(all_ones);
    let scan_out = t.r.d.d_scan.e().eq(lit(pb + 1, 0));
    let stop = Signal::assigned(items, "d_stop", 1, or(scan_out.clone(), all_used));
    let push_back = Signal::assigned(
        items,
        "d_push",
        1,
        dstate_is(t, D_JOB).and(gtail.e()).and(conflict.e()),
    );
    let (pop_next, used_after) = next_group(t, (&col, &conflict, &gtail), scan_out, items);
    let pop = Signal::assigned(
        items,
        "d_pop",
        1,
        or(dstate_is(t, D_POP).and(stop.e().lnot()), pop_next.e()),
    );
    // Below the PE count while no column of the group is taken: ib bits.
    let wi = Signal::assigned(
        items,
        "d_wi",
        ib,
        t.r.d
            .d_nsl
            .slice(ib - 1, 0)
            .plus(t.r.d.d_gi.slice(ib - 1, 0)),
    );
    // The front slot's job on this column (if any) is written back `fpos - wi` cycles after
    // this job would load: the load waits the largest such difference.
    let fpos = Signal::assigned(
        items,
        "d_fpos",
        ib,
        t.r.spos.at(Expr::concat(vec![t.r.rsel.e(), col.e()])),
    );
    let fused = Expr::mux(t.r.rsel.e(), t.r.sused_1.e(), t.r.sused_0.e());
    let in_front = Signal::assigned(items, "d_fused", 1 << ib, fused);
    let cand = Signal::assigned(items, "dly_cand", ib, fpos.e().minus(wi.e()));
    let take = Signal::assigned(
        items,
        "dly_take",
        1,
        t.r.d
            .d_front
            .e()
            .and(in_front.at(col.e()))
            .and(Expr::bin(BinaryOp::Gt, fpos.e(), wi.e()))
            .and(Expr::bin(BinaryOp::Gt, cand.e(), t.r.d.d_dly.e())),
    );
    let dly_after = Signal::assigned(
        items,
        "d_dly_after",
        ib,
        Expr::mux(
            conflict.e(),
            t.r.d.d_dsave.e(),
            Expr::mux(take.e(), cand.e(), t.r.d.d_dly.e()),
        ),
    );
    DispatchJob {
        col,
        gtail,
        conflict,
        pop,
        pop_next,
        used_after,
        dly_after,
        push_back,
        wi,
        dly_take: take,
        dly_cand: cand,
    }
}

/// At a group's last job: the columns used after the group (`d_used` with the job's column,
/// or `d_save` when the group is pushed back) and whether the next group is popped at once
/// (`d_pop_next`: some scan left and a column free). Returns `(d_pop_next, d_used_after)`.
fn next_group(
    t: &Dims<'_>,
    (col, conflict, gtail): (&Signal, &Signal, &Signal),
    scan_out: Expr,
    items: &mut Vec<Item>,
) -> (Signal, Signal) {
    let n = 1u32 << t.ib;
    let onehot = Expr::concat(
        (0..n)
            .rev()
            .map(|b| col.e().eq(lit(t.ib, u128::from(b))))
            .collect(),
    );
    let used_after = Signal::assigned(
        items,
        "d_used_after",
        n,
        Expr::mux(
            conflict.e(),
            t.r.d.d_save.e(),
            Expr::bin(BinaryOp::Or, t.r.d.d_used.e(), onehot),
        ),
    );
    let all_ones = lit(t.k, (1u128 << t.k) - 1);
    let full = used_after.slice(t.k - 1, 0).eq(all_ones);
    let pop_next = Signal::assigned(
        items,
        "d_pop_next",
        1,
        dstate_is(t, D_JOB)
            .and(gtail.e())
            .and(or(scan_out, full).lnot()),
    );
    (pop_next, used_after)
}

/// The dispatcher's pop of the queue's head: the group's entry and first group, its job
/// index, and the used columns and load delay before it (`save`, `dsave`).
fn pop_actions(t: &Dims<'_>, save: Expr, dsave: Expr) -> Vec<Stmt> {
    let eb = t.eb;
    vec![
        nb(t.r.d.d_scan.e(), t.r.d.d_scan.e().minus(lit(t.pb + 1, 1))),
        nb(t.r.d.d_gbase.e(), t.r.rq_q.slice(2 * eb - 1, eb)),
        nb(t.r.d.d_gptr.e(), t.r.rq_q.slice(eb - 1, 0)),
        clear(&t.r.d.d_gi),
        clear(&t.r.d.d_conf),
        nb(t.r.d.d_save.e(), save),
        nb(t.r.d.d_dsave.e(), dsave),
    ]
}

/// D_FIN: publish the built slot's length, load delay and PE columns in the half the front
/// slot does not use, and stop.
fn publish_slot(t: &Dims<'_>) -> Vec<Stmt> {
    vec![
        Stmt::If(
            t.r.rsel.e(),
            vec![
                nb(t.r.slen_0.e(), t.r.d.d_nsl.e()),
                nb(t.r.dly_0.e(), t.r.d.d_dly.e()),
                nb(t.r.sused_0.e(), t.r.d.d_used.e()),
            ],
            vec![
                nb(t.r.slen_1.e(), t.r.d.d_nsl.e()),
                nb(t.r.dly_1.e(), t.r.d.d_dly.e()),
                nb(t.r.sused_1.e(), t.r.d.d_used.e()),
            ],
        ),
        nb(t.r.dstate.e(), lit(DSTATE_BITS, D_OFF)),
    ]
}

/// The dispatcher (twin of `crate::dispatch::predict`): on `d_go` it builds the next slot in
/// the buffer the running slot does not use, examining up to `SCAN_LIMIT` queued groups, each
/// put into the slot when all its columns are free (else back to the queue), then publishes
/// the slot's length. `rq_q` always holds the queue's head: it is read every cycle (at the
/// head after this cycle's pop), and `D_WARM` reads it after a start or a write-back's push.
pub(super) fn dispatcher(
    t: &Dims<'_>,
    d: &DispatchJob,
    [go, scan_init, front]: [&Signal; 3],
) -> Item {
    let ib = t.ib;
    let gi_plus = |k: u128| t.r.d.d_gi.e().plus(lit(ib + 1, k));
    let on_tail = vec![Stmt::If(
        d.conflict.e().lnot(),
        vec![nb(t.r.d.d_nsl.e(), t.r.d.d_nsl.e().plus(gi_plus(1)))],
        vec![
            nb(t.r.d.d_used.e(), t.r.d.d_save.e()),
            nb(t.r.d.d_dly.e(), t.r.d.d_dsave.e()),
        ],
    )];
    let job = vec![
        nb(t.r.d.d_used.at(d.col.e()), lit(1, 1)),
        Stmt::If(
            d.conflict.e().lnot().and(d.dly_take.e()),
            vec![nb(t.r.d.d_dly.e(), d.dly_cand.e())],
            vec![],
        ),
        Stmt::If(
            d.gtail.e(),
            on_tail
                .into_iter()
                .chain([Stmt::If(
                    d.pop_next.e(),
                    pop_actions(t, d.used_after.e(), d.dly_after.e()),
                    vec![nb(t.r.dstate.e(), lit(DSTATE_BITS, D_FIN))],
                )])
                .collect(),
            vec![
                nb(t.r.d.d_gi.e(), gi_plus(1)),
                nb(t.r.d.d_conf.e(), d.conflict.e()),
            ],
        ),
    ];
    let arms = vec![
        (
            lit(DSTATE_BITS, D_OFF),
            vec![Stmt::If(
                go.e(),
                vec![
                    nb(t.r.dstate.e(), lit(DSTATE_BITS, D_WARM)),
                    nb(t.r.d.d_scan.e(), scan_init.e()),
                    clear(&t.r.d.d_used),
                    clear(&t.r.d.d_nsl),
                    clear(&t.r.d.d_dly),
                    nb(t.r.d.d_front.e(), front.e()),
                ],
                vec![],
            )],
        ),
        (
            lit(DSTATE_BITS, D_WARM),
            vec![nb(t.r.dstate.e(), lit(DSTATE_BITS, D_POP))],
        ),
        (
            lit(DSTATE_BITS, D_POP),
            vec![Stmt::If(
                d.pop.e(),
                [nb(t.r.dstate.e(), lit(DSTATE_BITS, D_JOB))]
                    .into_iter()
                    .chain(pop_actions(t, t.r.d.d_used.e(), t.r.d.d_dly.e()))
                    .collect(),
                vec![nb(t.r.dstate.e(), lit(DSTATE_BITS, D_FIN))],
            )],
        ),
        (lit(DSTATE_BITS, D_JOB), job),
        (lit(DSTATE_BITS, D_FIN), publish_slot(t)),
    ];
    Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![
            nb(t.r.dstate.e(), lit(DSTATE_BITS, D_OFF)),
            clear(&t.r.slen_0),
            clear(&t.r.slen_1),
        ],
        vec![Stmt::Case(
            t.r.dstate.e(),
            arms,
            vec![nb(t.r.dstate.e(), lit(DSTATE_BITS, D_OFF))],
        )],
    )])
}

/// Slot buffer, write side: a job of the group being examined, while no column of it is
/// taken, at `{~rsel, d_nsl + d_gi}` with its job-memory entry and its path's first group.
pub(super) fn slot_buffer_write(t: &Dims<'_>, d: &DispatchJob, items: &mut Vec<Item>) {
    let eb = t.eb;
    let we = dstate_is(t, D_JOB).and(d.conflict.e().lnot());
    let at = Expr::concat(vec![t.r.rsel.e().inv(), d.wi.e()]);
    let col_at = Expr::concat(vec![t.r.rsel.e().inv(), d.col.e()]);
    let src = t.r.d.d_gptr.e().plus(zero_extend(&t.r.d.d_gi, eb));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        we,
        vec![
            nb(
                t.r.sbuf.at(at),
                Expr::concat(vec![src, t.r.d.d_gbase.e(), t.r.job_q.e()]),
            ),
            nb(t.r.spos.at(col_at), d.wi.e()),
        ],
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
        t.io.avs_writedata.slice(2 * eb - 1, 0),
        Expr::mux(
            d.push_back.e(),
            Expr::concat(vec![t.r.d.d_gbase.e(), t.r.d.d_gptr.e()]),
            wb_data.e(),
        ),
    );
    // Write-back queues a path's next group at the head (the running paths first: a long
    // chain is not held up behind every waiting path), the dispatcher's push-backs at the tail.
    let head_before = t.r.rq_head.e().minus(lit(pb, 1));
    let addr = Expr::mux(
        bus.host_wr.e(),
        t.io.avs_address.slice(pb - 1, 0),
        Expr::mux(wb_push.e(), head_before.clone(), t.r.rq_tail.e()),
    );
    items.push(Item::AlwaysFf(vec![
        Stmt::If(or(host, push.e()), vec![nb(t.r.rq.at(addr), data)], vec![]),
        // The head after this cycle's pop: a group's last job pops the next group, whose
        // first job the next cycle reads from `rq_q`.
        nb(
            t.r.rq_q.e(),
            t.r.rq.at(Expr::mux(
                d.pop.e(),
                t.r.rq_head.e().plus(lit(pb, 1)),
                t.r.rq_head.e(),
            )),
        ),
    ]));
    let inc = |n: &Signal, w: u32| n.e().plus(lit(w, 1));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![
            clear(&t.r.rq_head),
            clear(&t.r.rq_tail),
            clear(&t.r.rq_count),
        ],
        vec![Stmt::If(
            start.e(),
            vec![
                clear(&t.r.rq_head),
                nb(t.r.rq_tail.e(), t.r.paths_r.slice(pb - 1, 0)),
                nb(t.r.rq_count.e(), t.r.paths_r.e()),
            ],
            vec![
                Stmt::If(
                    d.pop.e(),
                    vec![nb(t.r.rq_head.e(), inc(&t.r.rq_head, pb))],
                    vec![Stmt::If(
                        wb_push.e(),
                        vec![nb(t.r.rq_head.e(), head_before)],
                        vec![],
                    )],
                ),
                Stmt::If(
                    d.push_back.e(),
                    vec![nb(t.r.rq_tail.e(), inc(&t.r.rq_tail, pb))],
                    vec![],
                ),
                // A push-back and the next pop can share a cycle (the count stays).
                Stmt::If(
                    push.e().and(d.pop.e().lnot()),
                    vec![nb(t.r.rq_count.e(), inc(&t.r.rq_count, pb + 1))],
                    vec![Stmt::If(
                        d.pop.e().and(push.e().lnot()),
                        vec![nb(t.r.rq_count.e(), t.r.rq_count.e().minus(lit(pb + 1, 1)))],
                        vec![],
                    )],
                ),
            ],
        )],
    )]));
}

/// `cnt + 1`.
pub(super) fn cnt_inc(t: &Dims<'_>) -> Expr {
    t.r.cnt.e().plus(lit(t.cnt_bits, 1))
}

/// IDLE on a start request: clear the counters and every path's flags and rounds and let the
/// dispatcher build the first slot (the queue holds every path's first group); with no path,
/// report done at once.
pub(super) fn fsm_on_start(t: &Dims<'_>) -> Vec<Stmt> {
    let all_zero = lit(t.np2, 0);
    let no_path = t.r.paths_r.e().eq(lit(t.pb + 1, 0));
    let mut on_start = vec![
        nb(
            t.r.state.e(),
            Expr::mux(
                no_path.clone(),
                lit(STATE_BITS, S_IDLE),
                lit(STATE_BITS, S_DISP),
            ),
        ),
        clear(&t.r.cnt),
        clear(&t.r.rsel),
        clear(&t.r.cycles),
        nb(t.r.done.e(), no_path),
    ];
    let r = &t.r;
    for v in [&r.cur, &r.conv, &r.dz, &r.ov, &r.pbig, &r.pdz, &r.pov] {
        on_start.push(nb(v.e(), all_zero.clone()));
    }
    if let Some((lb, plb)) = t.r.early() {
        on_start.push(nb(lb.e(), all_zero.clone()));
        on_start.push(nb(plb.e(), all_zero.clone()));
    }
    on_start.push(nb(t.r.rvalid.e(), all_zero));
    on_start
}

/// The next slot's length is 0 (the buffer the dispatcher wrote: not `rsel`).
pub(super) fn next_len(t: &Dims<'_>) -> Expr {
    half_len(t, t.r.rsel.e().inv()).eq(lit(t.ib + 1, 0))
}

/// Enter LOAD for the slot the dispatcher built: flip `rsel`, clear `cnt` and take the
/// slot's load delay.
fn enter_load(t: &Dims<'_>) -> Vec<Stmt> {
    vec![
        nb(t.r.state.e(), lit(STATE_BITS, S_LOAD)),
        nb(t.r.rsel.e(), t.r.rsel.e().inv()),
        clear(&t.r.cnt),
        nb(
            t.r.ldly.e(),
            Expr::mux(t.r.rsel.e(), t.r.dly_0.e(), t.r.dly_1.e()),
        ),
    ]
}

/// DISP: wait for the dispatcher; run the slot it built, or report done if it found none
/// (nothing queued, nothing running).
pub(super) fn fsm_disp(t: &Dims<'_>) -> Vec<Stmt> {
    vec![Stmt::If(
        dstate_is(t, D_OFF),
        vec![Stmt::If(
            next_len(t),
            vec![
                nb(t.r.state.e(), lit(STATE_BITS, S_IDLE)),
                nb(t.r.done.e(), lit(1, 1)),
            ],
            enter_load(t),
        )],
        vec![],
    )]
}

/// LOAD: wait out the load delay (`ldly`: a column of the front slot is still to be written
/// back), then read the slot's entries for the operand broadcast until its tail, then EXEC.
pub(super) fn fsm_load(t: &Dims<'_>) -> Vec<Stmt> {
    vec![Stmt::If(
        t.r.ld_q_tail.e(),
        vec![nb(t.r.state.e(), lit(STATE_BITS, S_EXEC)), clear(&t.r.cnt)],
        vec![Stmt::If(
            t.r.ldly.e().eq(lit(t.ib, 0)),
            vec![nb(t.r.cnt.e(), cnt_inc(t))],
            vec![nb(t.r.ldly.e(), t.r.ldly.e().minus(lit(t.ib, 1)))],
        )],
    )]
}

/// Registers the load entry's fields for the operand broadcast (every cycle: `lrom_valid`
/// is set in LOAD only).
fn register_load_entry(t: &Dims<'_>, rom: &LoadRead) -> Vec<Stmt> {
    register_entry(&[
        (&t.r.ld_q_en, &rom.valid),
        (&t.r.ld_q_tail, &rom.tail),
        (&t.r.ld_q_first, &rom.first),
        (&t.r.ld_q_last, &rom.last),
        (&t.r.ld_q_inst, &rom.inst),
    ])
}

/// Registers the schedule entry's fields: one `register <= field` per pair, in order.
pub(super) fn register_entry(pairs: &[(&Signal, &Signal)]) -> Vec<Stmt> {
    pairs
        .iter()
        .map(|(reg, field)| nb(reg.e(), field.e()))
        .collect()
}

/// EXEC: wait until the slot's last PE has run the PE latency ([`pe_latency`]) less the
/// slot's other loads and the two cycles write-back takes from reading an entry to taking its
/// PE's result (`cnt + jobs + 2 >= latency`, at least one cycle), for the previous slot's
/// write-back to end and for the dispatcher (which starts when that write-back ends, so it
/// sees the paths it queued); then start this slot's write-back and load the next slot
/// (its load overlaps the write-back), or wait for the write-back (S_WB) if there is none.
pub(super) fn fsm_exec(t: &Dims<'_>, rom: &LoadRead) -> Vec<Stmt> {
    let w = t.cnt_bits.max(t.ib + 1) + 1;
    let ran = zero_extend(&t.r.cnt, w)
        .plus(zero_extend(&rom.slen, w))
        .plus(lit(w, 2));
    let mut start_wb = vec![
        nb(t.r.wb_on.e(), lit(1, 1)),
        clear(&t.r.wcnt),
        nb(t.r.wsel.e(), t.r.rsel.e()),
    ];
    start_wb.push(Stmt::If(
        next_len(t),
        vec![nb(t.r.state.e(), lit(STATE_BITS, S_WB))],
        enter_load(t),
    ));
    vec![Stmt::If(
        Expr::bin(BinaryOp::Gt, ran, lit(w, u128::from(t.latency() - 1))),
        vec![Stmt::If(
            dstate_is(t, D_OFF).and(t.r.wb_on.e().lnot()),
            start_wb,
            vec![],
        )],
        vec![nb(t.r.cnt.e(), cnt_inc(t))],
    )]
}

/// The write-back engine, beside the main FSM: register the entry for the write-back, commit,
/// and stop at the slot's tail.
fn writeback_engine(t: &Dims<'_>, rom: &ScheduleRead, f: &WritebackFlags) -> Vec<Stmt> {
    let mut stmts = register_entry(&[
        (&t.r.wbe.wb_q_en, &rom.valid),
        (&t.r.wbe.wb_q_tail, &rom.tail),
        (&t.r.wbe.wb_q_end, &rom.end),
        (&t.r.wbe.wb_q_path, &rom.path),
        (&t.r.wbe.wb_q_point, &rom.point),
        (&t.r.wbe.wb_q_inst, &rom.inst),
        (&t.r.wbe.wb_q_gtail, &rom.gtail),
        (&t.r.wbe.wb_q_src, &rom.src),
        (&t.r.wbe.wb_q_gbase, &rom.gbase),
    ]);
    if let (Some(reg), Some(field)) = (&t.r.wbe.wb_q_plane, &rom.plane) {
        stmts.extend(register_entry(&[(reg, field)]));
    }
    stmts.extend([
        Stmt::If(f.go.e(), path_commit(t, f), vec![]),
        Stmt::If(
            t.r.wb_on.e(),
            vec![Stmt::If(
                t.r.wbe.wb_q_tail.e(),
                vec![clear(&t.r.wb_on)],
                vec![nb(t.r.wcnt.e(), t.r.wcnt.e().plus(lit(t.cnt_bits, 1)))],
            )],
            vec![],
        ),
    ]);
    stmts
}

/// S_WB: no slot loads; at the write-back's end dispatch if paths are queued, else stop.
pub(super) fn fsm_drain(t: &Dims<'_>, queue_empty: &Signal) -> Vec<Stmt> {
    vec![Stmt::If(
        t.r.wb_on.e().and(t.r.wbe.wb_q_tail.e()),
        vec![Stmt::If(
            queue_empty.e(),
            vec![
                nb(t.r.state.e(), lit(STATE_BITS, S_IDLE)),
                nb(t.r.done.e(), lit(1, 1)),
            ],
            vec![nb(t.r.state.e(), lit(STATE_BITS, S_DISP))],
        )],
        vec![],
    )]
}

/// The start request and the dispatcher's trigger: at a start (no front slot), when a slot
/// built with no slot running starts loading, and when a write-back ends: with a front slot
/// the dispatcher builds the slot after it, with none (S_WB) it builds the next one at once
/// if paths are queued. Returns `(start_req, d_go, d_scan_init, d_front_in, queue_empty)`.
pub(super) fn dispatch_triggers(
    t: &Dims<'_>,
    wb_push: &Signal,
    items: &mut Vec<Item>,
) -> [Signal; 5] {
    let pb = t.pb;
    let start_req = Signal::assigned(
        items,
        "start_req",
        1,
        t.io.avs_write
            .e()
            .and(t.io.avs_address.e().eq(lit(t.ab, 0)))
            .and(t.io.avs_writedata.bit(0))
            .and(state_is(t, S_IDLE)),
    );
    let queued = Signal::assigned(
        items,
        "rq_after",
        pb + 1,
        Expr::mux(
            wb_push.e(),
            t.r.rq_count.e().plus(lit(pb + 1, 1)),
            t.r.rq_count.e(),
        ),
    );
    let empty = Signal::assigned(items, "rq_empty", 1, queued.e().eq(lit(pb + 1, 0)));
    let wb_end = Signal::assigned(items, "wb_end", 1, t.r.wb_on.e().and(t.r.wbe.wb_q_tail.e()));
    let front_busy = or(state_is(t, S_LOAD), state_is(t, S_EXEC));
    let to_load = state_is(t, S_DISP)
        .and(dstate_is(t, D_OFF))
        .and(next_len(t).lnot());
    // The dispatcher will run beside a front slot: its load delay is measured against it.
    let front = Signal::assigned(
        items,
        "d_front_in",
        1,
        or(to_load, wb_end.e().and(front_busy)),
    );
    let at_drain_end = wb_end.e().and(state_is(t, S_WB)).and(empty.e().lnot());
    let go = Signal::assigned(
        items,
        "d_go",
        1,
        or(
            or(
                start_req.e().and(t.r.paths_r.e().eq(lit(pb + 1, 0)).lnot()),
                front.e(),
            ),
            at_drain_end,
        ),
    );
    let limit = u128::from(crate::dispatch::SCAN_LIMIT.min(1 << pb));
    let count = Expr::mux(start_req.e(), t.r.paths_r.e(), queued.e());
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
    [start_req, go, capped, front, empty]
}

/// The main FSM (controller): IDLE -> DISP -> per slot LOAD, EXEC -> (LOAD of the next slot
/// beside this slot's write-back, or S_WB) ... -> IDLE with done, the write-back engine and
/// the cycle counter.
pub(super) fn controller(
    t: &Dims<'_>,
    (rom, lrom): (&ScheduleRead, &LoadRead),
    f: &WritebackFlags,
    [start_req, empty]: [&Signal; 2],
    items: &mut Vec<Item>,
) {
    items.push(Item::Comment(format!(
        "main FSM: IDLE -> DISP -> per slot LOAD (delay + jobs + 2) EXEC (max({} - jobs - 1, 1), the previous write-back and the dispatcher done) -> write-back (jobs + 2) beside the next slot's LOAD -> IDLE with done when no path is queued",
        t.latency()
    )));
    let mut body = vec![Stmt::If(
        Expr::bin(BinaryOp::Ne, t.r.state.e(), lit(STATE_BITS, S_IDLE)),
        vec![nb(t.r.cycles.e(), t.r.cycles.e().plus(lit(32, 1)))],
        vec![],
    )];
    body.extend(register_load_entry(t, lrom));
    body.extend(writeback_engine(t, rom, f));
    body.push(Stmt::Case(
        t.r.state.e(),
        vec![
            (
                lit(STATE_BITS, S_IDLE),
                vec![Stmt::If(start_req.e(), fsm_on_start(t), vec![])],
            ),
            (lit(STATE_BITS, S_DISP), fsm_disp(t)),
            (lit(STATE_BITS, S_LOAD), fsm_load(t)),
            (lit(STATE_BITS, S_EXEC), fsm_exec(t, lrom)),
            (lit(STATE_BITS, S_WB), fsm_drain(t, empty)),
        ],
        vec![nb(t.r.state.e(), lit(STATE_BITS, S_IDLE))],
    ));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![
            nb(t.r.state.e(), lit(STATE_BITS, S_IDLE)),
            clear(&t.r.cnt),
            clear(&t.r.rsel),
            clear(&t.r.cycles),
            clear(&t.r.done),
            clear(&t.r.ld_q_en),
            clear(&t.r.ld_q_tail),
            clear(&t.r.wbe.wb_q_en),
            clear(&t.r.wbe.wb_q_tail),
            clear(&t.r.wb_on),
            clear(&t.r.rvalid),
        ],
        body,
    )]));
}
