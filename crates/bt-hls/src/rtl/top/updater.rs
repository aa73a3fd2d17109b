//! The coordinate updater-buffer of `bt_top`: the point memory copies' ports and the
//! per-path `rounds` memory.

use super::*;

/// The ports of the coordinate updater-buffer (the two point memory copies).
pub(super) struct UpdaterPorts {
    /// Read addresses of the three copies (port a: previous point or a bus read, port b:
    /// next point, port c: the written point's old value).
    pub(super) ra_addr: Signal,
    pub(super) rb_addr: Signal,
    pub(super) rc_addr: Signal,
    /// Write enable, address `{point, bank}` and data of the common write port.
    pub(super) wr_en: Signal,
    pub(super) wr_addr: Signal,
    pub(super) wr_data: Signal,
}

/// Rounds memory, read side: `rounds_q` <= rounds[addr] every cycle, the address being the
/// write-back entry's path while the write-back engine runs (so `rounds_q` holds
/// rounds[wb_q_path] when the entry commits: a path's jobs in a slot belong to one round, so
/// no commit of the same path sits between) and the bus address otherwise (a PATH_STATUS read
/// while idle). `rounds_cur` = the rounds `wb_q_path` has committed since the start.
pub(super) fn rounds_read(t: &Dims<'_>, rom: &ScheduleRead, items: &mut Vec<Item>) -> Signal {
    items.push(Item::Comment(
        "rounds memory (M9K): read at the write-back entry's path, or the bus address".into(),
    ));
    let addr = Signal::assigned(
        items,
        "rounds_ra",
        t.pb,
        Expr::mux(
            t.r.wb_on.e(),
            rom.path.e(),
            t.io.avs_address.slice(t.pb - 1, 0),
        ),
    );
    items.push(Item::AlwaysFf(vec![nb(
        t.r.rounds_q.e(),
        t.r.rounds.at(addr.e()),
    )]));
    Signal::assigned(
        items,
        "rounds_cur",
        16,
        Expr::mux(
            t.r.rvalid.at(t.r.wbe.wb_q_path.e()),
            t.r.rounds_q.e(),
            lit(16, 0),
        ),
    )
}

/// Rounds memory, write side: a committed round's end writes rounds_cur + 1.
pub(super) fn rounds_write(t: &Dims<'_>, f: &WritebackFlags, items: &mut Vec<Item>) {
    items.push(Item::AlwaysFf(vec![Stmt::If(
        f.go.e().and(t.r.wbe.wb_q_end.e()),
        vec![nb(
            t.r.rounds.at(t.r.wbe.wb_q_path.e()),
            f.rounds.e().plus(lit(16, 1)),
        )],
        vec![],
    )]));
}

/// Coordinate updater-buffer, read side: two banks per point, bank = cur[path] holds the last
/// committed round. Port a reads the loaded job's previous point (or a bus read while idle),
/// port b its next point, port c the written-back job's own point (the old value, for the
/// displacement), so a slot loads while the previous one writes back.
pub(super) fn updater_read_ports(
    t: &Dims<'_>,
    bus: &Decode,
    (rom, lrom): (&ScheduleRead, &LoadRead),
    items: &mut Vec<Item>,
) -> UpdaterPorts {
    let ptb = t.ptb;
    items.push(Item::Comment(
        "coordinate updater-buffer: address {point, bank}; cur[path] = bank of the committed round"
            .into(),
    ));
    // Neighbours: the committed bank, or for a late job the bank its round writes.
    let nb_bank = Expr::bin(BinaryOp::Xor, t.r.cur.at(lrom.path.e()), lrom.late.e());
    let ra_addr = Signal::reg(items, "ra_addr", ptb + 1);
    let rb_addr = Signal::reg(items, "rb_addr", ptb + 1);
    let rc_addr = Signal::reg(items, "rc_addr", ptb + 1);
    let wr_addr = Signal::reg(items, "wr_addr", ptb + 1);
    let wr_en = Signal::reg(items, "wr_en", 1);
    let wr_data = Signal::reg(items, "wr_data", point_bits(t.wd));
    let one_pt = lit(ptb, 1);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(ra_addr.e(), bus_cell(t, bus)),
        Stmt::If(
            state_is(t, S_LOAD),
            vec![Stmt::Blocking(
                ra_addr.e(),
                Expr::concat(vec![lrom.point.e().minus(one_pt.clone()), nb_bank.clone()]),
            )],
            vec![],
        ),
        Stmt::Blocking(
            rb_addr.e(),
            Expr::concat(vec![lrom.point.e().plus(one_pt), nb_bank]),
        ),
        Stmt::Blocking(
            rc_addr.e(),
            Expr::concat(vec![rom.point.e(), t.r.cur.at(rom.path.e())]),
        ),
    ]));
    UpdaterPorts {
        ra_addr,
        rb_addr,
        rc_addr,
        wr_en,
        wr_addr,
        wr_data,
    }
}

/// Coordinate updater-buffer, write side: the host's point writes while idle, the selected
/// PE's result into the other bank at write-back; every memory copy takes every write.
pub(super) fn updater_write_port(
    t: &Dims<'_>,
    bus: &Decode,
    ports: &UpdaterPorts,
    sel: &Selected,
    flags: &WritebackFlags,
    items: &mut Vec<Item>,
) {
    // `st_<axis>` hold the millimetre words' kept bits already (`mm_width`).
    let host_point = Expr::concat(vec![
        t.r.st_z.e(),
        t.io.avs_writedata.slice(23, 16),
        t.r.st_y.e(),
        t.io.avs_writedata.slice(15, 8),
        t.r.st_x.e(),
        t.io.avs_writedata.slice(7, 0),
    ]);
    items.push(Item::AlwaysComb(vec![
        Stmt::Blocking(ports.wr_en.e(), bus.pt_we.e().or(flags.go.e())),
        Stmt::Blocking(ports.wr_addr.e(), bus_cell(t, bus)),
        Stmt::Blocking(ports.wr_data.e(), host_point),
        Stmt::If(
            t.r.wb_on.e(),
            vec![
                Stmt::Blocking(
                    ports.wr_addr.e(),
                    Expr::concat(vec![
                        t.r.wbe.wb_q_point.e(),
                        t.r.cur.at(t.r.wbe.wb_q_path.e()).inv(),
                    ]),
                ),
                Stmt::Blocking(ports.wr_data.e(), sel.point.e()),
            ],
            vec![],
        ),
    ]));
    for (mem, rd, addr) in [
        (&t.r.pm_a, &t.r.rd_a, &ports.ra_addr),
        (&t.r.pm_b, &t.r.rd_b, &ports.rb_addr),
        (&t.r.pm_c, &t.r.rd_c, &ports.rc_addr),
    ] {
        items.push(Item::AlwaysFf(vec![
            Stmt::If(
                ports.wr_en.e(),
                vec![nb(mem.at(ports.wr_addr.e()), ports.wr_data.e())],
                vec![],
            ),
            nb(rd.e(), mem.at(addr.e())),
        ]));
    }
}
