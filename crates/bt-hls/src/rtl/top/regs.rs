//! Every port, register and memory of `bt_top`, declared once as a typed [`Signal`]: the
//! blocks read and write these handles, so no block spells a signal's name and a misspelt
//! name is a compile error, not a new wire.

use super::*;

/// The Avalon-MM ports of `bt_top`, in port-list order.
pub(super) struct Ports {
    pub(super) clk: Signal,
    pub(super) rst_n: Signal,
    pub(super) avs_address: Signal,
    pub(super) avs_read: Signal,
    pub(super) avs_write: Signal,
    pub(super) avs_writedata: Signal,
    pub(super) avs_readdata: Signal,
    pub(super) avs_readdatavalid: Signal,
    pub(super) ins_irq: Signal,
}

impl Ports {
    /// The ports with a word address of `ab` bits.
    pub(super) fn new(ab: u32) -> Ports {
        Ports {
            clk: Signal::port("clk", 1),
            rst_n: Signal::port("rst_n", 1),
            avs_address: Signal::port("avs_address", ab),
            avs_read: Signal::port("avs_read", 1),
            avs_write: Signal::port("avs_write", 1),
            avs_writedata: Signal::port("avs_writedata", 32),
            avs_readdata: Signal::port("avs_readdata", 32),
            avs_readdatavalid: Signal::port("avs_readdatavalid", 1),
            ins_irq: Signal::port("ins_irq", 1),
        }
    }

    /// The module's port list.
    pub(super) fn list(&self) -> Vec<crate::rtl::verilog::Port> {
        use Direction::{Input, Output, OutputReg};
        [
            (&self.clk, Input),
            (&self.rst_n, Input),
            (&self.avs_address, Input),
            (&self.avs_read, Input),
            (&self.avs_write, Input),
            (&self.avs_writedata, Input),
            (&self.avs_readdata, OutputReg),
            (&self.avs_readdatavalid, OutputReg),
            (&self.ins_irq, Output),
        ]
        .into_iter()
        .map(|(s, dir)| port(s.name(), dir, s.width()))
        .collect()
    }
}

/// The sizes the registers are declared with.
pub(super) struct RegSizes {
    pub(super) pb: u32,
    pub(super) ptb: u32,
    pub(super) ib: u32,
    pub(super) eb: u32,
    /// Bits of a job's plane field (generic PEs; 0 otherwise).
    pub(super) plb: u32,
    pub(super) np2: u32,
    pub(super) cnt_bits: u32,
    pub(super) wd: bt_fixed::Widths,
    pub(super) early: bool,
}

impl RegSizes {
    /// Bits of the written job's plane that early stopping's box needs (generic PEs with
    /// early stopping), or none.
    fn box_plane_bits(&self) -> Option<u32> {
        (self.early && self.plb > 0).then_some(self.plb)
    }
}

