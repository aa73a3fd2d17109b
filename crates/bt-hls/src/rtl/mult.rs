//! A plane's constant products on the Cyclone IV E's 18 × 18 embedded multipliers: the split
//! of a wide product into signed 18 × 18 partial products (`bt_mul_map.v` maps each onto one
//! multiplier block), and the per-network choice between multipliers and the CSD shift-add
//! network while the device's blocks last.

use std::collections::BTreeMap;

use bt_fixed::{FixedPlane, Widths};

use crate::HlsError;
use crate::rtl::verilog::{Expr, Item, Signal};

/// 18 × 18 multipliers of the EP4CE115 (the paper's Cyclone IV E; 532 as 9 × 9 halves).
pub const EP4CE115_MULTIPLIERS: u32 = 266;

/// Operand width of one embedded multiplier, bits (signed).
const BLOCK_BITS: u32 = 18;

/// How a PE builds the product of one normal component (`net_<axis>` of `bt_pe_<i>`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NetworkForm {
    /// Shift-add network of the component's CSD digits (no multiplier).
    Csd,
    /// Signed 18 × 18 partial products of the input and the constant, summed.
    Multipliers,
}

/// One piece of a two's-complement word split for 18 × 18 signed multipliers: the low pieces
/// are 17 unsigned bits (zero-extended to 18), the top piece keeps the sign (≤ 18 bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Piece {
    /// Lowest bit of the piece in the word.
    lo: u32,
    /// Bits of the word in the piece.
    width: u32,
    /// The top piece (signed); the others are unsigned.
    top: bool,
}

impl Piece {
    /// Width of the multiplier operand (an unsigned piece gains a zero sign bit).
    fn operand_width(self) -> u32 {
        if self.top { self.width } else { self.width + 1 }
    }
}

/// The pieces of a `width`-bit two's-complement word, lowest first.
fn pieces(width: u32) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut lo = 0;
    while width - lo > BLOCK_BITS {
        out.push(Piece {
            lo,
            width: BLOCK_BITS - 1,
            top: false,
        });
        lo += BLOCK_BITS - 1;
    }
    out.push(Piece {
        lo,
        width: width - lo,
        top: true,
    });
    out
}

/// Bits of `c` as a two's-complement word (≥ 1).
fn signed_width(c: i64) -> u32 {
    65 - (c ^ (c >> 63)).leading_zeros()
}

/// The odd constant of a normal component's product and its shift: `n_k = c · 2^base`.
/// `None` for a zero component.
fn odd_constant(n: i32) -> Option<(i64, u32)> {
    (n != 0).then(|| {
        let base = n.trailing_zeros();
        (i64::from(n) >> base, base)
    })
}

/// One partial product, placed at `shift` in the network's result.
struct Term {
    shift: u32,
    product: Signal,
    /// Bits below which a non-negative product lies (both pieces unsigned); `None`: signed.
    magnitude: Option<u32>,
}

/// The partial products of `x · c` (`x` of `x_width` bits, `c` a `c_width`-bit coefficient)
/// whose shift lies below `total` bits, lowest shift first.
fn partial_products(x: (&str, u32), c_width: u32, total: u32) -> Vec<(Piece, Piece, u32)> {
    let mut out = Vec::new();
    for px in pieces(x.1) {
        for pc in pieces(c_width) {
            let shift = px.lo + pc.lo;
            if shift < total {
                out.push((px, pc, shift));
            }
        }
    }
    out.sort_by_key(|&(px, pc, shift)| (shift, px.lo, pc.lo));
    out
}

/// The groups of partial products that can be concatenated instead of added: a term joins a
/// group whose last term is non-negative and ends at or below the term's shift. Returns the
/// groups of indices into `terms` (given lowest shift first).
fn groups(terms: &[(u32, Option<u32>)]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (i, &(shift, _)) in terms.iter().enumerate() {
        let fits = out.iter().position(|g| {
            g.last().is_some_and(|&j| {
                let (s, magnitude) = terms[j];
                magnitude.is_some_and(|m| s + m <= shift)
            })
        });
        match fits {
            Some(g) => out[g].push(i),
            None => out.push(vec![i]),
        }
    }
    out
}

/// Multiplier blocks and adders of the product of `n` on a `x_width`-bit input into `total`
/// bits above its base (the network of [`multiplier_network`]). `None` for a zero component.
fn multiplier_cost(n: i32, x_width: u32, dot_acc: u32) -> Option<(u32, u32)> {
    let (c, base) = odd_constant(n)?;
    let total = dot_acc.checked_sub(base)?;
    let products = partial_products(("", x_width), signed_width(c), total);
    let terms: Vec<(u32, Option<u32>)> = products
        .iter()
        .map(|&(px, pc, s)| (s, (!px.top && !pc.top).then_some(px.width + pc.width)))
        .collect();
    let adders = groups(&terms).len().saturating_sub(1) as u32;
    Some((products.len() as u32, adders))
}

