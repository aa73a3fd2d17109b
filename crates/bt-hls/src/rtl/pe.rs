//! `bt_pe_<i>`: one processing element per plane (Algorithm 2 with Algorithm 3 inside), the
//! plane's constants baked in as CSD shift-add networks around `bt_pe_core`, the registers,
//! Algorithm 3 and the sequencer that every PE of a design shares. Twin of
//! `bt_fixed::intersection_point`.

use bt_fixed::{FixedPlane, GUARD_BITS, NORMAL_FRAC, Widths};

use crate::HlsError;
use crate::rtl::mult::{NetworkForm, multiplier_network};
use crate::rtl::verilog::{BinaryOp, Direction, Expr, Item, Module, Port, Signal, Stmt, UnaryOp};

/// Width of a packed point `{z, y, x}` of fine words in a design of widths `wd`.
pub fn point_bits(wd: Widths) -> u32 {
    3 * wd.coord
}

/// Width of a PE's packed unsaturated result `{z, y, x}` (`wd.sum_point` bits each).
pub fn sum_bits(wd: Widths) -> u32 {
    3 * wd.sum_point
}

pub(super) const AXES: [&str; 3] = ["x", "y", "z"];

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

/// Name of the plane-independent core that every `bt_pe_<i>` instantiates (`pe_core_module`).
pub const PE_CORE_MODULE: &str = "bt_pe_core";

/// First iteration step of Algorithm 3 in the PE's step counter (see [`pe_module`]).
const FIRST_ITERATION_STEP: u32 = 5;

/// Builds `bt_pe_<index>` for `plane`: the plane's constant front end around the shared
/// [`PE_CORE_MODULE`]. The front end time-shares one CSD network per non-zero normal component
/// over the four products of Algorithm 2 (`d = n·x − offset` and `t_k = x_k − d·n_k`, on the
/// core register that `step_sel` picks); the core ([`pe_core_module`]) holds the registers,
/// Algorithm 3 and the sequencer, with the operand, projection and Algorithm 3 registers
/// folded into each other and the output addition fused into the `B_p` accumulator.
/// Bit-exact with `bt_fixed::intersection_point` (before saturation, which `bt_top` applies
/// once after its PE select):
///
/// | step | network input | writes |
/// |---|---|---|
/// | idle, `load` | - | `a_k ← s_prev_k`, `b_k ← s_next_k` |
/// | idle, `start` | `a_k` | `r_e ← d_prev` |
/// | 1 | `b_k` | `r_l ← d_next` |
/// | 2 | `r_e` | `a_k ← t_prev_k = a_k − round(d_prev·n_k)` |
/// | 3 | `r_l` | from `t_next_k = b_k − round(d_next·n_k)` as computed: `b_k ← L_p0 = δ_k·2^15`, `a_k ← (t_prev+t_next)·2^15 + 2^15` (= `t_prev·2^16 + 2^15 + B_p0`) |
/// | 4 | - | `r_e ← E = (n−m)·2^15`, `r_l ← L = (m+n)·2^15` |
/// | 5 .. 36 | - | one halving step: `r_l ← L/2`, `b_k ← L_p/2`, `E ± L/2`, `a_k ± L_p/2` (sign of `E` decides) |
///
/// `s_sum_k = a_k >> 16 = t_prev_k + round(B_p/2^16)`, valid from [`crate::pe_latency`] cycles
/// after `start` until the next `load`.
///
/// `forms` picks, per normal component, the CSD network or the same product on 18 × 18
/// multipliers ([`crate::rtl::mult::multiplier_network`]); both give the same bits.
pub(crate) fn pe_module(
    index: usize,
    plane_name: &str,
    (plane, forms): (&FixedPlane, [NetworkForm; 3]),
    wd: Widths,
) -> Result<Module, HlsError> {
    debug_assert_eq!(wd.projection, wd.distance);
    let mut items = Vec::new();
    let mut unused = Vec::new();
    let csd: Vec<bt_fixed::Csd> = plane.normal.iter().map(|n| n.csd()).collect();
    items.push(plane_comment((index, plane_name, plane), &csd));
    let link = Link::named(wd);
    link.declare(&mut items);
    let nets = csd_networks(&link, (plane, &csd, forms), wd, (&mut items, &mut unused))?;
    signed_distance(
        DotConstant::Plane(plane),
        &nets,
        (&link.d_new, wd),
        &mut items,
        &mut unused,
    )?;
    projections(&link, &nets, &mut items, &mut unused)?;
    items.push(link.core_instance(wd));
    unused_ok(&mut items, unused);
    Ok(pe_shell(index, plane_name, wd, items))
}

