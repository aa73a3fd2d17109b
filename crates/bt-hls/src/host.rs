//! The host's side of a step: the bus program that loads the work (job memory, ready queue,
//! start points, TX/RX), starts each run and reads the results back, the expected words of
//! every read (from the model, verification only), the testbench stimulus and the register
//! map text. Nothing here feeds a model result into the program's writes.

use bt_fixed::{FixedPoint, PathResult};

use crate::input::{Design, StepDesign, pe_latency};
use crate::{CLOCK_HZ, HlsError, MAP_VERSION, dispatch, regs};

/// The cycle counts of a host program by the exact formulas (checked by co-simulation),
/// computed once from the program: [`crate::Report`] carries them, [`crate::SimReport`] sets the measured
/// counts beside them.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct CyclePrediction {
    /// `CYCLES` register value of every run (steps in order, each step's vectors in order),
    /// clock cycles: the sum over the step's slots of `2·(jobs + 2) + pe_latency`.
    pub run_cycles: Vec<u64>,
    /// Testbench clock edges of the whole bus program (1 per write, 2 per read, 1 + CYCLES per
    /// start).
    #[serde(rename = "predicted_tb_cycles")]
    pub tb_cycles: u64,
}

impl CyclePrediction {
    /// The prediction of the bus program `ops` whose runs the model expects as `runs`.
    pub(crate) fn of(ops: &[BusOp], runs: &[VectorExpectation]) -> CyclePrediction {
        CyclePrediction {
            run_cycles: runs.iter().map(|r| r.cycles).collect(),
            tb_cycles: ops.iter().map(|o| o.tb_cycles()).sum(),
        }
    }
}

/// One bus operation of the host program (and of the testbench's stimulus).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BusOp {
    /// Single-cycle write `(word address, data)`.
    Write(u32, u32),
    /// Read `(word address, expected data from the model)`.
    Read(u32, u32),
    /// Write CTRL = 1 and wait for the interrupt; the run's predicted `CYCLES`.
    Start(u64),
}

impl BusOp {
    /// Testbench clock edges of the operation.
    pub fn tb_cycles(self) -> u64 {
        match self {
            BusOp::Write(..) => 1,
            BusOp::Read(..) => 2,
            BusOp::Start(c) => 1 + c,
        }
    }
}

/// Expected bus words of one run, from the fixed-point model.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VectorExpectation {
    /// Time step (index into the design's work).
    pub step: usize,
    /// TX, millimetre words.
    pub tx: FixedPoint,
    /// RX, millimetre words.
    pub rx: FixedPoint,
    /// `(word address, expected data)` of every read, in program order.
    pub reads: Vec<(u32, u32)>,
    /// Predicted `CYCLES`.
    pub cycles: u64,
    /// Model outcome per path.
    pub paths: Vec<PathResult>,
}

/// The status word of a path:
/// `{rounds[15:0], 12'b0, left_bounds, overflow, zero_sum, converged}`. The final points are
/// in bank `rounds & 1`.
pub fn status_word(r: &PathResult) -> u32 {
    (r.rounds.min(0xffff) << 16)
        | (u32::from(r.left_bounds) << 3)
        | (u32::from(r.overflow) << 2)
        | (u32::from(r.zero_sum) << 1)
        | u32::from(r.converged)
}