/// The registers and memories of `bt_top` (field = Verilog name).
pub(super) struct Regs {
    /// Main FSM state and its step counter.
    pub(super) state: Signal,
    pub(super) cnt: Signal,
    /// PATHS and ROUND_CAP.
    pub(super) paths_r: Signal,
    pub(super) cap_r: Signal,
    /// The slot-buffer half of the front slot (loading or computing), and each half's
    /// length, load delay and PE columns.
    pub(super) rsel: Signal,
    pub(super) slen_0: Signal,
    pub(super) slen_1: Signal,
    pub(super) dly_0: Signal,
    pub(super) dly_1: Signal,
    pub(super) sused_0: Signal,
    pub(super) sused_1: Signal,
    /// The write-back engine: running, its step counter and its slot-buffer half.
    pub(super) wb_on: Signal,
    pub(super) wcnt: Signal,
    pub(super) wsel: Signal,
    /// Cycles the front slot's load still waits for the write-back it overlaps.
    pub(super) ldly: Signal,
    /// CYCLES and done.
    pub(super) cycles: Signal,
    pub(super) done: Signal,
    /// Transmitter and receiver, mm words.
    pub(super) tx_x: Signal,
    pub(super) tx_y: Signal,
    pub(super) tx_z: Signal,
    pub(super) rx_x: Signal,
    pub(super) rx_y: Signal,
    pub(super) rx_z: Signal,
    /// A host point's staged integer words.
    pub(super) st_x: Signal,
    pub(super) st_y: Signal,
    pub(super) st_z: Signal,
    /// Per-path flags: committed bank, converged, degenerate, overflow, and the round's
    /// pending moved / degenerate / overflow flags.
    pub(super) cur: Signal,
    pub(super) conv: Signal,
    pub(super) dz: Signal,
    pub(super) ov: Signal,
    pub(super) pbig: Signal,
    pub(super) pdz: Signal,
    pub(super) pov: Signal,
    /// The point memories' read data (a: previous point or a bus read, b: next point, c: the
    /// written point's old value).
    pub(super) rd_a: Signal,
    pub(super) rd_b: Signal,
    pub(super) rd_c: Signal,
    /// The slot-buffer entries read this cycle for the load (`sched_q`) and the write-back
    /// (`wsched_q`), and their qualifiers.
    pub(super) sched_q: Signal,
    pub(super) sq_ok: Signal,
    pub(super) sq_tail: Signal,
    pub(super) wsched_q: Signal,
    pub(super) wq_ok: Signal,
    pub(super) wq_tail: Signal,
    /// The registered load entry.
    pub(super) ld_q_en: Signal,
    pub(super) ld_q_tail: Signal,
    pub(super) ld_q_first: Signal,
    pub(super) ld_q_last: Signal,
    pub(super) ld_q_inst: Signal,
    /// The PE that loaded last cycle starts.
    pub(super) ld_go: Signal,
    pub(super) ld_go_inst: Signal,
    /// The registered write-back entry.
    pub(super) wbe: WbEntry,
    /// The bus read request in flight.
    pub(super) rq_valid: Signal,
    pub(super) rq_kind: Signal,
    pub(super) rq_reg: Signal,
    pub(super) rq_word: Signal,
    pub(super) rq_path: Signal,
    /// `rounds` read data, and the paths whose `rounds` entry is valid since the start.
    pub(super) rounds_q: Signal,
    pub(super) rvalid: Signal,
    /// The ready queue's pointers, count and head word.
    pub(super) rq_head: Signal,
    pub(super) rq_tail: Signal,
    pub(super) rq_count: Signal,
    pub(super) rq_q: Signal,
    /// The job-memory word the dispatcher reads.
    pub(super) job_q: Signal,
    /// The dispatcher's state and registers.
    pub(super) dstate: Signal,
    pub(super) d: DispatchRegs,
    /// Memories: the ready queue, the slot buffer and each slot's position per PE column.
    pub(super) rq: Signal,
    pub(super) sbuf: Signal,
    pub(super) spos: Signal,
    /// The high bits of wide job-memory entries (entries over 32 bits only).
    pub(super) sched_hi: Option<Signal>,
    /// Early stopping: left its box, and the round's pending flag.
    pub(super) lb: Option<Signal>,
    pub(super) plb: Option<Signal>,
    /// Memories: per-path rounds and the three point-memory copies.
    pub(super) rounds: Signal,
    pub(super) pm_a: Signal,
    pub(super) pm_b: Signal,
    pub(super) pm_c: Signal,
}

/// The registered write-back entry: valid, the slot's tail, the round's end, path, point, PE
/// column, the group's tail, the job's entry and its path's first group.
pub(super) struct WbEntry {
    pub(super) wb_q_en: Signal,
    pub(super) wb_q_tail: Signal,
    pub(super) wb_q_end: Signal,
    pub(super) wb_q_path: Signal,
    pub(super) wb_q_point: Signal,
    pub(super) wb_q_inst: Signal,
    pub(super) wb_q_gtail: Signal,
    pub(super) wb_q_src: Signal,
    pub(super) wb_q_gbase: Signal,
    /// The job's plane, for early stopping's box on generic PEs (none otherwise).
    pub(super) wb_q_plane: Option<Signal>,
}

