//! The Avalon-MM slave of `bt_top`: address decode, register writes, the read pipeline and
//! multiplexer, the interrupt.

use super::*;

/// The Avalon-MM address decode: which region a bus access hits, and the host's write strobes.
pub(super) struct Decode {
    /// Control registers (`avs_address < 16`).
    pub(super) is_ctrl: Signal,
    /// Per-path status words.
    pub(super) is_status: Signal,
    /// Point memory window.
    pub(super) is_point: Signal,
    /// Schedule memory window.
    pub(super) is_sched: Signal,
    /// Plane table window (generic PEs only).
    pub(super) is_plane: Option<Signal>,
    /// The point index of a point-window address.
    pub(super) bus_point: Signal,
    /// A host write while idle.
    pub(super) host_wr: Signal,
    /// The host writes a point's last word (fractions): the point memory write strobe.
    pub(super) pt_we: Signal,
}

/// Bus address decode.
pub(super) fn bus_decode(t: &Dims<'_>, items: &mut Vec<Item>) -> Decode {
    let l = &t.p.layout;
    let ab = t.ab;
    let hi = ab - 1;
    let window = |items: &mut Vec<Item>, name: &str, base: u32| {
        let bits = base.trailing_zeros();
        Signal::assigned(
            items,
            name,
            1,
            t.io.avs_address.slice(hi, bits).eq(lit(ab - bits, 1)),
        )
    };
    let idle = Signal::assigned(items, "idle", 1, state_is(t, S_IDLE));
    let is_ctrl = Signal::assigned(
        items,
        "is_ctrl",
        1,
        t.io.avs_address.slice(hi, 4).eq(lit(ab - 4, 0)),
    );
    let is_status = window(items, "is_status", l.map.status_base);
    let is_point = window(items, "is_point", l.map.point_base);
    let is_sched = window(items, "is_sched", l.map.sched_base);
    let is_plane = l.map.plane_base.map(|b| window(items, "is_plane", b));
    let bus_point = Signal::assigned(
        items,
        "bus_point",
        t.ptb,
        t.io.avs_address.slice(t.ptb + 2, 3),
    );
    let host_wr = Signal::assigned(items, "host_wr", 1, t.io.avs_write.e().and(idle.e()));
    let pt_we = Signal::assigned(
        items,
        "pt_we",
        1,
        host_wr
            .e()
            .and(is_point.e())
            .and(t.io.avs_address.slice(1, 0).eq(lit(2, 3))),
    );
    Decode {
        is_ctrl,
        is_status,
        is_point,
        is_sched,
        is_plane,
        bus_point,
        host_wr,
        pt_we,
    }
}

/// `{bus_point, avs_address[2]}`: the memory cell a point-window bus access addresses.
pub(super) fn bus_cell(t: &Dims<'_>, bus: &Decode) -> Expr {
    Expr::concat(vec![bus.bus_point.e(), t.io.avs_address.bit(2)])
}