/// The job-memory writes of one step: every path's groups (its round template), path after
/// path, each group's jobs in ascending PE column with the last one flagged `tail` and the
/// round's last job `end`; then `PATHS` and `ROUND_CAP`. The hardware repeats a path's
/// groups until it stops, so nothing here depends on how many rounds a path will take.
fn job_writes(d: &Design, s: &StepDesign, ops: &mut Vec<BusOp>) {
    let (pb, ptb) = (d.layout.path_bits, d.layout.point_bits);
    let tail_bit = 1u64 << (5 + pb + ptb);
    let l = &d.layout;
    let wide = crate::input::sched_entry_bits(pb, ptb, l.inst_bits, l.plane_bits) > 32;
    let phases = s.work.input.round_order.phases();
    let mut high = None;
    let mut entry = 0u32;
    for (p, groups) in s.groups.iter().enumerate() {
        let n = s.work.input.paths[p].len() as u32;
        for (g, group) in groups.iter().enumerate() {
            let mut jobs: Vec<(u32, u32)> = group
                .jobs
                .iter()
                .map(|&(c, point)| (s.columns[c as usize], point))
                .collect();
            jobs.sort_unstable();
            for (e, &(col, point)) in jobs.iter().enumerate() {
                let tail = e + 1 == jobs.len();
                let end = tail && g + 1 == groups.len();
                // A job after its round's first phase reads its neighbours' new points.
                let late = point % phases != 0;
                let word = 1
                    | (p as u64) << 1
                    | u64::from(s.first_point[p] + point) << (1 + pb)
                    | u64::from(point == 0) << (1 + pb + ptb)
                    | u64::from(point + 1 == n) << (2 + pb + ptb)
                    | u64::from(end) << (3 + pb + ptb)
                    | u64::from(late) << (4 + pb + ptb)
                    | if tail { tail_bit } else { 0 }
                    | u64::from(col) << (6 + pb + ptb)
                    | plane_field(d, s, p, point) << (6 + pb + ptb + l.inst_bits);
                // A wide entry's high bits go to SCHED_HI first, when they change.
                let hi = (word >> 32) as u32;
                if wide && high != Some(hi) {
                    ops.push(BusOp::Write(regs::SCHED_HI, hi));
                    high = Some(hi);
                }
                ops.push(BusOp::Write(d.layout.map.sched_base + entry, word as u32));
                entry += 1;
            }
        }
    }
    ops.push(BusOp::Write(regs::PATHS, s.groups.len() as u32));
    ops.push(BusOp::Write(regs::ROUND_CAP, s.work.input.max_rounds));
}

/// The plane of point `point` of path `p` as a job's plane field, on generic PEs (0 on plane
/// PEs, whose column says the plane).
fn plane_field(d: &Design, s: &StepDesign, p: usize, point: u32) -> u64 {
    if d.platform.is_generic() {
        u64::from(s.work.input.paths[p][point as usize])
    } else {
        0
    }
}

/// The plane table's writes (generic PEs only): per plane its bus words
/// ([`crate::input::plane_table_words`]) at `plane_base + 8·plane + word`. Refused: an
/// offset wider than the table's word.
fn plane_writes(d: &Design, ops: &mut Vec<BusOp>) -> Result<(), HlsError> {
    let Some(base) = d.layout.map.plane_base else {
        return Ok(());
    };
    let wd = bt_fixed::Widths::for_coord(d.platform.coord_bits);
    let ow = crate::rtl::generic::offset_bits(wd);
    let words = crate::input::plane_table_words(wd, true).len() - 3;
    for (i, plane) in d.model.planes().iter().enumerate() {
        let neg = -i128::from(plane.offset.0);
        if neg >= 1 << (ow - 1) || neg < -(1 << (ow - 1)) {
            return Err(HlsError::TooLarge(format!(
                "plane {i}'s offset does not fit the plane table's {ow}-bit word"
            )));
        }
        let at = base + 8 * i as u32;
        for (k, n) in plane.normal.iter().enumerate() {
            ops.push(BusOp::Write(at + k as u32, n.0 as u32));
        }
        for w in 0..words {
            let bits = (neg >> (32 * w)) as u32;
            ops.push(BusOp::Write(at + 3 + w as u32, bits));
        }
    }
    Ok(())
}

/// The ready queue's start of a run: `PATH_BASE[p] = {first, first}`, path `p`'s first
/// job-memory entry twice (its first group and its next one). A run consumes the queue, so
/// every run writes it.
fn queue_writes(d: &Design, s: &StepDesign, ops: &mut Vec<BusOp>) {
    let eb = d.layout.entry_bits;
    let mut first = 0u32;
    for (p, groups) in s.groups.iter().enumerate() {
        ops.push(BusOp::Write(
            d.layout.map.status_base + p as u32,
            (first << eb) | first,
        ));
        first += groups.iter().map(|g| g.jobs.len() as u32).sum::<u32>();
    }
}

