//! `bt_pe_<i>`: one processing element per plane (Algorithm 2 with Algorithm 3 inside), the
//! plane's constants baked in as CSD shift-add networks. Twin of `bt_fixed::intersection_point`.

use bt_fixed::{FixedPlane, GUARD_BITS, NORMAL_FRAC, PROPORTION_ITERATIONS, width};

use crate::HlsError;
use crate::verilog::{BinaryOp, Direction, Expr, Item, Module, Port, Stmt, UnaryOp};

/// Width of a packed point `{z, y, x}` of fine words.
pub const POINT_BITS: u32 = 3 * width::COORD;

/// Width of a PE's packed unsaturated result `{z, y, x}` ([`width::SUM_POINT`] bits each).
pub const SUM_BITS: u32 = 3 * width::SUM_POINT;

const AXES: [&str; 3] = ["x", "y", "z"];

pub(crate) fn port(name: &str, dir: Direction, width: u32) -> Port {
    Port {
        name: name.into(),
        dir,
        width,
    }
}

/// `{{pad{name[w-1]}}, name, {shift{1'b0}}}`: `name` (w bits, two's complement) sign-extended
/// and shifted left into a `total`-bit word.
pub(crate) fn shifted_term(name: &str, w: u32, shift: u32, total: u32) -> Result<Expr, HlsError> {
    let pad = total.checked_sub(w + shift).ok_or_else(|| {
        HlsError::TooLarge(format!("term {name} << {shift} does not fit {total} bits"))
    })?;
    let mut parts = Vec::new();
    if pad > 0 {
        parts.push(Expr::bit(name, w - 1).repeat(pad));
    }
    parts.push(Expr::id(name));
    if shift > 0 {
        parts.push(Expr::lit(1, 0).repeat(shift));
    }
    Ok(if parts.len() == 1 {
        Expr::id(name)
    } else {
        Expr::concat(parts)
    })
}

/// Sign extension of `name` (w bits) to `total` bits.
pub(crate) fn sext(name: &str, w: u32, total: u32) -> Expr {
    if total == w {
        Expr::id(name)
    } else {
        Expr::concat(vec![
            Expr::bit(name, w - 1).repeat(total - w),
            Expr::id(name),
        ])
    }
}

/// `Σ ±(input << (shift − base))` over the CSD digits of one normal component, in `total`
/// bits (two's complement, modulo 2^total): the product `input · n_k / 2^base`, exact because
/// every digit's shift is ≥ `base`.
fn csd_sum(
    input: &str,
    input_width: u32,
    csd: &bt_fixed::Csd,
    base: u32,
    total: u32,
) -> Result<Expr, HlsError> {
    let mut acc: Option<Expr> = None;
    for d in &csd.digits {
        let term = shifted_term(input, input_width, d.shift - base, total)?;
        acc = Some(match (acc, d.negative) {
            (None, false) => term,
            (None, true) => Expr::lit(total, 0).minus(term),
            (Some(a), false) => a.plus(term),
            (Some(a), true) => a.minus(term),
        });
    }
    Ok(acc.unwrap_or_else(|| Expr::lit(total, 0)))
}

/// `sub ? a − b : a + b` as one `w`-bit adder (`{a, 1} + {b ^ sub, sub}`, top `w` bits): the
/// carry-in rides on an extra LSB so no second adder and no result multiplexer is built.
/// Declares the `w + 1`-bit wire `name` and returns `name[w:1]`.
fn add_sub(
    items: &mut Vec<Item>,
    unused: &mut Vec<Expr>,
    name: &str,
    a: Expr,
    b: Expr,
    sub: Expr,
    w: u32,
) -> Expr {
    items.push(Item::Wire(name.into(), w + 1));
    items.push(Item::Assign(
        Expr::id(name),
        Expr::concat(vec![a, Expr::lit(1, 1)]).plus(Expr::concat(vec![
            Expr::bin(BinaryOp::Xor, b, sub.clone().repeat(w)),
            sub,
        ])),
    ));
    unused.push(Expr::bit(name, 0));
    Expr::slice(name, w, 1)
}

/// Name of the PE module of plane `index`.
pub fn pe_module_name(index: usize) -> String {
    format!("bt_pe_{index}")
}

/// First iteration step of Algorithm 3 in the PE's step counter (see [`pe_module`]).
const FIRST_ITERATION_STEP: u32 = 5;