/// The second operand of a product network: a plane's odd constant, or a coefficient
/// register (a generic PE's normal component, two's complement).
#[derive(Clone, Copy)]
pub(crate) enum Coefficient<'a> {
    /// The odd constant `c` of `n_k = c · 2^base`.
    Constant(i64),
    /// A register loaded with the job's plane.
    Register(&'a Signal),
}

impl Coefficient<'_> {
    /// Bits of the coefficient as a two's-complement word.
    fn width(self) -> u32 {
        match self {
            Coefficient::Constant(c) => signed_width(c),
            Coefficient::Register(s) => s.width(),
        }
    }

    /// Piece `pc` as a multiplier operand (an unsigned piece with a zero sign bit).
    fn piece(self, pc: Piece) -> Expr {
        match self {
            Coefficient::Constant(c) => {
                let cv = c >> pc.lo;
                let cv = if pc.top {
                    cv
                } else {
                    cv & ((1 << pc.width) - 1)
                };
                Expr::lit_signed(pc.operand_width(), i128::from(cv))
            }
            Coefficient::Register(s) => piece_of(s, pc),
        }
    }
}

/// Piece `p` of the word `x` as a signed multiplier operand.
fn piece_of(x: &Signal, p: Piece) -> Expr {
    if p.top {
        x.slice(x.width() - 1, p.lo)
    } else {
        Expr::concat(vec![Expr::lit(1, 0), x.slice(p.lo + p.width - 1, p.lo)])
    }
}

/// Multiplier blocks of the product of an `x_width`-bit input and a `c_width`-bit coefficient
/// register into `total` bits ([`product_network`] with [`Coefficient::Register`]).
pub(crate) fn register_product_blocks(x_width: u32, c_width: u32, total: u32) -> u32 {
    partial_products(("", x_width), c_width, total).len() as u32
}

/// `net = x · c mod 2^total` (the product `x · n_k / 2^base` of a CSD network, exactly) from
/// signed 18 × 18 partial products of `x`'s pieces and `c`'s (see [`product_network`]).
pub(crate) fn multiplier_network(
    axis: &str,
    x: &Signal,
    n: i32,
    total: u32,
    items: &mut Vec<Item>,
    unused: &mut Vec<Expr>,
) -> Result<Expr, HlsError> {
    let (c, _) = odd_constant(n)
        .ok_or_else(|| HlsError::TooLarge(format!("normal component {axis} is zero")))?;
    product_network(axis, x, Coefficient::Constant(c), total, (items, unused))
}

/// `net = x · c mod 2^total` from signed 18 × 18 partial products of `x`'s pieces and `c`'s:
/// the non-negative low products and the products above them are concatenated, the rest
/// added. Declares the products as `pp_<axis>_<i>_<j>` (i, j: the pieces of x and c) and
/// returns the sum in `total` bits.
pub(crate) fn product_network(
    axis: &str,
    x: &Signal,
    c: Coefficient<'_>,
    total: u32,
    (items, unused): (&mut Vec<Item>, &mut Vec<Expr>),
) -> Result<Expr, HlsError> {
    let mut terms = Vec::new();
    for (px, pc, shift) in partial_products((x.name(), x.width()), c.width(), total) {
        let product = Signal::signed_product(
            items,
            format!("pp_{axis}_{}_{}", px.lo, pc.lo),
            (piece_of(x, px), px.operand_width()),
            (c.piece(pc), pc.operand_width()),
        );
        let magnitude = (!px.top && !pc.top).then_some(px.width + pc.width);
        terms.push(Term {
            shift,
            product,
            magnitude,
        });
    }
    let keys: Vec<(u32, Option<u32>)> = terms.iter().map(|t| (t.shift, t.magnitude)).collect();
    let mut sum: Option<Expr> = None;
    for group in groups(&keys) {
        let g: Vec<&Term> = group.iter().map(|&i| &terms[i]).collect();
        let e = placed(&g, total, unused);
        sum = Some(match sum {
            None => e,
            Some(s) => s.plus(e),
        });
    }
    sum.ok_or_else(|| HlsError::TooLarge(format!("network {axis} has no product")))
}

/// One group of terms as a `total`-bit word: each term but the last its magnitude bits at its
/// shift, zeros between, the last sign-extended (or cut) to the top.
fn placed(group: &[&Term], total: u32, unused: &mut Vec<Expr>) -> Expr {
    let mut low_to_high = Vec::new();
    let mut at = 0;
    for (i, t) in group.iter().enumerate() {
        if t.shift > at {
            low_to_high.push(Expr::lit(1, 0).repeat(t.shift - at));
        }
        let w = t.product.width();
        let last = i + 1 == group.len();
        let keep = match (last, t.magnitude) {
            (false, Some(m)) => m,
            _ => w.min(total - t.shift),
        };
        if keep < w {
            unused.push(t.product.slice(w - 1, keep));
        }
        low_to_high.push(t.product.slice(keep - 1, 0));
        at = t.shift + keep;
        if last && at < total {
            low_to_high.push(t.product.bit(w - 1).repeat(total - at));
        }
    }
    low_to_high.reverse();
    Expr::concat(low_to_high)
}

