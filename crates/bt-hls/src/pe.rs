//! `bt_pe_<i>`: one processing element per plane (Algorithm 2 with Algorithm 3 inside), the
//! plane's constants baked in as CSD shift-add networks. Twin of `bt_fixed::intersection_point`.

use bt_fixed::{FixedPlane, GUARD_BITS, NORMAL_FRAC, PROPORTION_ITERATIONS, width};

use crate::HlsError;
use crate::verilog::{BinaryOp, Direction, Expr, Item, Module, Port, Stmt, UnaryOp};

/// Width of a packed point `{z, y, x}` of fine words.
pub const POINT_BITS: u32 = 3 * width::COORD;

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

/// Adder network `constant + Σ ±(input << shift)` for the CSD digits of `coeffs`.
fn csd_network(
    inputs: &[(&str, &bt_fixed::Csd)],
    input_width: u32,
    constant: i128,
    total: u32,
) -> Result<Expr, HlsError> {
    let mut acc = Expr::lit_signed(total, constant);
    for (name, csd) in inputs {
        for d in &csd.digits {
            let term = shifted_term(name, input_width, d.shift, total)?;
            acc = if d.negative {
                acc.minus(term)
            } else {
                acc.plus(term)
            };
        }
    }
    Ok(acc)
}

/// Name of the PE module of plane `index`.
pub fn pe_module_name(index: usize) -> String {
    format!("bt_pe_{index}")
}

