//! The plane table of `bt_top` on generic PEs: each plane's coefficients, written by the host
//! per step, read at a job's load and latched by the PE it loads.

use super::*;

/// Plane table (M9K, one memory per bus word of an entry: the normal's x, y, z in Q2.30, then
/// −offset in fine LSB, low word first), written over the bus at `plane_base + 8·plane + word`
/// and read at the loaded job's plane, one cycle after the address like the point memory, so
/// its words reach the PEs with the operands. Returns the PE's coefficient inputs (`c_n_x`,
/// `c_n_y`, `c_n_z`, `c_off`) as expressions; none on plane PEs.
pub(super) fn plane_table(
    t: &Dims<'_>,
    bus: &Decode,
    lrom: &LoadRead,
    items: &mut Vec<Item>,
) -> Option<Vec<Expr>> {
    let (Some(is_plane), Some(plane)) = (&bus.is_plane, &lrom.plane) else {
        return None;
    };
    let widths = crate::input::plane_table_words(t.wd, true);
    items.push(Item::Comment(format!(
        "plane table, written per step by the host: plane -> {{normal x, y, z (Q2.30), -offset (fine LSB, {} words)}}",
        widths.len() - 3
    )));
    let depth = 1u32 << t.plb;
    let mut q = Vec::new();
    for (w, &width) in widths.iter().enumerate() {
        let mem = Signal::memory(items, format!("ptab_{w}"), width, depth);
        let reg = Signal::reg(items, format!("ptab_q_{w}"), width);
        let here = t.io.avs_address.slice(2, 0).eq(lit(3, w as u128));
        items.push(Item::AlwaysFf(vec![
            Stmt::If(
                bus.host_wr.e().and(is_plane.e()).and(here),
                vec![nb(
                    mem.at(t.io.avs_address.slice(t.plb + 2, 3)),
                    t.io.avs_writedata.slice(width - 1, 0),
                )],
                vec![],
            ),
            nb(reg.e(), mem.at(plane.e())),
        ]));
        q.push(reg);
    }
    let mut out: Vec<Expr> = q[..3].iter().map(Signal::e).collect();
    out.push(Expr::concat(q[3..].iter().rev().map(Signal::e).collect()));
    Some(out)
}