impl WbEntry {
    /// Declares them in order with `r` (path, point, instance and entry bits).
    fn declare(
        r: &mut impl FnMut(&str, u32) -> Signal,
        (pb, ptb, ib, eb): (u32, u32, u32, u32),
        plane_bits: Option<u32>,
    ) -> Self {
        WbEntry {
            wb_q_en: r("wb_q_en", 1),
            wb_q_tail: r("wb_q_tail", 1),
            wb_q_end: r("wb_q_end", 1),
            wb_q_path: r("wb_q_path", pb),
            wb_q_point: r("wb_q_point", ptb),
            wb_q_inst: r("wb_q_inst", ib),
            wb_q_gtail: r("wb_q_gtail", 1),
            wb_q_src: r("wb_q_src", eb),
            wb_q_gbase: r("wb_q_gbase", eb),
            wb_q_plane: plane_bits.map(|w| r("wb_q_plane", w)),
        }
    }
}

/// The dispatcher's registers: scan budget, used / saved columns, slot length, job index,
/// conflict, the examined group's first group and entry, the slot's load delay (and its value
/// before the examined group) and whether a front slot runs.
pub(super) struct DispatchRegs {
    pub(super) d_scan: Signal,
    pub(super) d_used: Signal,
    pub(super) d_save: Signal,
    pub(super) d_nsl: Signal,
    pub(super) d_gi: Signal,
    pub(super) d_conf: Signal,
    pub(super) d_gbase: Signal,
    pub(super) d_gptr: Signal,
    pub(super) d_dly: Signal,
    pub(super) d_dsave: Signal,
    pub(super) d_front: Signal,
}

impl DispatchRegs {
    /// Declares them in order with `r` (path, instance and entry bits `(pb, ib, eb)`).
    fn declare(r: &mut impl FnMut(&str, u32) -> Signal, (pb, ib, eb): (u32, u32, u32)) -> Self {
        DispatchRegs {
            d_scan: r("d_scan", pb + 1),
            d_used: r("d_used", 1 << ib),
            d_save: r("d_save", 1 << ib),
            d_nsl: r("d_nsl", ib + 1),
            d_gi: r("d_gi", ib + 1),
            d_conf: r("d_conf", 1),
            d_gbase: r("d_gbase", eb),
            d_gptr: r("d_gptr", eb),
            d_dly: r("d_dly", ib),
            d_dsave: r("d_dsave", ib),
            d_front: r("d_front", 1),
        }
    }
}