/// One run of step `s`: write the ready queue, the start points (bank 0) and TX/RX, start,
/// read CYCLES, every status word and every final point.
fn run_ops(
    d: &Design,
    s: &StepDesign,
    step: usize,
    [tx, rx]: [FixedPoint; 2],
) -> (Vec<BusOp>, VectorExpectation) {
    let map = &d.layout.map;
    let mut ops = Vec::new();
    queue_writes(d, s, &mut ops);
    for p in 0..s.work.input.paths.len() {
        for (i, pt) in s.model.init_points(p).iter().enumerate() {
            let g = s.first_point[p] + i as u32;
            for (k, c) in pt.iter().enumerate() {
                ops.push(BusOp::Write(
                    map.point_word(g, 0, k as u32),
                    c.floor_mm().0 as u32,
                ));
            }
            ops.push(BusOp::Write(map.point_word(g, 0, 3), frac_word(pt)));
        }
    }
    for (k, c) in tx.iter().enumerate() {
        ops.push(BusOp::Write(regs::TX + k as u32, c.0 as u32));
    }
    for (k, c) in rx.iter().enumerate() {
        ops.push(BusOp::Write(regs::RX + k as u32, c.0 as u32));
    }
    // The expected words: the model run to each path's own stop (convergence, freezing or
    // the round cap), as the dispatching hardware runs it; verification only.
    let paths = s.model.run_fixed(tx, rx, None);
    let rounds: Vec<u32> = paths.iter().map(|r| r.rounds).collect();
    let run = crate::dispatch::predict(
        &s.groups,
        d.layout.num_instances as usize,
        &rounds,
        pe_latency(d.platform.coord_bits),
    );
    let cycles = run.cycles;
    ops.push(BusOp::Start(cycles));
    let mut reads = vec![(regs::CYCLES, cycles as u32)];
    for (p, r) in paths.iter().enumerate() {
        reads.push((map.status_base + p as u32, status_word(r)));
    }
    for (p, r) in paths.iter().enumerate() {
        for (i, pt) in r.points.iter().enumerate() {
            let g = s.first_point[p] + i as u32;
            let bank = r.rounds & 1;
            for (k, c) in pt.iter().enumerate() {
                reads.push((map.point_word(g, bank, k as u32), c.floor_mm().0 as u32));
            }
            reads.push((map.point_word(g, bank, 3), frac_word(pt)));
        }
    }
    ops.extend(reads.iter().map(|&(a, v)| BusOp::Read(a, v)));
    let v = VectorExpectation {
        step,
        tx,
        rx,
        reads,
        cycles,
        paths,
    };
    (ops, v)
}

fn frac_word(pt: &bt_fixed::FinePoint) -> u32 {
    u32::from(pt[0].frac()) | u32::from(pt[1].frac()) << 8 | u32::from(pt[2].frac()) << 16
}

/// The whole host program of the design (every step: load the schedule once, then per vector
/// load the start points and TX/RX, run, read back) and the model's expectation per run.
pub(crate) fn host_program(d: &Design) -> Result<(Vec<BusOp>, Vec<VectorExpectation>), HlsError> {
    let mut ops = Vec::new();
    let mut runs = Vec::new();
    for (k, s) in d.steps.iter().enumerate() {
        plane_writes(d, &mut ops)?;
        job_writes(d, s, &mut ops);
        for v in s.work.input.vectors()? {
            let (o, e) = run_ops(d, s, k, v);
            ops.extend(o);
            runs.push(e);
        }
    }
    Ok((ops, runs))
}