/// Builds `bt_pe_<index>` for `plane`.
pub(crate) fn pe_module(
    index: usize,
    plane_name: &str,
    plane: &FixedPlane,
) -> Result<Module, HlsError> {
    let cw = width::COORD;
    let half = 1i128 << (NORMAL_FRAC - 1);
    let g = GUARD_BITS;
    let (dw, tw, deltaw, sumw) = (
        width::DISTANCE,
        width::PROJECTION,
        width::DELTA,
        width::DISTANCE_SUM,
    );
    let (lw, bw, lpw, bpw) = (
        width::HALF_SUM,
        width::SEARCH,
        width::HALF_DELTA,
        width::ACC_DELTA,
    );
    let (offw, spw) = (width::OFFSET, width::SUM_POINT);
    debug_assert_eq!(width::DOT_ACC, width::PROJ_ACC);
    let accw = width::DOT_ACC;
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
    // Stage 0 (combinational from the held operands): signed distances.
    let dot_const = half - (i128::from(plane.offset.0) << NORMAL_FRAC);
    for side in ["prev", "next"] {
        for (k, axis) in AXES.iter().enumerate() {
            let name = format!("{side}_{axis}");
            items.push(Item::Wire(name.clone(), cw));
            items.push(Item::Assign(
                Expr::id(&name),
                Expr::slice(format!("s_{side}"), cw * (k as u32 + 1) - 1, cw * k as u32),
            ));
        }
        let names: Vec<String> = AXES.iter().map(|a| format!("{side}_{a}")).collect();
        let inputs: Vec<(&str, &bt_fixed::Csd)> =
            names.iter().map(String::as_str).zip(csd.iter()).collect();
        let acc = format!("d_{side}_acc");
        items.push(Item::Comment(format!(
            "d_{side} = round_half_up((n . s_{side} - offset * 2^30) / 2^30)"
        )));
        items.push(Item::Wire(acc.clone(), accw));
        items.push(Item::Assign(
            Expr::id(&acc),
            csd_network(&inputs, cw, dot_const, accw)?,
        ));
        unused.push(Expr::slice(&acc, NORMAL_FRAC - 1, 0));
        items.push(Item::Reg(format!("d_{side}"), dw));
    }
    // Stage 1: projections, m, n, delta.
    for side in ["prev", "next"] {
        for (k, axis) in AXES.iter().enumerate() {
            let acc = format!("p_{side}_{axis}_acc");
            let d = format!("d_{side}");
            items.push(Item::Wire(acc.clone(), accw));
            items.push(Item::Assign(
                Expr::id(&acc),
                csd_network(&[(&d, &csd[k])], dw, half, accw)?,
            ));
            unused.push(Expr::slice(&acc, NORMAL_FRAC - 1, 0));
            let t = format!("t_{side}_{axis}");
            items.push(Item::Wire(t.clone(), tw));
            items.push(Item::Assign(
                Expr::id(&t),
                sext(&format!("{side}_{axis}"), cw, tw).minus(Expr::slice(
                    &acc,
                    accw - 1,
                    NORMAL_FRAC,
                )),
            ));
        }
    }
    for axis in AXES {
        let delta = format!("delta_{axis}");
        items.push(Item::Wire(delta.clone(), deltaw));
        items.push(Item::Assign(
            Expr::id(&delta),
            sext(&format!("t_next_{axis}"), tw, deltaw).minus(sext(
                &format!("t_prev_{axis}"),
                tw,
                deltaw,
            )),
        ));
    }
    for (abs, d) in [("m_dist", "d_prev"), ("n_dist", "d_next")] {
        items.push(Item::Wire(abs.into(), dw));
        items.push(Item::Assign(
            Expr::id(abs),
            Expr::mux(
                Expr::bit(d, dw - 1),
                Expr::id(d).inv().plus(Expr::lit(dw, 1)),
                Expr::id(d),
            ),
        ));
    }
    debug_assert_eq!(sumw, dw);
    items.push(Item::Wire("dist_sum".into(), sumw));
    items.push(Item::Assign(
        Expr::id("dist_sum"),
        Expr::id("m_dist").plus(Expr::id("n_dist")),
    ));
    // Algorithm 3 registers and one iteration.
    items.push(Item::Comment(format!(
        "Algorithm 3 on {g} guard bits: L <- (m+n)/2, B <- L, Lp <- l/2, Bp <- Lp; {PROPORTION_ITERATIONS} steps, frozen once L = 0"
    )));
    for (n, w) in [
        ("hc_l", lw),
        ("hc_b", bw),
        ("hc_m", bw),
        ("hc_iter", width::ITERATION),
        ("phase", 2),
    ] {
        items.push(Item::Reg(n.into(), w));
    }
    items.push(Item::Reg("hc_zs".into(), 1));
    for axis in AXES {
        items.push(Item::Reg(format!("hc_lp_{axis}"), lpw));
        items.push(Item::Reg(format!("hc_bp_{axis}"), bpw));
        items.push(Item::Reg(format!("hc_t_{axis}"), tw));
    }
    items.push(Item::Wire("l_half".into(), lw));
    items.push(Item::Assign(
        Expr::id("l_half"),
        Expr::concat(vec![Expr::lit(1, 0), Expr::slice("hc_l", lw - 1, 1)]),
    ));
    items.push(Item::Wire("go_up".into(), 1));
    items.push(Item::Assign(
        Expr::id("go_up"),
        Expr::bin(BinaryOp::Lt, Expr::id("hc_b"), Expr::id("hc_m")),
    ));
    items.push(Item::Wire("b_next".into(), bw));
    let l_ext = Expr::concat(vec![Expr::lit(1, 0), Expr::id("l_half")]);
    items.push(Item::Assign(
        Expr::id("b_next"),
        Expr::mux(
            Expr::id("go_up"),
            Expr::id("hc_b").plus(l_ext.clone()),
            Expr::id("hc_b").minus(l_ext),
        ),
    ));
    let mut sat_parts = Vec::new();
    let mut ovf_terms = Vec::new();
    for axis in AXES {
        let lp = format!("hc_lp_{axis}");
        unused.push(Expr::bit(&lp, 0));
        let lph = format!("lp_half_{axis}");
        items.push(Item::Wire(lph.clone(), lpw));
        items.push(Item::Assign(
            Expr::id(&lph),
            Expr::concat(vec![Expr::bit(&lp, lpw - 1), Expr::slice(&lp, lpw - 1, 1)]),
        ));
        let bp = format!("hc_bp_{axis}");
        let bpn = format!("bp_next_{axis}");
        items.push(Item::Wire(bpn.clone(), bpw));
        items.push(Item::Assign(
            Expr::id(&bpn),
            Expr::mux(
                Expr::id("go_up"),
                Expr::id(&bp).plus(sext(&lph, lpw, bpw)),
                Expr::id(&bp).minus(sext(&lph, lpw, bpw)),
            ),
        ));
        // Output: round_half_up(Bp / 2^G), add to t_prev, saturate to the 40-bit word.
        let oacc = format!("off_acc_{axis}");
        items.push(Item::Wire(oacc.clone(), bpw));
        items.push(Item::Assign(
            Expr::id(&oacc),
            Expr::id(&bp).plus(Expr::lit(bpw, 1 << (g - 1))),
        ));
        unused.push(Expr::slice(&oacc, g - 1, 0));
        debug_assert_eq!(bpw - g, offw);
        let sum = format!("sum_{axis}");
        items.push(Item::Wire(sum.clone(), spw));
        items.push(Item::Assign(
            Expr::id(&sum),
            sext(&format!("hc_t_{axis}"), tw, spw).plus(sext_slice(&oacc, bpw - 1, g, spw)),
        ));
        let ovf = format!("ovf_{axis}");
        let top = Expr::slice(&sum, spw - 1, cw - 1);
        let topw = spw - cw + 1;
        items.push(Item::Wire(ovf.clone(), 1));
        items.push(Item::Assign(
            Expr::id(&ovf),
            Expr::bin(
                BinaryOp::LogicAnd,
                Expr::bin(BinaryOp::Ne, top.clone(), Expr::lit(topw, 0)),
                Expr::bin(BinaryOp::Ne, top, Expr::lit(topw, (1u128 << topw) - 1)),
            ),
        ));
        let sat = format!("sat_{axis}");
        items.push(Item::Wire(sat.clone(), cw));
        items.push(Item::Assign(
            Expr::id(&sat),
            Expr::mux(
                Expr::id(&ovf),
                Expr::mux(
                    Expr::bit(&sum, spw - 1),
                    Expr::lit(cw, 1 << (cw - 1)),
                    Expr::lit(cw, (1 << (cw - 1)) - 1),
                ),
                Expr::slice(&sum, cw - 1, 0),
            ),
        ));
        sat_parts.insert(0, Expr::id(&sat));
        ovf_terms.push(Expr::id(&ovf));
    }
    // Sequencer.
    let nb = |l: &str, r: Expr| Stmt::NonBlocking(Expr::id(l), r);
    let idle = vec![Stmt::If(
        Expr::id("start"),
        vec![
            nb("d_prev", Expr::slice("d_prev_acc", accw - 1, NORMAL_FRAC)),
            nb("d_next", Expr::slice("d_next_acc", accw - 1, NORMAL_FRAC)),
            nb("phase", Expr::lit(2, 1)),
        ],
        vec![],
    )];
    let mut setup = vec![
        nb(
            "hc_l",
            Expr::concat(vec![Expr::id("dist_sum"), Expr::lit(1, 0).repeat(g - 1)]),
        ),
        nb(
            "hc_b",
            Expr::concat(vec![
                Expr::lit(1, 0),
                Expr::id("dist_sum"),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ),
        nb(
            "hc_m",
            Expr::concat(vec![Expr::id("m_dist"), Expr::lit(1, 0).repeat(g)]),
        ),
        nb("hc_zs", Expr::id("dist_sum").eq(Expr::lit(sumw, 0))),
        nb("hc_iter", Expr::lit(width::ITERATION, 0)),
        nb("phase", Expr::lit(2, 2)),
    ];
    debug_assert_eq!(bw, sumw + g);
    for axis in AXES {
        let delta = format!("delta_{axis}");
        setup.push(nb(
            &format!("hc_lp_{axis}"),
            Expr::concat(vec![Expr::id(&delta), Expr::lit(1, 0).repeat(g - 1)]),
        ));
        setup.push(nb(
            &format!("hc_bp_{axis}"),
            Expr::concat(vec![
                Expr::bit(&delta, deltaw - 1).repeat(bpw - lpw),
                Expr::id(&delta),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ));
        setup.push(nb(
            &format!("hc_t_{axis}"),
            Expr::id(format!("t_prev_{axis}")),
        ));
    }
    let mut step = vec![
        nb("hc_l", Expr::id("l_half")),
        nb("hc_b", Expr::id("b_next")),
    ];
    for axis in AXES {
        step.push(nb(
            &format!("hc_lp_{axis}"),
            Expr::id(format!("lp_half_{axis}")),
        ));
        step.push(nb(
            &format!("hc_bp_{axis}"),
            Expr::id(format!("bp_next_{axis}")),
        ));
    }
    let iterate = vec![
        Stmt::If(
            Expr::bin(BinaryOp::Ne, Expr::id("hc_l"), Expr::lit(lw, 0)),
            step,
            vec![],
        ),
        nb(
            "hc_iter",
            Expr::id("hc_iter").plus(Expr::lit(width::ITERATION, 1)),
        ),
        Stmt::If(
            Expr::id("hc_iter").eq(Expr::lit(
                width::ITERATION,
                u128::from(PROPORTION_ITERATIONS - 1),
            )),
            vec![nb("phase", Expr::lit(2, 3))],
            vec![],
        ),
    ];
    let ovf_any = ovf_terms
        .into_iter()
        .reduce(|a, b| Expr::bin(BinaryOp::Or, a, b))
        .expect("three axes");
    let output = vec![
        nb("s_out", Expr::concat(sat_parts)),
        nb("zero_sum", Expr::id("hc_zs")),
        nb("overflow", ovf_any),
        nb("phase", Expr::lit(2, 0)),
    ];
    items.push(Item::AlwaysFf(vec![Stmt::If(
        Expr::id("rst_n").lnot(),
        vec![
            nb("phase", Expr::lit(2, 0)),
            nb("s_out", Expr::lit(POINT_BITS, 0)),
            nb("zero_sum", Expr::lit(1, 0)),
            nb("overflow", Expr::lit(1, 0)),
        ],
        vec![Stmt::Case(
            Expr::id("phase"),
            vec![
                (Expr::lit(2, 0), idle),
                (Expr::lit(2, 1), setup),
                (Expr::lit(2, 2), iterate),
                (Expr::lit(2, 3), output),
            ],
            vec![nb("phase", Expr::lit(2, 0))],
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
                "Latency {} cycles from `start`; twin of bt_fixed::intersection_point.",
                crate::PE_LATENCY
            ),
            "Points are {z, y, x} of 40-bit two's-complement words, mm x 2^8.".into(),
        ],
        ports: vec![
            port("clk", Direction::Input, 1),
            port("rst_n", Direction::Input, 1),
            port("start", Direction::Input, 1),
            port("s_prev", Direction::Input, POINT_BITS),
            port("s_next", Direction::Input, POINT_BITS),
            port("s_out", Direction::OutputReg, POINT_BITS),
            port("zero_sum", Direction::OutputReg, 1),
            port("overflow", Direction::OutputReg, 1),
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