impl Regs {
    /// Declares every register and memory in `items`, in the order the golden files show.
    pub(super) fn declare(s: &RegSizes, items: &mut Vec<Item>) -> Regs {
        let (pb, ptb, ib, eb, np2) = (s.pb, s.ptb, s.ib, s.eb, s.np2);
        let sw = sched_entry_bits(pb, ptb, ib, s.plb);
        let mm = mm_width(s.wd);
        let pw = point_bits(s.wd);
        let depth = 1u32 << (ptb + 1);
        let mut r = |n: &str, w: u32| Signal::reg(items, n, w);
        Regs {
            state: r("state", STATE_BITS),
            cnt: r("cnt", s.cnt_bits),
            paths_r: r("paths_r", pb + 1),
            cap_r: r("cap_r", 16),
            rsel: r("rsel", 1),
            slen_0: r("slen_0", ib + 1),
            slen_1: r("slen_1", ib + 1),
            dly_0: r("dly_0", ib),
            dly_1: r("dly_1", ib),
            sused_0: r("sused_0", 1 << ib),
            sused_1: r("sused_1", 1 << ib),
            wb_on: r("wb_on", 1),
            wcnt: r("wcnt", s.cnt_bits),
            wsel: r("wsel", 1),
            ldly: r("ldly", ib),
            cycles: r("cycles", 32),
            done: r("done", 1),
            tx_x: r("tx_x", 32),
            tx_y: r("tx_y", 32),
            tx_z: r("tx_z", 32),
            rx_x: r("rx_x", 32),
            rx_y: r("rx_y", 32),
            rx_z: r("rx_z", 32),
            st_x: r("st_x", mm),
            st_y: r("st_y", mm),
            st_z: r("st_z", mm),
            cur: r("cur", np2),
            conv: r("conv", np2),
            dz: r("dz", np2),
            ov: r("ov", np2),
            pbig: r("pbig", np2),
            pdz: r("pdz", np2),
            pov: r("pov", np2),
            rd_a: r("rd_a", pw),
            rd_b: r("rd_b", pw),
            rd_c: r("rd_c", pw),
            sched_q: r("sched_q", sw + 2 * eb),
            sq_ok: r("sq_ok", 1),
            sq_tail: r("sq_tail", 1),
            wsched_q: r("wsched_q", sw + 2 * eb),
            wq_ok: r("wq_ok", 1),
            wq_tail: r("wq_tail", 1),
            ld_q_en: r("ld_q_en", 1),
            ld_q_tail: r("ld_q_tail", 1),
            ld_q_first: r("ld_q_first", 1),
            ld_q_last: r("ld_q_last", 1),
            ld_q_inst: r("ld_q_inst", ib),
            ld_go: r("ld_go", 1),
            ld_go_inst: r("ld_go_inst", ib),
            wbe: WbEntry::declare(&mut r, (pb, ptb, ib, eb), s.box_plane_bits()),
            rq_valid: r("rq_valid", 1),
            rq_kind: r("rq_kind", 2),
            rq_reg: r("rq_reg", 4),
            rq_word: r("rq_word", 2),
            rq_path: r("rq_path", pb),
            rounds_q: r("rounds_q", 16),
            rvalid: r("rvalid", np2),
            rq_head: r("rq_head", pb),
            rq_tail: r("rq_tail", pb),
            rq_count: r("rq_count", pb + 1),
            rq_q: r("rq_q", 2 * eb),
            job_q: r("job_q", sw),
            dstate: r("dstate", DSTATE_BITS),
            d: DispatchRegs::declare(&mut r, (pb, ib, eb)),
            // The ready queue (one entry per queued path: {first group, next group}, entry
            // indices of the job memory) and the slot buffer (two slots: the running one and
            // the next, each job with {its job-memory entry, its path's first group}).
            rq: Signal::memory(items, "rq", 2 * eb, np2),
            sbuf: Signal::memory(items, "sbuf", sw + 2 * eb, 2 << ib),
            // The position of each PE column's job in the slot of each half (valid where that
            // half's `sused` bit is set): the dispatcher compares the front slot's with the
            // one it builds, for the load delay.
            spos: Signal::memory(items, "spos", ib, 2 << ib),
            // Entries wider than the bus word: the host writes their high bits first.
            sched_hi: (sw > 32).then(|| Signal::reg(items, "sched_hi", sw - 32)),
            lb: s.early.then(|| Signal::reg(items, "lb", np2)),
            plb: s.early.then(|| Signal::reg(items, "plb", np2)),
            // Rounds per path in a RAM (M9K), not 16 registers a path: `rvalid` marks the
            // paths that committed a round since the start (the RAM cannot be cleared in one
            // cycle).
            rounds: Signal::memory(items, "rounds", 16, np2),
            // Three copies of the point memory (one per read port, all written: the load's
            // two neighbours, the write-back's old point): each is a plain 1-write 1-read
            // array with a registered read, which Yosys maps to M9K.
            pm_a: Signal::memory(items, "pm_a", pw, depth),
            pm_b: Signal::memory(items, "pm_b", pw, depth),
            pm_c: Signal::memory(items, "pm_c", pw, depth),
        }
    }

    /// The early-stopping registers `(lb, plb)`, in designs with early stopping.
    pub(super) fn early(&self) -> Option<(&Signal, &Signal)> {
        self.lb.as_ref().zip(self.plb.as_ref())
    }
}