/// Multiplier blocks the choice of [`network_forms`] uses.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub(crate) struct MultiplierPlan {
    /// Per plane with a PE: the form of each normal component's network (x, y, z).
    pub forms: BTreeMap<u32, [NetworkForm; 3]>,
    /// 18 × 18 multiplier blocks of the whole design (every PE instance's).
    pub blocks: u32,
}

/// Chooses each network's form: multipliers where they need fewer adders than the CSD
/// network (the most adders saved first, then the plane and axis order), as long as the
/// design's blocks (`instances` of each plane × the network's partial products) stay within
/// `budget`; CSD networks for the rest (an axis-aligned plane's one-digit network always).
/// `planes`: (plane index, its PE instances, the plane).
pub(crate) fn network_forms(
    planes: &[(u32, u32, &FixedPlane)],
    wd: Widths,
    budget: u32,
) -> MultiplierPlan {
    let mut plan = MultiplierPlan::default();
    let mut candidates = Vec::new();
    for &(p, instances, plane) in planes {
        plan.forms.insert(p, [NetworkForm::Csd; 3]);
        for (k, n) in plane.normal.iter().enumerate() {
            let digits = n.csd().digits.len() as u32;
            let Some((blocks, adders)) = multiplier_cost(n.0, wd.distance, wd.dot_acc) else {
                continue;
            };
            let csd_adders = digits.saturating_sub(1);
            if adders < csd_adders {
                candidates.push((csd_adders - adders, p, k, blocks * instances));
            }
        }
    }
    candidates.sort_by_key(|&(saved, p, k, _)| (std::cmp::Reverse(saved), p, k));
    for (_, p, k, blocks) in candidates {
        if plan.blocks + blocks <= budget {
            plan.blocks += blocks;
            if let Some(f) = plan.forms.get_mut(&p) {
                f[k] = NetworkForm::Multipliers;
            }
        }
    }
    plan
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_split_into_unsigned_low_pieces_and_a_signed_top() {
        let p = |w| -> Vec<(u32, u32, bool)> {
            pieces(w).iter().map(|p| (p.lo, p.width, p.top)).collect()
        };
        assert_eq!(p(18), [(0, 18, true)]);
        assert_eq!(p(26), [(0, 17, false), (17, 9, true)]);
        assert_eq!(p(32), [(0, 17, false), (17, 15, true)]);
        assert_eq!(p(40), [(0, 17, false), (17, 17, false), (34, 6, true)]);
        assert_eq!(
            [signed_width(1), signed_width(-1), signed_width(-2)],
            [2, 1, 2]
        );
        assert_eq!(signed_width(i64::from(i32::MIN)), 32);
    }

    /// The pieces and groups reproduce `x · c mod 2^total` for corners of x (one, two and
    /// three pieces) and c.
    #[test]
    fn partial_products_and_groups_sum_to_the_product() {
        let total = 50u32;
        let mask = (1i128 << total) - 1;
        for c in [
            1i64,
            -1,
            3,
            -3,
            0x1_ffff,
            -0x2_0001,
            0x3fff_ffff >> 1,
            -(1 << 29) - 1,
        ] {
            for (w, x) in [18u32, 26, 42].into_iter().flat_map(|w| {
                let top = 1i128 << (w - 1);
                [0i128, 1, -1, top - 1, -top, 0x1_2345, -0x1_4321].map(|x| (w, x))
            }) {
                let products = partial_products(("x", w), signed_width(c), total);
                let terms: Vec<(u32, Option<u32>)> = products
                    .iter()
                    .map(|&(px, pc, s)| (s, (!px.top && !pc.top).then_some(px.width + pc.width)))
                    .collect();
                let value = |piece: Piece, v: i128| -> i128 {
                    let part = v >> piece.lo;
                    if piece.top {
                        part
                    } else {
                        part & ((1 << piece.width) - 1)
                    }
                };
                let mut sum = 0i128;
                for g in groups(&terms) {
                    for (i, &t) in g.iter().enumerate() {
                        let (px, pc, s) = products[t];
                        let p = value(px, x) * value(pc, i128::from(c));
                        if i + 1 < g.len() {
                            assert!(p >= 0 && p < 1 << terms[t].1.unwrap(), "{x} {c}");
                        }
                        sum += p << s;
                    }
                }
                assert_eq!(sum & mask, (x * i128::from(c)) & mask, "{x} * {c}");
            }
        }
    }

    #[test]
    fn a_full_width_coefficient_takes_four_blocks_and_two_adders() {
        // 26-bit input, 32-bit odd coefficient: {hh, ll} concatenated, + lh + hl.
        assert_eq!(multiplier_cost(0x2bcd_ef01, 26, 55), Some((4, 2)));
        // An 18-bit coefficient: two blocks, one adder.
        assert_eq!(multiplier_cost(0x1_2345 << 8, 26, 55), Some((2, 1)));
        assert_eq!(multiplier_cost(0, 26, 55), None);
    }
}