/// Builds [`PE_CORE_MODULE`], the part of a PE that does not depend on its plane (one module
/// per design, instantiated by every `bt_pe_<i>`): the registers, the step-4 set-up, the
/// halving steps of Algorithm 3 and the sequencer of [`pe_module`]'s table. It shows its
/// registers to the front end (`step_sel`, `op_*`) and latches what the front end computes
/// from them (`d_new`, `t_k`).
pub(crate) fn pe_core_module(wd: Widths) -> Module {
    let mut items = Vec::new();
    let mut unused = Vec::new();
    let regs = pe_state(wd, &mut items);
    let link = Link::named(wd);
    link.show(&regs, &mut items);
    let setup = setup_values(&regs, &link.t, &mut items, &mut unused);
    let halving = halving_step(&regs, &mut items, &mut unused);
    pe_outputs(&regs, &mut items);
    sequencer(&regs, &link.d_new, &link.t, &setup, &halving, &mut items);
    unused_ok(&mut items, unused);
    let mut ports = pe_ports(wd);
    ports.extend(link.core_ports());
    Module {
        name: PE_CORE_MODULE.into(),
        header: vec![
            format!("{PE_CORE_MODULE}: the plane-independent part of every IPC processing element, generated by bt-hls."),
            "Operand registers, Algorithm 3 and the step sequencer; the plane's front end (bt_pe_<i>) computes d_new and t_k from the op_* that step_sel selects.".into(),
        ],
        ports,
        items,
    }
}

/// `bt_unused_ok = &{1'b0, unused...}`: reads the bits a module computes but does not use, so
/// that linters see them read (the value is never used).
pub(super) fn unused_ok(items: &mut Vec<Item>, mut unused: Vec<Expr>) {
    unused.insert(0, Expr::lit(1, 0));
    Signal::assigned(
        items,
        "bt_unused_ok",
        1,
        Expr::Unary(UnaryOp::ReduceAnd, Box::new(Expr::concat(unused))),
    );
}

/// The signals between a PE's plane front end and its core: what the core shows of its
/// registers (`step_sel` = the step counter's low two bits; `op_a_k`, `op_b_k`, `op_e`,
/// `op_l` = the low `wd.distance` bits of `a_k`, `b_k`, `r_e`, `r_l`) and what the front end
/// returns (`d_new`, `t_k`, `wd.distance` bits each). The same names on both sides.
pub(super) struct Link {
    step_sel: Signal,
    a: Vec<Signal>,
    b: Vec<Signal>,
    e: Signal,
    l: Signal,
    pub(super) d_new: Signal,
    t: Vec<Signal>,
}

impl Link {
    pub(super) fn named(wd: Widths) -> Link {
        let x = wd.distance;
        let per_axis = |prefix: &str| {
            AXES.iter()
                .map(|axis| Signal::port(format!("{prefix}_{axis}"), x))
                .collect()
        };
        Link {
            step_sel: Signal::port("step_sel", 2),
            a: per_axis("op_a"),
            b: per_axis("op_b"),
            e: Signal::port("op_e", x),
            l: Signal::port("op_l", x),
            d_new: Signal::port("d_new", x),
            t: per_axis("t"),
        }
    }

    /// `x_in_<axis>`, the input of axis `k`'s product network: the core register that
    /// `step_sel` picks (0 = `a_k`, 1 = `b_k`, 2 = `r_e`, 3 = `r_l`).
    pub(super) fn network_input(&self, k: usize, wd: Widths, items: &mut Vec<Item>) -> Signal {
        let (s1, s0) = (self.step_sel.bit(1), self.step_sel.bit(0));
        Signal::assigned(
            items,
            format!("x_in_{}", AXES[k]),
            wd.distance,
            Expr::mux(
                s1,
                Expr::mux(s0.clone(), self.l.e(), self.e.e()),
                Expr::mux(s0, self.b[k].e(), self.a[k].e()),
            ),
        )
    }

