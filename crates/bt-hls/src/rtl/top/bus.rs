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

/// `{bus_point, avs_address[2]}`: the memory cell a point-window bus access addresses.
pub(super) fn bus_cell(bus: &Decode) -> Expr {
    Expr::concat(vec![bus.bus_point.e(), Expr::bit("avs_address", 2)])
}

/// Avalon-MM slave, writes: the transmitter, receiver and slot-count registers and the
/// staging words of a point (its last word, the fractions, goes to the point memory).
pub(super) fn register_writes(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
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
pub(super) fn read_pipeline(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) -> Signal {
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
pub(super) fn sched_hi_register(t: &Dims<'_>, bus: &Decode, items: &mut Vec<Item>) {
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
pub(super) fn control_read_arms(t: &Dims<'_>, mux: &Signal) -> Vec<(Expr, Vec<Stmt>)> {
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
pub(super) fn read_mux(t: &Dims<'_>, mux: &Signal, items: &mut Vec<Item>) {
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
pub(super) fn interrupt_and_unused(items: &mut Vec<Item>) {
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