/// The testbench stimulus: 3 words per operation (1 = write addr data, 2 = read addr, 3 =
/// start addr data, 0 = end).
pub(crate) fn stimulus(ops: &[BusOp]) -> Vec<u32> {
    let mut prog = Vec::with_capacity(3 * ops.len() + 3);
    for op in ops {
        match *op {
            BusOp::Write(a, v) => prog.extend([1, a, v]),
            BusOp::Read(a, _) => prog.extend([2, a, 0]),
            BusOp::Start(_) => prog.extend([3, regs::CTRL, 1]),
        }
    }
    prog.extend([0, 0, 0]);
    prog
}

/// Words the testbench's program memory holds (`prog` in `bt_tb.v`).
pub const TB_PROGRAM_WORDS: usize = 1 << 22;

pub(crate) fn register_map(d: &Design) -> String {
    let (cap, l) = (d.platform.capacity, &d.layout);
    let mut s = String::new();
    s.push_str("# bt_top register map (Avalon-MM slave)\n\n");
    s.push_str(&format!(
        "32-bit data, word addresses on `avs_address[{}:0]`, no waitrequest, single-cycle writes, \
         pipelined reads with a fixed latency of 2 cycles (`avs_readdatavalid` marks the data), \
         interrupt `ins_irq` = done (level, cleared by the next start). Coordinates on the bus \
         are millimetre words (two's complement, metres x 1000). Writes other than CTRL are \
         ignored while busy.\n\n",
        l.address_bits - 1
    ));
    s.push_str("| address | access | name | content |\n|---|---|---|---|\n");
    s.push_str("| 0x0000 | W | CTRL | bit 0 = 1 starts a run (ignored while busy) |\n");
    s.push_str("| 0x0000 | R | STATUS | bit 0 busy, bit 1 done |\n");
    s.push_str("| 0x0001 | R | CYCLES | clock cycles of the last run |\n");
    s.push_str(&format!(
        "| 0x0002 | R | INFO | `{{instances[7:0], version[7:0], path capacity[15:0]}}` = 0x{:08x} |\n",
        (l.num_instances << 24) | (MAP_VERSION << 16) | (cap.paths & 0xffff)
    ));
    s.push_str(&format!(
        "| 0x0003 | R | THRESHOLD | {} fine LSB (1/256 mm) |\n",
        d.platform.threshold_lsb
    ));
    s.push_str("| 0x0004-0x0006 | RW | TX_X, TX_Y, TX_Z | transmitter, mm |\n");
    s.push_str("| 0x0008-0x000a | RW | RX_X, RX_Y, RX_Z | receiver, mm |\n");
    s.push_str(&format!(
        "| 0x000c | RW | PATHS | paths of the loaded step, up to {} |\n",
        cap.paths
    ));
    s.push_str(
        "| 0x000e | RW | ROUND_CAP | rounds after which a path stops unconverged (16 bits) |\n",
    );
    s.push_str(&format!(
        "| 0x{:04x} + p | R | PATH_STATUS[p] | `{{rounds[15:0], 12'b0, left_bounds, overflow, zero_sum, converged}}`, p < {} |\n",
        l.map.status_base, cap.paths
    ));
    s.push_str(&format!(
        "| 0x{:04x} + i | W | PATH_BASE[i] | ready queue at the start: `{{first[{eb}:0], first[{eb}:0]}}`, the job-memory entry of the i-th queued path's first group, i < PATHS |\n",
        l.map.status_base,
        eb = l.entry_bits - 1
    ));
    s.push_str(&format!(
        "| 0x{:04x} + 8i + 4b + {{0,1,2}} | RW | POINT[i].X/Y/Z, bank b | floor(mm) of point i, i < {} |\n",
        l.map.point_base, cap.points
    ));
    s.push_str(&format!(
        "| 0x{:04x} + 8i + 4b + 3 | RW | POINT[i].FRAC, bank b | `{{8'b0, z_frac, y_frac, x_frac}}` (1/256 mm; value = mm + frac/256); a write stores the point (X, Y, Z written before) |\n",
        l.map.point_base
    ));
    s.push_str(&format!(
        "| 0x{:04x} + j | W | SCHED[j] | job memory entry j (one round of every path as groups, path after path, each group's jobs in ascending PE column): `{{column[{}:0], tail, late, end, last, first, point[{}:0], path[{}:0], valid}}`, `valid` at bit 0, `tail` on a group's last job, `end` on the round's last job, `late` on a job that reads its round's new points (red-black), j < {} |\n\n",
        l.map.sched_base,
        l.inst_bits - 1,
        l.point_bits - 1,
        l.path_bits - 1,
        cap.entries
    ));
    if let Some(base) = l.map.plane_base {
        s.push_str(&format!(
            "Generic PEs: each SCHED entry also holds the job's plane, `plane[{}:0]`, above its \
             column; the host writes the plane table per step at 0x{base:04x} + 8p + w \
             (PLANE[p] word w, p < {}): w = 0, 1, 2 the normal's x, y, z (Q2.30, two's \
             complement), w = 3.. −offset in fine LSB (1/256 mm), low word first. A PE latches \
             its job's plane with the operands.\n\n",
            l.plane_bits - 1,
            d.platform.planes.len()
        ));
    }
    s.push_str("PE columns: ");
    let cols: Vec<String> = d
        .platform
        .instances
        .iter()
        .enumerate()
        .map(|(c, i)| match i.is_generic() {
            true => format!("{c} = generic"),
            false => format!("{c} = plane {} copy {}", i.plane, i.copy),
        })
        .collect();
    s.push_str(&cols.join(", "));
    s.push_str(".\n\n");
    s.push_str(
        "Per time step the host writes the job memory (one round of every path, as groups: a \
         group's jobs run in one slot), PATHS and ROUND_CAP; per run it writes PATH_BASE[*] \
         (the ready queue), every path point's start value into bank 0 (X, Y, Z, then FRAC), \
         TX_X..RX_Z, CTRL = 1, waits for `ins_irq` (or polls STATUS bit 1), then reads CYCLES, \
         PATH_STATUS[*] and each point in bank `rounds & 1` of its path. The controller \
         dispatches the queued groups into slots (a group whose PEs are free in the slot being \
         built), queues a path's next group at write-back and stops a path when it converges, \
         freezes or reaches ROUND_CAP: no round count is loaded. Point i of path p is global \
         index `first_point[p] + i` (paths in order, points TX side first); `first`/`last` \
         mark the points next to TX/RX.\n\n",
    );
    s.push_str(&cycle_formulas(d));
    s
}

