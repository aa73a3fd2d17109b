//! Write-back in `bt_top`: PE output select and saturation, displacement, the per-path
//! flags and queue push, early stopping.

use super::*;

/// Width of the early-stopping comparisons (`bt_fixed::FineBox::outside`): a 40-bit point
/// plus or minus `(L1 move) << 4` and the ±2^41 box bounds fit in 48 signed bits.
pub(super) const BOX_BITS: u32 = 48;

/// Write-back's queue push: a group's last job queues the path's next group, or after the
/// round's last group the path's first group again, unless the path converged, froze or
/// reached the round cap (`cap_r`).
pub(super) fn writeback_push(
    t: &Dims<'_>,
    f: &WritebackFlags,
    items: &mut Vec<Item>,
) -> (Signal, Signal) {
    let eb = t.eb;
    let mut goes_on = f
        .any_big
        .e()
        .and(f.any_dz.e().lnot())
        .and(f.any_ov.e().lnot());
    if let Some(lb) = &f.any_lb {
        goes_on = goes_on.and(lb.e().lnot());
    }
    let below_cap = Expr::bin(BinaryOp::Lt, f.rounds.e().plus(lit(16, 1)), t.r.cap_r.e());
    let again = Signal::assigned(items, "wb_again", 1, goes_on.and(below_cap));
    let push = Signal::assigned(
        items,
        "wb_push",
        1,
        f.go.e()
            .and(t.r.wbe.wb_q_gtail.e())
            .and(or(t.r.wbe.wb_q_end.e().lnot(), again.e())),
    );
    let next = Expr::mux(
        t.r.wbe.wb_q_end.e(),
        t.r.wbe.wb_q_gbase.e(),
        t.r.wbe.wb_q_src.e().plus(lit(eb, 1)),
    );
    let data = Signal::assigned(
        items,
        "wb_push_data",
        2 * eb,
        Expr::concat(vec![t.r.wbe.wb_q_gbase.e(), next]),
    );
    (push, data)
}

/// The selected PE's result at write-back, saturated once for all PEs.
pub(super) struct Selected {
    /// The saturated point `{z, y, x}`.
    pub(super) point: Signal,
    /// Some axis saturated.
    pub(super) ov: Signal,
    /// The PE reported a zero distance sum.
    pub(super) zs: Signal,
}