    /// The core's outputs, then its inputs.
    fn outputs(&self) -> impl Iterator<Item = &Signal> {
        std::iter::once(&self.step_sel)
            .chain(&self.a)
            .chain(&self.b)
            .chain([&self.e, &self.l])
    }
    fn inputs(&self) -> impl Iterator<Item = &Signal> {
        std::iter::once(&self.d_new).chain(&self.t)
    }

    /// The core's ports of the link.
    fn core_ports(&self) -> Vec<Port> {
        let out = self
            .outputs()
            .map(|s| port(s.name(), Direction::Output, s.width()));
        let inp = self
            .inputs()
            .map(|s| port(s.name(), Direction::Input, s.width()));
        out.chain(inp).collect()
    }

    /// The front end's wires of the link.
    pub(super) fn declare(&self, items: &mut Vec<Item>) {
        for s in self.outputs().chain(self.inputs()) {
            items.push(Item::Wire(s.name().into(), s.width()));
        }
    }

    /// In the core: the registers the front end reads.
    fn show(&self, r: &PeRegs, items: &mut Vec<Item>) {
        items.push(Item::Assign(self.step_sel.e(), r.step.slice(1, 0)));
        for k in 0..AXES.len() {
            items.push(Item::Assign(self.a[k].e(), r.low(&r.a[k])));
            items.push(Item::Assign(self.b[k].e(), r.low(&r.b[k])));
        }
        items.push(Item::Assign(self.e.e(), r.low(&r.r_e)));
        items.push(Item::Assign(self.l.e(), r.low(&r.r_l)));
    }

    /// In the front end: the core instance, every port by name (the PE's own ports, which the
    /// core shares, passed through).
    pub(super) fn core_instance(&self, wd: Widths) -> Item {
        let mut ports: Vec<(String, Expr)> = PePorts::new(wd)
            .each()
            .into_iter()
            .map(|(s, _)| (s.name().to_string(), s.e()))
            .collect();
        ports.extend(
            self.outputs()
                .chain(self.inputs())
                .map(|s| (s.name().to_string(), s.e())),
        );
        Item::Instance {
            module: PE_CORE_MODULE.into(),
            name: "u_core".into(),
            ports,
        }
    }
}

/// The PE's registers (see the step table of [`pe_module`]).
struct PeRegs {
    /// Step counter.
    step: Signal,
    /// Zero distance sum.
    zs: Signal,
    /// `d_prev`, then `E`.
    r_e: Signal,
    /// `d_next`, then `L`.
    r_l: Signal,
    /// Per axis: `s_prev`, `t_prev`, then the `B_p` accumulator.
    a: Vec<Signal>,
    /// Per axis: `s_next`, then `L_p` (`t_next` is never stored: step 3 writes `L_p0`).
    b: Vec<Signal>,
    /// The design's datapath widths.
    wd: Widths,
    /// The ports.
    io: PePorts,
}

/// The plane's header comment of `bt_pe_<index>`.
fn plane_comment(
    (index, plane_name, plane): (usize, &str, &FixedPlane),
    csd: &[bt_fixed::Csd],
) -> Item {
    Item::Comment(format!(
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
    ))
}

/// The core's registers.
fn pe_state(wd: Widths, items: &mut Vec<Item>) -> PeRegs {
    let step = Signal::reg(items, "step", step_bits(wd));
    let zs = Signal::reg(items, "zs", 1);
    let r_e = Signal::reg(items, "r_e", wd.search_diff);
    let r_l = Signal::reg(items, "r_l", wd.half_sum);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for axis in AXES {
        a.push(Signal::reg(items, format!("a_{axis}"), wd.point_acc));
        b.push(Signal::reg(items, format!("b_{axis}"), wd.half_delta));
    }
    PeRegs {
        step,
        zs,
        r_e,
        r_l,
        a,
        b,
        wd,
        io: PePorts::new(wd),
    }
}

/// The last step of the PE's counter (after `wd.iterations` halving steps) and the counter's
/// width.
fn last_step(wd: Widths) -> u32 {
    FIRST_ITERATION_STEP + wd.iterations - 1
}
fn step_bits(wd: Widths) -> u32 {
    64 - u64::from(last_step(wd)).leading_zeros()
}

impl PeRegs {
    /// The low `wd.distance` bits of a register (the network input: the coordinate `s`
    /// sign-extended, or `d` or `t`).
    fn low(&self, s: &Signal) -> Expr {
        s.slice(self.wd.distance - 1, 0)
    }
}