/// The register map's section on the cycle count.
fn cycle_formulas(d: &Design) -> String {
    let mut s = String::from("## Cycle formulas (exact, checked by co-simulation)\n\n");
    s.push_str(&format!(
        "* a slot's load enters when the previous slot's write-back starts (it overlaps it) and \
         waits `delay` cycles (the largest lead of a shared PE column's position in the previous \
         slot over its position in this one), loads its first job 2 cycles later and one a \
         cycle (each PE starts the cycle after its own load); its write-back (jobs + 2 cycles) \
         starts at max(first load + max(PE_LATENCY - 1, jobs + 1), previous write-back's last \
         cycle + 2, dispatcher's last cycle + 2); the dispatcher of the slot after it starts \
         when the previous write-back ends; a slot dispatched with no slot running loads \
         dispatch + 1 cycles after that dispatch began; CYCLES ends with the last write-back; \
         dispatch = 3 + the jobs of the examined groups (at most {}); PE_LATENCY = {} \
         (5 + {} halving steps of Algorithm 3 at the {}-bit coordinate word); \
         `bt_hls::dispatch::predict` is the exact twin\n",
        dispatch::SCAN_LIMIT,
        pe_latency(d.platform.coord_bits),
        bt_fixed::Widths::for_coord(d.platform.coord_bits).iterations,
        d.platform.coord_bits
    ));
    s.push_str("* testbench edges: 1 per write, 2 per read, 1 + CYCLES per start\n");
    s.push_str(&format!(
        "* at {} MHz (the paper's clock) one run takes CYCLES x {} ns\n",
        CLOCK_HZ / 1e6,
        1e9 / CLOCK_HZ
    ));
    s
}