/// Write-back, PE output select and saturation (twin of the model's `saturate`).
pub(super) fn pe_output_select(t: &Dims<'_>, pe: &[PeWires], items: &mut Vec<Item>) -> Selected {
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
        t.r.wbe.wb_q_inst.e(),
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
pub(super) struct Displacement {
    /// `new_<axis>`: the written coordinate.
    pub(super) new: Vec<Signal>,
    /// `adiff_<axis>`: |new − old| per axis.
    pub(super) adiff: Vec<Signal>,
    /// `wb_big`: the L∞ move exceeds the threshold.
    pub(super) big: Signal,
}

/// Write-back displacement: per-axis |new − old| and the threshold test.
pub(super) fn displacement(t: &Dims<'_>, sel: &Selected, items: &mut Vec<Item>) -> Displacement {
    let cw = t.wd.coord;
    let dispw = cw + 1;
    let (mut new, mut adiff, mut big_terms) = (Vec::new(), Vec::new(), Vec::new());
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let (hi, lo) = (cw * (a as u32 + 1) - 1, cw * a as u32);
        let nw = Signal::assigned(items, format!("new_{axis}"), cw, sel.point.slice(hi, lo));
        let old = t.r.rd_c.slice(hi, lo);
        let ow = Signal::assigned(items, format!("old_{axis}"), cw, old);
        let wide = |s: &Signal| crate::rtl::pe::sext(s.name(), cw, dispw);
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
pub(super) struct WritebackFlags {
    /// Commit the PE's result (write-back state, a job, path not frozen).
    pub(super) go: Signal,
    /// Some point of the path moved more than the threshold this round.
    pub(super) any_big: Signal,
    /// Some point of the path had a zero distance sum this round.
    pub(super) any_dz: Signal,
    /// Some point of the path saturated this round.
    pub(super) any_ov: Signal,
    /// Some point of the path left its box this round (early stopping only).
    pub(super) any_lb: Option<Signal>,
    /// `rounds_cur`: the rounds the written path has committed since the start.
    pub(super) rounds: Signal,
}

/// Write-back flags: a path is frozen once converged, degenerate, saturated or (early
/// stopping) left its box; the `any_*` flags fold this job into its round's flags.
pub(super) fn writeback_flags(
    t: &Dims<'_>,
    (sel, disp): (&Selected, &Displacement),
    wb_lb: Option<Signal>,
    rounds: Signal,
    items: &mut Vec<Item>,
) -> WritebackFlags {
    let r = &t.r;
    let at_wb = |v: &Signal| v.at(r.wbe.wb_q_path.e());
    let frozen_sig = Signal::wire(items, "wb_frozen", 1);
    let mut frozen = or(or(at_wb(&r.conv), at_wb(&r.dz)), at_wb(&r.ov));
    let any_lb = wb_lb.zip(r.early()).map(|(wb_lb, (lb, plb))| {
        frozen = or(frozen.clone(), at_wb(lb));
        Signal::assigned(items, "any_lb", 1, or(at_wb(plb), wb_lb.e()))
    });
    items.push(Item::Assign(frozen_sig.e(), frozen));
    let go = Signal::assigned(
        items,
        "wb_go",
        1,
        t.r.wb_on
            .e()
            .and(t.r.wbe.wb_q_en.e())
            .and(frozen_sig.e().lnot()),
    );
    let any_big = Signal::assigned(items, "any_big", 1, or(at_wb(&r.pbig), disp.big.e()));
    let any_dz = Signal::assigned(items, "any_dz", 1, or(at_wb(&r.pdz), sel.zs.e()));
    let any_ov = Signal::assigned(items, "any_ov", 1, or(at_wb(&r.pov), sel.ov.e()));
    WritebackFlags {
        go,
        any_big,
        any_dz,
        any_ov,
        any_lb,
        rounds,
    }
}

/// A committed job's effect on its path's flags: at the round's end, flip the bank, count the
/// round and decide convergence; inside the round, accumulate the flags.
pub(super) fn path_commit(t: &Dims<'_>, f: &WritebackFlags) -> Vec<Stmt> {
    let r = &t.r;
    let wbp = |v: &Signal| v.at(r.wbe.wb_q_path.e());
    let mut conv_next = f
        .any_big
        .e()
        .lnot()
        .and(f.any_dz.e().lnot())
        .and(f.any_ov.e().lnot());
    let mut at_end = Vec::new();
    let mut in_round = Vec::new();
    if let Some((any_lb, (lb, plb))) = f.any_lb.as_ref().zip(r.early()) {
        conv_next = conv_next.and(any_lb.e().lnot());
        at_end.push(nb(
            wbp(lb),
            any_lb.e().and(f.any_dz.e().lnot()).and(f.any_ov.e().lnot()),
        ));
        at_end.push(nb(wbp(plb), lit(1, 0)));
        in_round.push(nb(wbp(plb), any_lb.e()));
    }
    vec![Stmt::If(
        t.r.wbe.wb_q_end.e(),
        vec![
            nb(wbp(&r.cur), wbp(&r.cur).inv()),
            nb(wbp(&r.rvalid), lit(1, 1)),
            nb(wbp(&r.dz), f.any_dz.e()),
            nb(wbp(&r.ov), f.any_ov.e()),
            nb(wbp(&r.conv), conv_next),
            nb(wbp(&r.pbig), lit(1, 0)),
            nb(wbp(&r.pdz), lit(1, 0)),
            nb(wbp(&r.pov), lit(1, 0)),
        ]
        .into_iter()
        .chain(at_end)
        .collect(),
        vec![
            nb(wbp(&r.pbig), f.any_big.e()),
            nb(wbp(&r.pdz), f.any_dz.e()),
            nb(wbp(&r.pov), f.any_ov.e()),
        ]
        .into_iter()
        .chain(in_round)
        .collect(),
    )]
}

/// The widened polygon box of the written instance's plane, per axis (sign bit flipped).
pub(super) struct InstanceBox {
    /// `box_lo_<axis>`.
    pub(super) lo: Vec<Signal>,
    /// `box_hi_<axis>`.
    pub(super) hi: Vec<Signal>,
}

/// Early stopping, box table: the box of the instance being written (`wb_q_inst`), its
/// constants biased by 2^47 so that signed comparisons become unsigned ones.
pub(super) fn instance_box(
    t: &Dims<'_>,
    boxes: &[bt_fixed::FineBox],
    items: &mut Vec<Item>,
) -> InstanceBox {
    let d = t.p;
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
    let set = |b: &bt_fixed::FineBox| {
        let mut stmts = Vec::new();
        for a in 0..3 {
            stmts.push(Stmt::Blocking(lo[a].e(), biased(b.lo[a])));
            stmts.push(Stmt::Blocking(hi[a].e(), biased(b.hi[a])));
        }
        stmts
    };
    // On generic PEs by the job's plane, else by the PE's (its instance).
    let (select, arms, whose) = match &t.r.wbe.wb_q_plane {
        Some(plane) => (
            plane.e(),
            boxes
                .iter()
                .enumerate()
                .map(|(p, b)| (lit(t.plb, p as u128), set(b)))
                .collect(),
            "job's",
        ),
        None => (
            t.r.wbe.wb_q_inst.e(),
            d.platform
                .instances
                .iter()
                .enumerate()
                .map(|(j, inst)| {
                    (
                        lit(d.layout.inst_bits, j as u128),
                        set(&boxes[inst.plane as usize]),
                    )
                })
                .collect(),
            "instance's",
        ),
    };
    items.push(Item::Comment(format!(
        "early stopping: widened polygon box of the written {whose} plane (sign bit flipped)"
    )));
    items.push(Item::AlwaysComb(vec![Stmt::Case(select, arms, defaults)]));
    InstanceBox { lo, hi }
}

/// Early stopping at write-back (twin of `bt_fixed::FineBox::outside` and the `min_rounds`
/// rule of `FixedIpc::run_path`): `wb_lb` = the written point lies outside its instance's
/// widened box by more than `(L1 move) << shift`, in a round ≥ `min_rounds`. Signed 48-bit
/// comparisons are unsigned ones with the sign bit flipped (the box constants are flipped
/// when generated).
pub(super) fn early_stop_logic(
    t: &Dims<'_>,
    (stop, boxes): (&bt_fixed::EarlyStop, &[bt_fixed::FineBox]),
    (disp, rounds_cur): (&Displacement, &Signal),
    items: &mut Vec<Item>,
) -> Signal {
    let d = t.p;
    let w = BOX_BITS;
    let axes = ["x", "y", "z"];
    let bx = instance_box(t, boxes, items);
    let cw = d.model.coord_bits();
    let dispw = cw + 1;
    let mvw = w - bt_fixed::EarlyStop::MAX_SHIFT;
    let zext = |s: &Signal| Expr::concat(vec![lit(mvw - dispw, 0), s.e()]);
    let mv_l1 = Signal::assigned(
        items,
        "mv_l1",
        mvw,
        zext(&disp.adiff[0])
            .plus(zext(&disp.adiff[1]))
            .plus(zext(&disp.adiff[2])),
    );
    let shift = stop.displacement_shift;
    let mut parts = vec![lit(w - mvw - shift, 0), mv_l1.e()];
    if shift > 0 {
        parts.push(lit(shift, 0));
    }
    let slack = Signal::assigned(items, "slack", w, Expr::concat(parts));
    let mut terms = Vec::new();
    for (a, (axis, new)) in axes.iter().zip(&disp.new).enumerate() {
        let bp = Signal::assigned(
            items,
            format!("bp_{axis}"),
            w,
            crate::rtl::pe::sext(new.name(), cw, w),
        );
        for (side, expr) in [
            ("lo", bp.e().plus(slack.e())),
            ("hi", bp.e().minus(slack.e())),
        ] {
            let q = Signal::assigned(items, format!("bq_{side}_{axis}"), w, expr);
            let flipped = Expr::concat(vec![q.bit(w - 1).inv(), q.slice(w - 2, 0)]);
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
            rounds_cur.e(),
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