/// One shared CSD network: `net = x_in · n_k / 2^base`.
pub(super) struct Network {
    /// The lowest digit shift (the network's exact low bits are all zero below it).
    pub(super) base: u32,
    /// `net_<axis>`, `DOT_ACC − base` bits.
    pub(super) net: Signal,
}

/// Shared networks, one per non-zero normal component: input selected by step[1:0] (0 = a,
/// 1 = b, 2 = r_e, 3 = r_l); each a CSD network or multipliers, as `forms` says.
fn csd_networks(
    r: &Link,
    (plane, csd, forms): (&FixedPlane, &[bt_fixed::Csd], [NetworkForm; 3]),
    wd: Widths,
    (items, unused): (&mut Vec<Item>, &mut Vec<Expr>),
) -> Result<Vec<Option<Network>>, HlsError> {
    let kind = if forms.contains(&NetworkForm::Multipliers) {
        "network (CSD or 18 x 18 multipliers)"
    } else {
        "CSD network"
    };
    items.push(Item::Comment(format!(
        "one {kind} per non-zero normal component, shared by d_prev, d_next, t_prev, t_next"
    )));
    let mut nets = Vec::new();
    for (k, axis) in AXES.iter().enumerate() {
        let Some(bk) = csd[k].digits.iter().map(|d| d.shift).min() else {
            nets.push(None);
            continue;
        };
        let xin = r.network_input(k, wd, items);
        let nw = wd.dot_acc - bk;
        let sum = match forms[k] {
            NetworkForm::Csd => {
                items.push(Item::Comment(format!(
                    "net_{axis} = x_in_{axis} * n_{axis} / 2^{bk} ({} digits)",
                    csd[k].digits.len()
                )));
                csd_sum(xin.name(), wd.distance, &csd[k], bk, nw)?
            }
            NetworkForm::Multipliers => {
                items.push(Item::Comment(format!(
                    "net_{axis} = x_in_{axis} * n_{axis} / 2^{bk} on 18 x 18 multipliers (pp_{axis}_<bit of x>_<bit of n / 2^{bk}>; {} CSD digits)",
                    csd[k].digits.len()
                )));
                multiplier_network(axis, &xin, plane.normal[k].0, nw, items, unused)?
            }
        };
        let net = Signal::assigned(items, format!("net_{axis}"), nw, sum);
        nets.push(Some(Network { base: bk, net }));
    }
    Ok(nets)
}

/// The constant term of a PE's dot product, `2^29 − offset·2^30`.
#[derive(Clone, Copy)]
pub(super) enum DotConstant<'a> {
    /// The plane's offset, baked in.
    Plane(&'a FixedPlane),
    /// A register holding `−offset` (fine LSB, two's complement), loaded with the job's plane;
    /// the networks' products must be whole (base 0).
    NegatedOffset(&'a Signal),
}

impl DotConstant<'_> {
    /// The term in `dw` bits above bit `sd` of the product.
    fn expr(self, sd: u32, dw: u32) -> Result<Expr, HlsError> {
        let nf = NORMAL_FRAC;
        match self {
            DotConstant::Plane(plane) => {
                let dot_const = (1i128 << (nf - 1)) - (i128::from(plane.offset.0) << nf);
                Ok(Expr::lit_signed(dw, dot_const >> sd))
            }
            DotConstant::NegatedOffset(neg) => {
                let high = dw.checked_sub(nf).filter(|&h| sd == 0 && h >= neg.width());
                let high = high.ok_or_else(|| {
                    HlsError::TooLarge(format!(
                        "offset register of {} bits does not fit a {dw}-bit dot product",
                        neg.width()
                    ))
                })?;
                Ok(Expr::concat(vec![
                    sext(neg.name(), neg.width(), high),
                    Expr::lit(nf, 1 << (nf - 1)),
                ]))
            }
        }
    }
}