/// Builds `bt_pe_<index>` for `plane`: a small sequential datapath that time-shares one CSD
/// network per normal component over the four products of Algorithm 2, folds the operand,
/// projection and Algorithm 3 registers into each other and fuses the output addition into the
/// `B_p` accumulator. Bit-exact with `bt_fixed::intersection_point` (before saturation, which
/// `bt_top` applies once after its PE select):
///
/// | step | network input | writes |
/// |---|---|---|
/// | idle, `load` | - | `a_k ← s_prev_k`, `b_k ← s_next_k` |
/// | idle, `start` | `a_k` | `r_e ← d_prev` |
/// | 1 | `b_k` | `r_l ← d_next` |
/// | 2 | `r_e` | `a_k ← t_prev_k = a_k − round(d_prev·n_k)` |
/// | 3 | `r_l` | `b_k ← t_next_k` |
/// | 4 | - | `b_k ← L_p0 = δ_k·2^15`, `a_k ← (t_prev+t_next)·2^15 + 2^15` (= `t_prev·2^16 + 2^15 + B_p0`), `r_e ← E = (n−m)·2^15`, `r_l ← L = (m+n)·2^15` |
/// | 5 .. 36 | - | one halving step: `r_l ← L/2`, `b_k ← L_p/2`, `E ± L/2`, `a_k ± L_p/2` (sign of `E` decides) |
///
/// `s_sum_k = a_k >> 16 = t_prev_k + round(B_p/2^16)`, valid from [`crate::PE_LATENCY`] cycles
/// after `start` until the next `load`.
pub(crate) fn pe_module(
    index: usize,
    plane_name: &str,
    plane: &FixedPlane,
) -> Result<Module, HlsError> {
    let cw = width::COORD;
    let g = GUARD_BITS;
    let xw = width::DISTANCE; // network input: s (40 bits, sign-extended), d or t (42 bits)
    debug_assert_eq!(width::PROJECTION, xw);
    let (deltaw, sumw, accw) = (width::DELTA, width::DISTANCE_SUM, width::DOT_ACC);
    let (lw, ew, lpw, aw) = (
        width::HALF_SUM,
        width::SEARCH_DIFF,
        width::HALF_DELTA,
        width::POINT_ACC,
    );
    let spw = width::SUM_POINT;
    let last_step = FIRST_ITERATION_STEP + PROPORTION_ITERATIONS - 1;
    let stepw = 64 - u64::from(last_step).leading_zeros();
    let mut items = Vec::new();
    let csd: Vec<bt_fixed::Csd> = plane.normal.iter().map(|n| n.csd()).collect();
    items.push(Item::Comment(format!(
        "plane {index} '{plane_name}': n = ({}, {}, {}) (Q2.30 raw {}, {}, {}), offset = {} fine LSB\n\
         CSD digits per component: {}, {}, {}",
        plane.normal[0].dequantize(),
        plane.normal[1].dequantize(),
        plane.normal[2].dequantize(),
        plane.normal[0].0,
        plane.normal[1].0,
        plane.normal[2].0,
        plane.offset.0,
        csd[0].digits.len(),
        csd[1].digits.len(),
        csd[2].digits.len()
    )));
    let mut unused = Vec::new();
    items.push(Item::Reg("step".into(), stepw));
    items.push(Item::Reg("zs".into(), 1));
    items.push(Item::Reg("r_e".into(), ew));
    items.push(Item::Reg("r_l".into(), lw));
    for axis in AXES {
        items.push(Item::Reg(format!("a_{axis}"), aw));
        items.push(Item::Reg(format!("b_{axis}"), lpw));
    }
    // Shared networks: input selected by step[1:0] (0 = a, 1 = b, 2 = r_e, 3 = r_l).
    items.push(Item::Comment(
        "one CSD network per non-zero normal component, shared by d_prev, d_next, t_prev, t_next"
            .into(),
    ));
    let low = |n: &str| Expr::slice(n, xw - 1, 0);
    let s1 = Expr::bit("step", 1);
    let s0 = Expr::bit("step", 0);
    // Lowest digit shift per component (the network's exact low bits are all zero below it).
    let base: Vec<Option<u32>> = csd
        .iter()
        .map(|c| c.digits.iter().map(|d| d.shift).min())
        .collect();
    for (k, axis) in AXES.iter().enumerate() {
        let Some(bk) = base[k] else { continue };
        let xin = format!("x_in_{axis}");
        items.push(Item::Wire(xin.clone(), xw));
        items.push(Item::Assign(
            Expr::id(&xin),
            Expr::mux(
                s1.clone(),
                Expr::mux(s0.clone(), low("r_l"), low("r_e")),
                Expr::mux(
                    s0.clone(),
                    low(&format!("b_{axis}")),
                    low(&format!("a_{axis}")),
                ),
            ),
        ));
        let net = format!("net_{axis}");
        let nw = accw - bk;
        items.push(Item::Comment(format!(
            "net_{axis} = x_in_{axis} * n_{axis} / 2^{bk} ({} digits)",
            csd[k].digits.len()
        )));
        items.push(Item::Wire(net.clone(), nw));
        items.push(Item::Assign(
            Expr::id(&net),
            csd_sum(&xin, xw, &csd[k], bk, nw)?,
        ));
    }
    // Signed distance: round_half_up((Σ n_k x_k − offset·2^30) / 2^30), exact below bit `sd`.
    let nf = NORMAL_FRAC;
    let sd = base.iter().flatten().copied().min().unwrap_or(nf).min(nf);
    let dot_const = (1i128 << (nf - 1)) - (i128::from(plane.offset.0) << nf);
    let dw = accw - sd;
    let mut dot = Expr::lit_signed(dw, dot_const >> sd);
    for (k, axis) in AXES.iter().enumerate() {
        let Some(bk) = base[k] else { continue };
        dot = dot.plus(shifted_term(
            &format!("net_{axis}"),
            accw - bk,
            bk - sd,
            dw,
        )?);
    }
    items.push(Item::Comment(format!(
        "dot = (n . x_in - offset * 2^30 + 2^29) / 2^{sd}; d = dot >> {}",
        nf - sd
    )));
    items.push(Item::Wire("dot".into(), dw));
    items.push(Item::Assign(Expr::id("dot"), dot));
    if nf > sd {
        unused.push(Expr::slice("dot", nf - sd - 1, 0));
    }
    items.push(Item::Wire("d_new".into(), xw));
    items.push(Item::Assign(
        Expr::id("d_new"),
        Expr::slice("dot", dw - 1, nf - sd),
    ));
    // Projections: t_k = base_k − round_half_up(d · n_k / 2^30), base = a (step 2) or b (step 3).
    for (k, axis) in AXES.iter().enumerate() {
        let pbase = Expr::mux(
            s0.clone(),
            low(&format!("b_{axis}")),
            low(&format!("a_{axis}")),
        );
        let t = format!("t_{axis}");
        items.push(Item::Wire(t.clone(), xw));
        let Some(bk) = base[k] else {
            items.push(Item::Assign(Expr::id(&t), pbase));
            continue;
        };
        let net = format!("net_{axis}");
        let nw = accw - bk;
        let p = if bk >= nf {
            // Multiple of 2^30: the rounding half cannot carry.
            if bk > nf {
                return Err(HlsError::TooLarge(format!(
                    "normal component {axis} of plane {index} has a digit above 2^30"
                )));
            }
            Expr::id(&net)
        } else {
            let pr = format!("p_round_{axis}");
            items.push(Item::Wire(pr.clone(), nw));
            items.push(Item::Assign(
                Expr::id(&pr),
                Expr::id(&net).plus(Expr::lit(nw, 1u128 << (nf - 1 - bk))),
            ));
            unused.push(Expr::slice(&pr, nf - bk - 1, 0));
            Expr::slice(&pr, nw - 1, nf - bk)
        };
        items.push(Item::Assign(Expr::id(&t), pbase.minus(p)));
    }
    // Step 4: m, n, delta, and the Algorithm 3 initial values.
    for (abs, r) in [("m_dist", "r_e"), ("n_dist", "r_l")] {
        items.push(Item::Wire(abs.into(), xw));
        items.push(Item::Assign(
            Expr::id(abs),
            Expr::mux(
                Expr::bit(r, xw - 1),
                low(r).inv().plus(Expr::lit(xw, 1)),
                low(r),
            ),
        ));
    }
    debug_assert_eq!(sumw, xw);
    items.push(Item::Wire("dist_sum".into(), sumw));
    items.push(Item::Assign(
        Expr::id("dist_sum"),
        Expr::id("m_dist").plus(Expr::id("n_dist")),
    ));
    items.push(Item::Wire("dist_diff".into(), sumw + 1));
    items.push(Item::Assign(
        Expr::id("dist_diff"),
        Expr::concat(vec![Expr::lit(1, 0), Expr::id("n_dist")])
            .minus(Expr::concat(vec![Expr::lit(1, 0), Expr::id("m_dist")])),
    ));
    for axis in AXES {
        let (a, b) = (format!("a_{axis}"), format!("b_{axis}"));
        let delta = format!("delta_{axis}");
        items.push(Item::Wire(delta.clone(), deltaw));
        items.push(Item::Assign(
            Expr::id(&delta),
            sext_slice(&b, xw - 1, 0, deltaw).minus(sext_slice(&a, xw - 1, 0, deltaw)),
        ));
        // t_prev + t_next + 1 as one adder: {b, 1} + {a, 1} = 2·(a + b + 1).
        let tsum = format!("tsum_{axis}");
        items.push(Item::Wire(tsum.clone(), deltaw + 1));
        items.push(Item::Assign(
            Expr::id(&tsum),
            Expr::concat(vec![sext_slice(&b, xw - 1, 0, deltaw), Expr::lit(1, 1)]).plus(
                Expr::concat(vec![sext_slice(&a, xw - 1, 0, deltaw), Expr::lit(1, 1)]),
            ),
        ));
        unused.push(Expr::bit(&tsum, 0));
    }
    // One halving step.
    items.push(Item::Comment(format!(
        "Algorithm 3 on {g} guard bits, {PROPORTION_ITERATIONS} steps frozen once L = 0; E = B - m*2^{g} replaces B, m and the comparator"
    )));
    items.push(Item::Wire("go_up".into(), 1));
    items.push(Item::Assign(Expr::id("go_up"), Expr::bit("r_e", ew - 1)));
    let l_half = Expr::concat(vec![
        Expr::lit(ew - lw + 1, 0),
        Expr::slice("r_l", lw - 1, 1),
    ]);
    let e_next = add_sub(
        &mut items,
        &mut unused,
        "e_next",
        Expr::id("r_e"),
        l_half,
        Expr::id("go_up").lnot(),
        ew,
    );
    let mut a_next = Vec::new();
    for axis in AXES {
        let b = format!("b_{axis}");
        let lph = format!("lp_half_{axis}");
        items.push(Item::Wire(lph.clone(), lpw));
        items.push(Item::Assign(
            Expr::id(&lph),
            Expr::concat(vec![Expr::bit(&b, lpw - 1), Expr::slice(&b, lpw - 1, 1)]),
        ));
        a_next.push(add_sub(
            &mut items,
            &mut unused,
            &format!("a_next_{axis}"),
            Expr::id(format!("a_{axis}")),
            sext(&lph, lpw, aw),
            Expr::id("go_up").lnot(),
            aw,
        ));
    }
    // Output: the unsaturated point t_prev + round(B_p / 2^G) = a >> G.
    let mut sum_parts = Vec::new();
    for axis in AXES {
        sum_parts.insert(0, Expr::slice(format!("a_{axis}"), aw - 1, g));
    }
    debug_assert_eq!(aw - g, spw);
    items.push(Item::Assign(Expr::id("s_sum"), Expr::concat(sum_parts)));
    items.push(Item::Assign(Expr::id("zero_sum"), Expr::id("zs")));

    // Sequencer.
    let nb = |l: &str, r: Expr| Stmt::NonBlocking(Expr::id(l), r);
    let step_is = |v: u32| Expr::id("step").eq(Expr::lit(stepw, v.into()));
    let mut load = Vec::new();
    for (k, axis) in AXES.iter().enumerate() {
        let (hi, lo) = (cw * (k as u32 + 1) - 1, cw * k as u32);
        load.push(nb(&format!("a_{axis}"), sext_slice("s_prev", hi, lo, aw)));
        load.push(nb(&format!("b_{axis}"), sext_slice("s_next", hi, lo, lpw)));
    }
    let idle = vec![Stmt::If(
        Expr::id("start"),
        vec![
            nb("r_e", sext("d_new", xw, ew)),
            nb("step", Expr::lit(stepw, 1)),
        ],
        vec![Stmt::If(Expr::id("load"), load, vec![])],
    )];
    let mut proj_prev = Vec::new();
    let mut proj_next = Vec::new();
    let mut setup = vec![
        nb(
            "r_e",
            Expr::concat(vec![
                Expr::bit("dist_diff", sumw).repeat(ew - (sumw + 1) - (g - 1)),
                Expr::id("dist_diff"),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ),
        nb(
            "r_l",
            Expr::concat(vec![Expr::id("dist_sum"), Expr::lit(1, 0).repeat(g - 1)]),
        ),
        nb("zs", Expr::id("dist_sum").eq(Expr::lit(sumw, 0))),
    ];
    debug_assert_eq!(lw, sumw + g - 1);
    debug_assert_eq!(lpw, deltaw + g - 1);
    let mut iterate = vec![
        nb(
            "r_l",
            Expr::concat(vec![Expr::lit(1, 0), Expr::slice("r_l", lw - 1, 1)]),
        ),
        nb("r_e", e_next),
    ];
    for (k, axis) in AXES.iter().enumerate() {
        let (a, b, t) = (
            format!("a_{axis}"),
            format!("b_{axis}"),
            format!("t_{axis}"),
        );
        proj_prev.push(nb(&a, sext(&t, xw, aw)));
        proj_next.push(nb(&b, sext(&t, xw, lpw)));
        setup.push(nb(
            &b,
            Expr::concat(vec![
                Expr::id(format!("delta_{axis}")),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ));
        // t_prev·2^G + 2^(G−1) + B_p0 = (t_prev + t_next + 1)·2^(G−1), modulo 2^POINT_ACC.
        let tsum = format!("tsum_{axis}");
        setup.push(nb(
            &a,
            Expr::concat(vec![
                Expr::bit(&tsum, deltaw).repeat(aw - deltaw - (g - 1)),
                Expr::slice(&tsum, deltaw, 1),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ));
        iterate.push(nb(&b, Expr::id(format!("lp_half_{axis}"))));
        iterate.push(nb(&a, a_next[k].clone()));
    }
    debug_assert!(aw >= deltaw + g);
    proj_prev.push(nb("step", Expr::lit(stepw, 3)));
    proj_next.push(nb("step", Expr::lit(stepw, 4)));
    setup.push(nb("step", Expr::lit(stepw, FIRST_ITERATION_STEP.into())));
    let iterate = vec![
        Stmt::If(
            Expr::bin(BinaryOp::Ne, Expr::id("r_l"), Expr::lit(lw, 0)),
            iterate,
            vec![],
        ),
        Stmt::If(
            step_is(last_step),
            vec![nb("step", Expr::lit(stepw, 0))],
            vec![nb("step", Expr::id("step").plus(Expr::lit(stepw, 1)))],
        ),
    ];
    items.push(Item::AlwaysFf(vec![Stmt::If(
        Expr::id("rst_n").lnot(),
        vec![nb("step", Expr::lit(stepw, 0))],
        vec![Stmt::Case(
            Expr::id("step"),
            vec![
                (Expr::lit(stepw, 0), idle),
                (
                    Expr::lit(stepw, 1),
                    vec![
                        nb(
                            "r_l",
                            Expr::concat(vec![Expr::lit(lw - xw, 0), Expr::id("d_new")]),
                        ),
                        nb("step", Expr::lit(stepw, 2)),
                    ],
                ),
                (Expr::lit(stepw, 2), proj_prev),
                (Expr::lit(stepw, 3), proj_next),
                (Expr::lit(stepw, 4), setup),
            ],
            iterate,
        )],
    )]));
    items.push(Item::Wire("bt_unused_ok".into(), 1));
    unused.insert(0, Expr::lit(1, 0));
    items.push(Item::Assign(
        Expr::id("bt_unused_ok"),
        Expr::Unary(UnaryOp::ReduceAnd, Box::new(Expr::concat(unused))),
    ));
    Ok(Module {
        name: pe_module_name(index),
        header: vec![
            format!(
                "bt_pe_{index}: IPC processing element of plane {index} ('{plane_name}'), generated by bt-hls."
            ),
            format!(
                "`load` latches the operands; `s_sum` valid {} cycles after `start`; twin of bt_fixed::intersection_point before saturation.",
                crate::PE_LATENCY
            ),
            format!(
                "Operands are {{z, y, x}} of 40-bit words, s_sum {{z, y, x}} of {spw}-bit words, mm x 2^8."
            ),
        ],
        ports: vec![
            port("clk", Direction::Input, 1),
            port("rst_n", Direction::Input, 1),
            port("load", Direction::Input, 1),
            port("start", Direction::Input, 1),
            port("s_prev", Direction::Input, POINT_BITS),
            port("s_next", Direction::Input, POINT_BITS),
            port("s_sum", Direction::Output, SUM_BITS),
            port("zero_sum", Direction::Output, 1),
        ],
        items,
    })
}

/// `name[hi:lo]` sign-extended to `total` bits.
fn sext_slice(name: &str, hi: u32, lo: u32, total: u32) -> Expr {
    let w = hi - lo + 1;
    if total == w {
        Expr::slice(name, hi, lo)
    } else {
        Expr::concat(vec![
            Expr::bit(name, hi).repeat(total - w),
            Expr::slice(name, hi, lo),
        ])
    }
}