/// Avalon-MM slave, writes: the transmitter, receiver and slot-count registers and the
/// staging words of a point (its last word, the fractions, goes to the point memory).
pub(super) fn register_writes(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
    let (ab, pb) = (t.ab, t.pb);
    let wr = |addr: u32, reg: &Signal| {
        Stmt::If(
            t.io.avs_address.e().eq(lit(ab, addr.into())),
            vec![nb(reg.e(), t.io.avs_writedata.e())],
            vec![],
        )
    };
    items.push(Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![
            clear(&t.r.tx_x),
            clear(&t.r.tx_y),
            clear(&t.r.tx_z),
            clear(&t.r.rx_x),
            clear(&t.r.rx_y),
            clear(&t.r.rx_z),
            clear(&t.r.paths_r),
            clear(&t.r.cap_r),
        ],
        vec![Stmt::If(
            bus.host_wr.e(),
            vec![
                wr(4, &t.r.tx_x),
                wr(5, &t.r.tx_y),
                wr(6, &t.r.tx_z),
                wr(8, &t.r.rx_x),
                wr(9, &t.r.rx_y),
                wr(10, &t.r.rx_z),
                Stmt::If(
                    t.io.avs_address.e().eq(lit(ab, crate::regs::PATHS.into())),
                    vec![nb(t.r.paths_r.e(), t.io.avs_writedata.slice(pb, 0))],
                    vec![],
                ),
                Stmt::If(
                    t.io.avs_address
                        .e()
                        .eq(lit(ab, crate::regs::ROUND_CAP.into())),
                    vec![nb(t.r.cap_r.e(), t.io.avs_writedata.slice(15, 0))],
                    vec![],
                ),
                Stmt::If(
                    bus.is_point.e(),
                    vec![Stmt::Case(
                        t.io.avs_address.slice(1, 0),
                        vec![
                            (
                                lit(2, 0),
                                vec![nb(t.r.st_x.e(), mm_bits(&t.io.avs_writedata, t.wd))],
                            ),
                            (
                                lit(2, 1),
                                vec![nb(t.r.st_y.e(), mm_bits(&t.io.avs_writedata, t.wd))],
                            ),
                            (
                                lit(2, 2),
                                vec![nb(t.r.st_z.e(), mm_bits(&t.io.avs_writedata, t.wd))],
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
pub(super) fn read_pipeline(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) -> Signal {
    let mut mux_decl = Vec::new();
    let read_mux = Signal::reg(&mut mux_decl, "read_mux", 32);
    items.push(Item::AlwaysFf(vec![Stmt::If(
        t.io.rst_n.e().lnot(),
        vec![
            clear(&t.r.rq_valid),
            nb(t.io.avs_readdatavalid.e(), lit(1, 0)),
            nb(t.io.avs_readdata.e(), lit(32, 0)),
        ],
        vec![
            nb(t.r.rq_valid.e(), t.io.avs_read.e()),
            nb(
                t.r.rq_kind.e(),
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
            nb(t.r.rq_reg.e(), t.io.avs_address.slice(3, 0)),
            nb(t.r.rq_word.e(), t.io.avs_address.slice(1, 0)),
            nb(t.r.rq_path.e(), t.io.avs_address.slice(t.pb - 1, 0)),
            nb(t.io.avs_readdatavalid.e(), t.r.rq_valid.e()),
            nb(t.io.avs_readdata.e(), read_mux.e()),
        ],
    )]));
    items.extend(mux_decl);
    read_mux
}

/// SCHED_HI: the high bits of wide schedule entries, written by the host before the entries
/// (only in designs whose entries exceed 32 bits).
pub(super) fn sched_hi_register(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
    let sw = t.sw();
    let Some(sched_hi) = &t.r.sched_hi else {
        return;
    };
    items.push(Item::AlwaysFf(vec![Stmt::If(
        bus.host_wr.e().and(
            t.io.avs_address
                .e()
                .eq(lit(t.ab, crate::regs::SCHED_HI.into())),
        ),
        vec![nb(sched_hi.e(), t.io.avs_writedata.slice(sw - 33, 0))],
        vec![],
    )]));
}

/// The control registers' read values by word address (register map in `docs/hardware.md`).
pub(super) fn control_read_arms(t: &Dims<'_>, mux: &Signal) -> Vec<(Expr, Vec<Stmt>)> {
    let platform = t.p.platform;
    let info = (t.k << 24) | (MAP_VERSION << 16) | (platform.capacity.paths & 0xffff);
    let read = |addr: u128, value: Expr| (lit(4, addr), vec![Stmt::Blocking(mux.e(), value)]);
    vec![
        read(
            0,
            Expr::concat(vec![
                lit(30, 0),
                t.r.done.e(),
                Expr::bin(BinaryOp::Ne, t.r.state.e(), lit(STATE_BITS, S_IDLE)),
            ]),
        ),
        read(1, t.r.cycles.e()),
        read(2, lit(32, info.into())),
        read(3, lit(32, platform.threshold_lsb.into())),
        read(4, t.r.tx_x.e()),
        read(5, t.r.tx_y.e()),
        read(6, t.r.tx_z.e()),
        read(8, t.r.rx_x.e()),
        read(9, t.r.rx_y.e()),
        read(10, t.r.rx_z.e()),
        read(12, Expr::concat(vec![lit(31 - t.pb, 0), t.r.paths_r.e()])),
        read(14, Expr::concat(vec![lit(16, 0), t.r.cap_r.e()])),
    ]
}

/// The read multiplexer: control registers, a path's status word, or a point's words (three
/// integer words, then the packed fractions).
pub(super) fn read_mux(t: &Dims<'_>, mux: &Signal, items: &mut Vec<Item>) {
    let cw = t.wd.coord;
    let set = |value: Expr| vec![Stmt::Blocking(mux.e(), value)];
    let rqp = |v: &Signal| v.at(t.r.rq_path.e());
    let point_arms = vec![
        (lit(2, 0), set(sext_slice(t.r.rd_a.name(), cw - 1, 8, 32))),
        (
            lit(2, 1),
            set(sext_slice(t.r.rd_a.name(), 2 * cw - 1, cw + 8, 32)),
        ),
        (
            lit(2, 2),
            set(sext_slice(t.r.rd_a.name(), 3 * cw - 1, 2 * cw + 8, 32)),
        ),
    ];
    let frac_word = Expr::concat(vec![
        lit(8, 0),
        t.r.rd_a.slice(2 * cw + 7, 2 * cw),
        t.r.rd_a.slice(cw + 7, cw),
        t.r.rd_a.slice(7, 0),
    ]);
    let status_word = Expr::concat(vec![
        // `rounds_q` holds rounds[rq_path]: read with the request's address while idle.
        Expr::mux(t.r.rvalid.at(t.r.rq_path.e()), t.r.rounds_q.e(), lit(16, 0)),
        lit(12, 0),
        match &t.r.lb {
            Some(lb) => rqp(lb),
            None => lit(1, 0),
        },
        rqp(&t.r.ov),
        rqp(&t.r.dz),
        rqp(&t.r.conv),
    ]);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(mux.e(), lit(32, 0)),
        Stmt::Case(
            t.r.rq_kind.e(),
            vec![
                (
                    lit(2, 1),
                    vec![Stmt::Case(
                        t.r.rq_reg.e(),
                        control_read_arms(t, mux),
                        set(lit(32, 0)),
                    )],
                ),
                (lit(2, 2), set(status_word)),
                (
                    lit(2, 3),
                    vec![Stmt::Case(t.r.rq_word.e(), point_arms, set(frac_word))],
                ),
            ],
            set(lit(32, 0)),
        ),
    ]));
}

/// The interrupt (`ins_irq = done`) and `bt_unused_ok`, which reads the bits no block uses so
/// the linter sees them consumed on purpose.
pub(super) fn interrupt_and_unused(t: &Dims<'_>, items: &mut Vec<Item>) {
    items.push(Item::Assign(t.io.ins_irq.e(), t.r.done.e()));
    // The slot buffer's `valid` bit (every entry below the slot's length is a job), the
    // write-back fields the load does not read and the load fields the write-back does not.
    let (pb, ptb) = (t.pb, t.ptb);
    let top = t.r.sched_q.width() - 1;
    let mut unused = vec![
        lit(1, 0),
        t.io.avs_writedata.slice(31, 1),
        t.r.sched_q.bit(0),
        t.r.sched_q.bit(3 + pb + ptb),
        t.r.sched_q.bit(gtail_bit(t)),
        t.r.sched_q.slice(top, t.sw()),
        t.r.wsched_q.bit(0),
        t.r.wsched_q.slice(2 + pb + ptb, 1 + pb + ptb),
        t.r.wsched_q.bit(4 + pb + ptb),
    ];
    if t.plb > 0 && t.early.is_none() {
        // The write-back does not read the job's plane (early stopping's box would).
        let lo = plane_lo_bit(t);
        unused.push(t.r.wsched_q.slice(lo + t.plb - 1, lo));
    }
    Signal::assigned(
        items,
        "bt_unused_ok",
        1,
        Expr::Unary(UnaryOp::ReduceAnd, Box::new(Expr::concat(unused))),
    );
}