/// Signed distance: round_half_up((Σ n_k x_k − offset·2^30) / 2^30), exact below bit `sd`,
/// assigned to `d_new`.
pub(super) fn signed_distance(
    constant: DotConstant<'_>,
    nets: &[Option<Network>],
    (d_new, wd): (&Signal, Widths),
    items: &mut Vec<Item>,
    unused: &mut Vec<Expr>,
) -> Result<(), HlsError> {
    let accw = wd.dot_acc;
    let nf = NORMAL_FRAC;
    let sd = nets
        .iter()
        .flatten()
        .map(|n| n.base)
        .min()
        .unwrap_or(nf)
        .min(nf);
    let dw = accw - sd;
    let mut dot = constant.expr(sd, dw)?;
    for n in nets.iter().flatten() {
        dot = dot.plus(shifted_term(n.net.name(), accw - n.base, n.base - sd, dw)?);
    }
    items.push(Item::Comment(format!(
        "dot = (n . x_in - offset * 2^30 + 2^29) / 2^{sd}; d = dot >> {}",
        nf - sd
    )));
    let dot = Signal::assigned(items, "dot", dw, dot);
    if nf > sd {
        unused.push(dot.slice(nf - sd - 1, 0));
    }
    debug_assert_eq!(d_new.width(), dw - (nf - sd));
    items.push(Item::Assign(d_new.e(), dot.slice(dw - 1, nf - sd)));
    Ok(())
}

/// Projections: t_k = base_k − round_half_up(d · n_k / 2^30), base = a (step 2) or b (step 3),
/// assigned to the link's `t_k`.
pub(super) fn projections(
    r: &Link,
    nets: &[Option<Network>],
    items: &mut Vec<Item>,
    unused: &mut Vec<Expr>,
) -> Result<(), HlsError> {
    let nf = NORMAL_FRAC;
    let s0 = r.step_sel.bit(0);
    for (k, axis) in AXES.iter().enumerate() {
        let pbase = Expr::mux(s0.clone(), r.b[k].e(), r.a[k].e());
        let t = &r.t[k];
        let Some(Network { base: bk, net }) = &nets[k] else {
            items.push(Item::Assign(t.e(), pbase));
            continue;
        };
        let (bk, nw) = (*bk, net.width());
        let p = if bk >= nf {
            // Multiple of 2^30: the rounding half cannot carry.
            if bk > nf {
                return Err(HlsError::TooLarge(format!(
                    "normal component {axis} has a digit above 2^30"
                )));
            }
            net.e()
        } else {
            let pr = Signal::assigned(
                items,
                format!("p_round_{axis}"),
                nw,
                net.e().plus(Expr::lit(nw, 1u128 << (nf - 1 - bk))),
            );
            unused.push(pr.slice(nf - bk - 1, 0));
            pr.slice(nw - 1, nf - bk)
        };
        items.push(Item::Assign(t.e(), pbase.minus(p)));
    }
    Ok(())
}

/// The set-up values: `m + n` and `n − m` (step 4), per axis `δ` and `t_prev + t_next + 1`
/// (step 3, from `t_next` as the front end computes it, so that `b_k` never holds it).
struct SetupValues {
    dist_sum: Signal,
    dist_diff: Signal,
    delta: Vec<Signal>,
    tsum: Vec<Signal>,
}

/// Steps 3 and 4: m, n, delta, and the Algorithm 3 initial values; `t` is the front end's
/// `t_next` at step 3.
fn setup_values(
    r: &PeRegs,
    t: &[Signal],
    items: &mut Vec<Item>,
    unused: &mut Vec<Expr>,
) -> SetupValues {
    let wd = r.wd;
    let (deltaw, sumw) = (wd.delta, wd.distance_sum);
    let abs = |items: &mut Vec<Item>, name: &str, reg: &Signal| {
        Signal::assigned(
            items,
            name,
            wd.distance,
            Expr::mux(
                reg.bit(wd.distance - 1),
                r.low(reg).inv().plus(Expr::lit(wd.distance, 1)),
                r.low(reg),
            ),
        )
    };
    let m = abs(items, "m_dist", &r.r_e);
    let n = abs(items, "n_dist", &r.r_l);
    debug_assert_eq!(sumw, wd.distance);
    let dist_sum = Signal::assigned(items, "dist_sum", sumw, m.e().plus(n.e()));
    let dist_diff = Signal::assigned(
        items,
        "dist_diff",
        sumw + 1,
        Expr::concat(vec![Expr::lit(1, 0), n.e()])
            .minus(Expr::concat(vec![Expr::lit(1, 0), m.e()])),
    );
    let (mut delta, mut tsum) = (Vec::new(), Vec::new());
    for (k, axis) in AXES.iter().enumerate() {
        let (a, t_next) = (r.a[k].name(), t[k].name());
        delta.push(Signal::assigned(
            items,
            format!("delta_{axis}"),
            deltaw,
            sext(t_next, wd.distance, deltaw).minus(sext_slice(a, wd.distance - 1, 0, deltaw)),
        ));
        // t_prev + t_next + 1 as one adder: {t_next, 1} + {a, 1} = 2·(a + t_next + 1).
        let ts = Signal::assigned(
            items,
            format!("tsum_{axis}"),
            deltaw + 1,
            Expr::concat(vec![sext(t_next, wd.distance, deltaw), Expr::lit(1, 1)]).plus(
                Expr::concat(vec![
                    sext_slice(a, wd.distance - 1, 0, deltaw),
                    Expr::lit(1, 1),
                ]),
            ),
        );
        unused.push(ts.bit(0));
        tsum.push(ts);
    }
    SetupValues {
        dist_sum,
        dist_diff,
        delta,
        tsum,
    }
}

/// The next values of one halving step of Algorithm 3.
struct Halving {
    /// `E ± L/2`.
    e_next: Expr,
    /// Per axis `L_p / 2`.
    lp_half: Vec<Signal>,
    /// Per axis `a ± L_p/2`.
    a_next: Vec<Expr>,
}

/// One halving step (the sign of `E` decides the direction).
fn halving_step(r: &PeRegs, items: &mut Vec<Item>, unused: &mut Vec<Expr>) -> Halving {
    let wd = r.wd;
    let g = GUARD_BITS;
    let (lw, ew, lpw, aw) = (wd.half_sum, wd.search_diff, wd.half_delta, wd.point_acc);
    items.push(Item::Comment(format!(
        "Algorithm 3 on {g} guard bits, {} steps frozen once L = 0; E = B - m*2^{g} replaces B, m and the comparator",
        wd.iterations
    )));
    let go_up = Signal::assigned(items, "go_up", 1, r.r_e.bit(ew - 1));
    let l_half = Expr::concat(vec![Expr::lit(ew - lw + 1, 0), r.r_l.slice(lw - 1, 1)]);
    let e_next = add_sub(
        items,
        unused,
        "e_next",
        r.r_e.e(),
        l_half,
        go_up.e().lnot(),
        ew,
    );
    let (mut lp_half, mut a_next) = (Vec::new(), Vec::new());
    for (k, axis) in AXES.iter().enumerate() {
        let b = &r.b[k];
        let lph = Signal::assigned(
            items,
            format!("lp_half_{axis}"),
            lpw,
            Expr::concat(vec![b.bit(lpw - 1), b.slice(lpw - 1, 1)]),
        );
        a_next.push(add_sub(
            items,
            unused,
            &format!("a_next_{axis}"),
            r.a[k].e(),
            sext(lph.name(), lpw, aw),
            go_up.e().lnot(),
            aw,
        ));
        lp_half.push(lph);
    }
    Halving {
        e_next,
        lp_half,
        a_next,
    }
}

/// Output: the unsaturated point t_prev + round(B_p / 2^G) = a >> G, and the zero flag.
fn pe_outputs(r: &PeRegs, items: &mut Vec<Item>) {
    let wd = r.wd;
    let (g, aw) = (GUARD_BITS, wd.point_acc);
    let mut sum_parts = Vec::new();
    for a in &r.a {
        sum_parts.insert(0, a.slice(aw - 1, g));
    }
    debug_assert_eq!(aw - g, wd.sum_point);
    items.push(Item::Assign(r.io.s_sum.e(), Expr::concat(sum_parts)));
    items.push(Item::Assign(r.io.zero_sum.e(), r.zs.e()));
}

/// `reg <= value;`
fn nb(reg: &Signal, value: Expr) -> Stmt {
    Stmt::NonBlocking(reg.e(), value)
}

/// `step <= value;`
fn goto(r: &PeRegs, value: u32) -> Stmt {
    nb(&r.step, Expr::lit(step_bits(r.wd), value.into()))
}

/// Idle: on `start` latch `d_prev` and go to step 1; on `load` latch the operands.
fn seq_idle(r: &PeRegs, d_new: &Signal) -> Vec<Stmt> {
    let wd = r.wd;
    let (cw, aw, lpw) = (wd.coord, wd.point_acc, wd.half_delta);
    let mut load = Vec::new();
    for k in 0..AXES.len() {
        let (hi, lo) = (cw * (k as u32 + 1) - 1, cw * k as u32);
        load.push(nb(&r.a[k], sext_slice(r.io.s_prev.name(), hi, lo, aw)));
        load.push(nb(&r.b[k], sext_slice(r.io.s_next.name(), hi, lo, lpw)));
    }
    vec![Stmt::If(
        r.io.start.e(),
        vec![
            nb(&r.r_e, sext(d_new.name(), wd.distance, wd.search_diff)),
            goto(r, 1),
        ],
        vec![Stmt::If(r.io.load.e(), load, vec![])],
    )]
}

/// Step 3: per axis the Algorithm 3 initial values from `t_prev` (in `a_k`) and the front
/// end's `t_next`, written straight into `b_k` and `a_k` (the `t_next` register of before
/// and its multiplexer input are gone).
fn seq_setup_axes(r: &PeRegs, s: &SetupValues) -> Vec<Stmt> {
    let wd = r.wd;
    let g = GUARD_BITS;
    let (deltaw, aw) = (wd.delta, wd.point_acc);
    debug_assert_eq!(wd.half_delta, deltaw + g - 1);
    let mut setup = Vec::new();
    for k in 0..AXES.len() {
        setup.push(nb(
            &r.b[k],
            Expr::concat(vec![s.delta[k].e(), Expr::lit(1, 0).repeat(g - 1)]),
        ));
        // t_prev·2^G + 2^(G−1) + B_p0 = (t_prev + t_next + 1)·2^(G−1), modulo 2^POINT_ACC.
        setup.push(nb(
            &r.a[k],
            Expr::concat(vec![
                s.tsum[k].bit(deltaw).repeat(aw - deltaw - (g - 1)),
                s.tsum[k].slice(deltaw, 1),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ));
    }
    debug_assert!(aw >= deltaw + g);
    setup.push(goto(r, 4));
    setup
}

/// Step 4: the scalar Algorithm 3 initial values (`E`, `L`, the zero flag).
fn seq_setup(r: &PeRegs, s: &SetupValues) -> Vec<Stmt> {
    let wd = r.wd;
    let g = GUARD_BITS;
    let (sumw, ew) = (wd.distance_sum, wd.search_diff);
    let mut setup = vec![
        nb(
            &r.r_e,
            Expr::concat(vec![
                s.dist_diff.bit(sumw).repeat(ew - (sumw + 1) - (g - 1)),
                s.dist_diff.e(),
                Expr::lit(1, 0).repeat(g - 1),
            ]),
        ),
        nb(
            &r.r_l,
            Expr::concat(vec![s.dist_sum.e(), Expr::lit(1, 0).repeat(g - 1)]),
        ),
        nb(&r.zs, s.dist_sum.e().eq(Expr::lit(sumw, 0))),
    ];
    debug_assert_eq!(wd.half_sum, sumw + g - 1);
    setup.push(goto(r, FIRST_ITERATION_STEP));
    setup
}

/// Steps 5 ..: one halving step while `L ≠ 0`, back to idle after the last.
fn seq_iterate(r: &PeRegs, h: &Halving) -> Vec<Stmt> {
    let wd = r.wd;
    let (lw, stepw) = (wd.half_sum, step_bits(wd));
    let mut iterate = vec![
        nb(
            &r.r_l,
            Expr::concat(vec![Expr::lit(1, 0), r.r_l.slice(lw - 1, 1)]),
        ),
        nb(&r.r_e, h.e_next.clone()),
    ];
    for k in 0..AXES.len() {
        iterate.push(nb(&r.b[k], h.lp_half[k].e()));
        iterate.push(nb(&r.a[k], h.a_next[k].clone()));
    }
    vec![
        Stmt::If(
            Expr::bin(BinaryOp::Ne, r.r_l.e(), Expr::lit(lw, 0)),
            iterate,
            vec![],
        ),
        Stmt::If(
            r.step.e().eq(Expr::lit(stepw, last_step(wd).into())),
            vec![goto(r, 0)],
            vec![nb(&r.step, r.step.e().plus(Expr::lit(stepw, 1)))],
        ),
    ]
}

/// The sequencer: the step counter's `case` over the table of [`pe_module`].
fn sequencer(
    r: &PeRegs,
    d_new: &Signal,
    t: &[Signal],
    s: &SetupValues,
    h: &Halving,
    items: &mut Vec<Item>,
) {
    let wd = r.wd;
    let (stepw, xw) = (step_bits(wd), wd.distance);
    let aw = wd.point_acc;
    let mut proj_prev: Vec<Stmt> = (0..AXES.len())
        .map(|k| nb(&r.a[k], sext(t[k].name(), xw, aw)))
        .collect();
    proj_prev.push(goto(r, 3));
    items.push(Item::AlwaysFf(vec![Stmt::If(
        r.io.rst_n.e().lnot(),
        vec![goto(r, 0)],
        vec![Stmt::Case(
            r.step.e(),
            vec![
                (Expr::lit(stepw, 0), seq_idle(r, d_new)),
                (
                    Expr::lit(stepw, 1),
                    vec![
                        nb(
                            &r.r_l,
                            Expr::concat(vec![Expr::lit(wd.half_sum - xw, 0), d_new.e()]),
                        ),
                        goto(r, 2),
                    ],
                ),
                (Expr::lit(stepw, 2), proj_prev),
                (Expr::lit(stepw, 3), seq_setup_axes(r, s)),
                (Expr::lit(stepw, 4), seq_setup(r, s)),
            ],
            seq_iterate(r, h),
        )],
    )]));
}

/// The `bt_pe_<index>` module around `items`: header and ports.
fn pe_shell(index: usize, plane_name: &str, wd: Widths, items: Vec<Item>) -> Module {
    let spw = wd.sum_point;
    Module {
        name: pe_module_name(index),
        header: vec![
            format!(
                "bt_pe_{index}: IPC processing element of plane {index} ('{plane_name}'), generated by bt-hls."
            ),
            format!(
                "The plane's constant networks (d = n.x - offset, t_k = x_k - d*n_k) around the shared {PE_CORE_MODULE} (registers, Algorithm 3, sequencer)."
            ),
            format!(
                "`load` latches the operands; `s_sum` valid {} cycles after `start`; twin of bt_fixed::intersection_point before saturation.",
                crate::pe_latency(wd.coord)
            ),
            format!(
                "Operands are {{z, y, x}} of {}-bit words, s_sum {{z, y, x}} of {spw}-bit words, mm x 2^8.",
                wd.coord
            ),
        ],
        ports: pe_ports(wd),
        items,
    }
}

/// The ports of a PE (and the first ones of its core): clock, reset, `load`, `start`, the
/// operands and the result, each declared once.
struct PePorts {
    clk: Signal,
    rst_n: Signal,
    /// Latch the operands.
    load: Signal,
    /// Start the evaluation.
    start: Signal,
    /// The previous and next points `{z, y, x}`.
    s_prev: Signal,
    s_next: Signal,
    /// The unsaturated result `{z, y, x}`.
    s_sum: Signal,
    /// Zero distance sum.
    zero_sum: Signal,
}

impl PePorts {
    fn new(wd: Widths) -> PePorts {
        PePorts {
            clk: Signal::port("clk", 1),
            rst_n: Signal::port("rst_n", 1),
            load: Signal::port("load", 1),
            start: Signal::port("start", 1),
            s_prev: Signal::port("s_prev", point_bits(wd)),
            s_next: Signal::port("s_next", point_bits(wd)),
            s_sum: Signal::port("s_sum", sum_bits(wd)),
            zero_sum: Signal::port("zero_sum", 1),
        }
    }

    /// The ports in order, with their directions.
    fn each(&self) -> [(&Signal, Direction); 8] {
        use Direction::{Input, Output};
        [
            (&self.clk, Input),
            (&self.rst_n, Input),
            (&self.load, Input),
            (&self.start, Input),
            (&self.s_prev, Input),
            (&self.s_next, Input),
            (&self.s_sum, Output),
            (&self.zero_sum, Output),
        ]
    }
}

/// The port list of a PE (and the first ports of its core).
pub(super) fn pe_ports(wd: Widths) -> Vec<Port> {
    PePorts::new(wd)
        .each()
        .into_iter()
        .map(|(s, dir)| port(s.name(), dir, s.width()))
        .collect()
}

/// `name[hi:lo]` sign-extended to `total` bits.
pub(crate) fn sext_slice(name: &str, hi: u32, lo: u32, total: u32) -> Expr {
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
