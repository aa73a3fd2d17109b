//! The generator's input, its validation, and the derived design parameters.

use bt_fixed::{
    BoundsM, EarlyStop, FixedIpc, FixedPoint, PathResult, PlaneInput, RoundOrder, quantize_point,
};
use bt_schedule::{PathJob, PeInstance, Problem, Schedule};

use crate::HlsError;
use crate::rtl::mult::EP4CE115_MULTIPLIERS;

/// One reflection plane: `normal · x = offset_m` (normal unit, offset in metres).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlaneSpec {
    /// Human-readable name (goes into comments of `bt_pe_<i>`).
    pub name: String,
    /// Unit normal (unitless).
    pub normal: [f64; 3],
    /// Offset along the normal, metres.
    pub offset_m: f64,
    /// Axis-aligned bounds of the plane's polygon, metres (`[min, max]`), for early stopping;
    /// `None`: this plane never freezes a path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds_m: Option<BoundsM>,
}

/// Everything `generate` needs besides the schedule. Plain data, metres outside.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HlsInput {
    /// Reflection planes; PE `bt_pe_<i>` is built for plane `i`.
    pub planes: Vec<PlaneSpec>,
    /// Candidate paths: plane indices, TX side first.
    pub paths: Vec<Vec<u32>>,
    /// Starting point of every path point, metres (e.g. the polygon centroid).
    pub init_points: Vec<Vec<[f64; 3]>>,
    /// Design transmitter position, metres (first test vector).
    pub tx: [f64; 3],
    /// Design receiver position, metres (first test vector).
    pub rx: [f64; 3],
    /// Convergence threshold on a round's L∞ displacement, fine LSB (1/256 mm).
    pub threshold_lsb: u32,
    /// Round cap used by [`HlsInput::problem`] to size each path's budget.
    pub max_rounds: u32,
    /// Further (TX, RX) pairs in metres to co-simulate after the design pair.
    pub test_vectors: Vec<[[f64; 3]; 2]>,
    /// Early stopping on the planes' `bounds_m` ([`EarlyStop`]); `None`: off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub early_stop: Option<EarlyStop>,
    /// Width of the coordinate word, bits ([`bt_fixed::Widths`]; 40 = the full design, a room
    /// needs about 24: [`bt_fixed::coord_bits_for`]). Every datapath narrows with it.
    #[serde(default = "full_coord_bits")]
    pub coord_bits: u32,
    /// Update order of a round ([`RoundOrder`]; inputs written before it existed: Jacobi).
    /// Red-black runs a round in two phases, the second reading the first's new points (the
    /// schedule's `late` jobs); the platform runs either.
    #[serde(default)]
    pub round_order: RoundOrder,
}

/// The full 40-bit coordinate word (inputs written before narrowing existed).
pub fn full_coord_bits() -> u32 {
    bt_fixed::width::COORD
}

impl HlsInput {
    /// The fixed-point model of this input.
    pub fn model(&self) -> Result<FixedIpc, HlsError> {
        let planes: Vec<PlaneInput> = self
            .planes
            .iter()
            .map(|p| PlaneInput {
                normal: p.normal,
                offset_m: p.offset_m,
            })
            .collect();
        let model = FixedIpc::new(
            &planes,
            &self.paths,
            &self.init_points,
            self.threshold_lsb,
            self.max_rounds,
        )?
        .with_coord_bits(self.coord_bits)?
        .with_round_order(self.round_order);
        Ok(match self.early_stop {
            Some(stop) => {
                let bounds: Vec<Option<BoundsM>> = self.planes.iter().map(|p| p.bounds_m).collect();
                model.with_early_stop(stop, &bounds)?
            }
            None => model,
        })
    }

    /// The scheduling problem: each path's round budget is the number of rounds the fixed-point
    /// model needs at the design TX/RX (at least 1, at most `max_rounds`; with early stopping,
    /// a frozen path's budget ends at the round that froze it).
    pub fn problem(&self) -> Result<Problem, HlsError> {
        let model = self.model()?;
        let results = model.run(self.tx, self.rx)?;
        Ok(self.problem_for(&results))
    }

    /// The scheduling problem of one round of every path (rounds 1, the input's phases): what
    /// dynamic dispatch plans from ([`crate::plan_dispatch`]). Runs no model.
    pub fn one_round_problem(&self) -> Problem {
        Problem {
            num_planes: self.planes.len() as u32,
            paths: self
                .paths
                .iter()
                .map(|planes| PathJob {
                    planes: planes.clone(),
                    rounds: 1,
                    phases: self.round_order.phases(),
                })
                .collect(),
        }
    }

    /// The scheduling problem from model results already computed at the design TX/RX
    /// (`results[p]` of path `p`, as [`FixedIpc::run`] returns them): saves a second run.
    pub fn problem_for(&self, results: &[PathResult]) -> Problem {
        debug_assert_eq!(results.len(), self.paths.len());
        Problem {
            num_planes: self.planes.len() as u32,
            paths: self
                .paths
                .iter()
                .zip(results)
                .map(|(planes, r)| PathJob {
                    planes: planes.clone(),
                    rounds: r.rounds.max(1),
                    phases: self.round_order.phases(),
                })
                .collect(),
        }
    }

    /// All (TX, RX) vectors quantised to bus words, the design pair first.
    pub fn vectors(&self) -> Result<Vec<[FixedPoint; 2]>, HlsError> {
        std::iter::once([self.tx, self.rx])
            .chain(self.test_vectors.iter().copied())
            .map(|[t, r]| Ok([quantize_point(t)?, quantize_point(r)?]))
            .collect()
    }
}

/// Latency of one PE evaluation in cycles for a `coord_bits`-bit coordinate word, from `start`
/// to a valid `s_sum`: `d_prev`, `d_next`, `t_prev`, `t_next` through the shared CSD networks
/// (4), Algorithm 3 set-up (1), [`bt_fixed::Widths::iterations`] halving steps (32 at 40 bits,
/// 24 at a room's 24 bits). The result is combinational from the registers, so no output
/// cycle.
pub fn pe_latency(coord_bits: u32) -> u32 {
    5 + bt_fixed::Widths::for_coord(coord_bits).iterations
}

impl HlsInput {
    /// The PE latency of this input's design, cycles ([`pe_latency`]).
    pub fn pe_latency(&self) -> u32 {
        pe_latency(self.coord_bits)
    }
}

/// Narrowest Avalon word address of a design, bits: the control, status, point and schedule
/// regions of `Layout::of` take what they need above it (the port is
/// `avs_address[address_bits-1:0]`, at least 16 bits).
pub const MIN_ADDRESS_BITS: u32 = 16;

/// Widest Avalon word address, bits (the testbench's program words are 32 bits).
pub const MAX_ADDRESS_BITS: u32 = 30;

/// M9K blocks of the EP4CE115 (the paper's Cyclone IV E), 9,216 bits each.
pub const EP4CE115_M9K_BLOCKS: u32 = 432;

/// M9K blocks a simple dual-port RAM of `depth` words of `width` bits takes: the best of the
/// block's shapes (8K x 1, 4K x 2, 2K x 4, 1K x 9, 512 x 18, 256 x 36), as `bt_m9k.txt` maps them.
pub fn m9k_blocks(depth: u64, width: u64) -> u64 {
    [
        (8192, 1),
        (4096, 2),
        (2048, 4),
        (1024, 9),
        (512, 18),
        (256, 36),
    ]
    .iter()
    .map(|&(d, w)| depth.div_ceil(d) * width.div_ceil(w))
    .min()
    .unwrap_or(0)
}

/// `ceil(log2(n))`, at least 1.
pub(crate) fn bits_for(n: u64) -> u32 {
    (64 - n.saturating_sub(1).leading_zeros()).max(1)
}

/// How much per-step work the synthesised accelerator holds: the sizes of its RAMs (path
/// flags, point memory, schedule memory). Work is loaded over the bus per time step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Capacity {
    /// Candidate paths per run.
    pub paths: u32,
    /// Path points per run (sum of the paths' orders).
    pub points: u32,
    /// Groups of a step's round template (its slots: one group each).
    pub slots: u32,
    /// Job-memory entries per run: one round of every path, one entry per path point
    /// ([`crate::schedule_entries`] of the template).
    #[serde(default)]
    pub entries: u32,
}

/// The accelerator as synthesised once per static room: generic PEs
/// ([`bt_schedule::PeInstance::generic`], the planes' coefficients in a plane table), or one PE
/// per plane (plus duplicates) with its constants baked in, the convergence threshold, early stopping, and the capacity of
/// the RAMs the host fills per time step.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Platform {
    /// Reflection planes; PE module `bt_pe_<i>` is built for plane `i`.
    pub planes: Vec<PlaneSpec>,
    /// Convergence threshold on a round's L∞ displacement, fine LSB (1/256 mm).
    pub threshold_lsb: u32,
    /// Early stopping on the planes' `bounds_m`; `None`: off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub early_stop: Option<EarlyStop>,
    /// PE instances (columns of the schedule memory), sorted by `(plane, copy)`.
    pub instances: Vec<PeInstance>,
    /// RAM sizes.
    pub capacity: Capacity,
    /// M9K blocks the RAMs may take (point memory copies and schedule memory); a design that
    /// needs more is refused. Default: the EP4CE115's [`EP4CE115_M9K_BLOCKS`].
    #[serde(default = "default_m9k_budget")]
    pub m9k_budget: u32,
    /// 18 × 18 multiplier blocks the PEs' products may take (every PE instance's): the
    /// networks that save the most adders get multipliers while these last, the rest keep
    /// their CSD shift-add networks; 0 builds every network as CSD. Default: the EP4CE115's
    /// [`EP4CE115_MULTIPLIERS`].
    #[serde(default = "default_multiplier_budget")]
    pub multiplier_budget: u32,
    /// Width of the coordinate word, bits ([`HlsInput::coord_bits`]; every step's must equal it).
    #[serde(default = "full_coord_bits")]
    pub coord_bits: u32,
}

fn default_m9k_budget() -> u32 {
    EP4CE115_M9K_BLOCKS
}

fn default_multiplier_budget() -> u32 {
    EP4CE115_MULTIPLIERS
}

/// One accelerator run's work as the host loads it: candidates, start points, TX/RX (the
/// [`HlsInput`], whose planes must be the platform's) and the PE schedule.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepWork {
    /// Candidates, start points, TX/RX, test vectors.
    pub input: HlsInput,
    /// PE schedule (its instances must exist on the platform).
    pub schedule: Schedule,
}

impl Platform {
    /// Checks what the platform alone must satisfy, every problem at once (as generating its
    /// design would): named planes, at least one PE, PEs of existing planes, and on generic
    /// PEs no mix with plane PEs and the multiplier budget. Lets a caller that only plans
    /// (`hls gen --plan-only`) refuse what it could not build.
    pub fn check(&self) -> Result<(), HlsError> {
        let problems = self.problems();
        if problems.is_empty() {
            Ok(())
        } else {
            Err(HlsError::InvalidInput { problems })
        }
    }

    fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        for (i, p) in self.planes.iter().enumerate() {
            if p.name.is_empty() {
                problems.push(format!("plane {i} has an empty name"));
            }
        }
        if self.instances.is_empty() {
            problems.push("the platform has no PE".into());
        }
        for inst in &self.instances {
            if inst.plane as usize >= self.planes.len() && !inst.is_generic() {
                problems.push(format!("PE of plane {} out of range", inst.plane));
            }
        }
        problems.extend(generic_problems(self));
        problems
    }

    /// Whether the platform's PEs are generic ([`PeInstance::generic`]): any PE takes any
    /// plane's job, the plane's coefficients loaded with it from the plane table.
    pub fn is_generic(&self) -> bool {
        self.instances.first().is_some_and(|i| i.is_generic())
    }

    /// The smallest platform that runs every step of `work`: the planes, threshold, early
    /// stopping and coordinate word of the first step, one PE per plane that some step's
    /// schedule uses (more where a schedule duplicates it; none for a plane no step's paths
    /// meet, which would never get a job), and RAMs for the largest step.
    pub fn fitting(work: &[StepWork]) -> Result<Platform, HlsError> {
        let Some(first) = work.first() else {
            return Err(HlsError::InvalidInput {
                problems: vec!["no step to run".into()],
            });
        };
        let n = first.input.planes.len();
        // No PE for a plane that no step's schedule uses: it would never get a job.
        let mut copies = vec![0u32; n];
        let mut capacity = Capacity {
            paths: 1,
            points: 1,
            slots: 1,
            entries: 1,
        };
        let mut generic = 0u32;
        for w in work {
            for inst in &w.schedule.instances {
                if inst.is_generic() {
                    generic = generic.max(inst.copy + 1);
                } else if let Some(c) = copies.get_mut(inst.plane as usize) {
                    *c = (*c).max(inst.copy + 1);
                }
            }
            let points: usize = w.input.paths.iter().map(Vec::len).sum();
            capacity.paths = capacity.paths.max(w.input.paths.len() as u32);
            capacity.points = capacity.points.max(points as u32);
            capacity.slots = capacity.slots.max(w.schedule.makespan());
            capacity.entries = capacity
                .entries
                .max(crate::plan::schedule_entries(&w.schedule));
        }
        let instances = copies
            .iter()
            .enumerate()
            .flat_map(|(plane, &c)| {
                (0..c).map(move |copy| PeInstance {
                    plane: plane as u32,
                    copy,
                })
            })
            .chain((0..generic).map(PeInstance::generic))
            .collect();
        Ok(Platform {
            planes: first.input.planes.clone(),
            threshold_lsb: first.input.threshold_lsb,
            early_stop: first.input.early_stop,
            instances,
            capacity,
            m9k_budget: EP4CE115_M9K_BLOCKS,
            multiplier_budget: EP4CE115_MULTIPLIERS,
            coord_bits: first.input.coord_bits,
        })
    }
}

/// One step of a [`Design`]: the validated work and everything derived from it.
#[derive(Debug, Clone)]
pub(crate) struct StepDesign {
    /// The step's input and schedule, validated against the platform.
    pub work: StepWork,
    /// The fixed-point model of the step's paths, which computes the expected bus words.
    pub model: FixedIpc,
    /// Each path's groups (one round), from the step's round template.
    pub groups: Vec<Vec<crate::dispatch::Group>>,
    /// Global index of the first point of each path.
    pub first_point: Vec<u32>,
    /// Groups of the round template (its slots), at least 1.
    pub makespan: u32,
    /// Platform column of each schedule instance.
    pub columns: Vec<u32>,
}

/// The validated design: platform, per-step work and every derived size.
#[derive(Debug, Clone)]
pub(crate) struct Design {
    pub platform: Platform,
    /// Model of the platform's planes (early-stopping boxes included), for the PEs and boxes.
    pub model: FixedIpc,
    pub steps: Vec<StepDesign>,
    /// Index widths and bus regions of the platform.
    pub layout: Layout,
}

/// Where the platform-sized regions of the bus address map start: Avalon-MM word addresses
/// (32-bit words), each a power of two above the fixed registers of [`crate::regs`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct AddressMap {
    /// Word address of path 0's status word (`PATH_STATUS[p]` at `status_base + p`).
    pub status_base: u32,
    /// Word address of point 0's first word (8 words per point: 2 banks of X, Y, Z, FRAC).
    pub point_base: u32,
    /// Word address of the first schedule entry (`SCHED[j]` at `sched_base + j`).
    pub sched_base: u32,
    /// Word address of the plane table on generic PEs (`PLANE[p]` word `w` at
    /// `plane_base + 8·p + w`: the normal's x, y, z in Q2.30, then −offset in fine LSB, low
    /// word first); `None` on plane PEs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane_base: Option<u32>,
}

impl AddressMap {
    /// Word address of word `word` (0-3: X, Y, Z, FRAC) of point `g` in `bank` (0 or 1).
    pub fn point_word(&self, g: u32, bank: u32, word: u32) -> u32 {
        self.point_base + 8 * g + 4 * bank + word
    }
}

/// Index widths and bus regions of a platform.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub num_instances: u32,
    /// Bits of a path index, point index, instance index, slot index.
    pub path_bits: u32,
    pub point_bits: u32,
    pub inst_bits: u32,
    /// Bits of a schedule-memory entry index.
    pub entry_bits: u32,
    /// Bits of a job's plane field (generic PEs; 0 on plane PEs).
    pub plane_bits: u32,
    /// Width of `avs_address`, bits.
    pub address_bits: u32,
    /// The status, point and schedule regions.
    pub map: AddressMap,
}

impl Layout {
    /// Regions: status `[2^s, 2^(s+1))` with `s = max(4, path bits)`, points
    /// `[2^q, 2^(q+1))` (8 words per point: 2 banks of 4) with `q > s`, schedule
    /// `[2^r, 2^(r+1))` with `r > q`; the address is `max(16, r + 1)` bits. Refused: more than
    /// [`MAX_ADDRESS_BITS`], or RAMs over the platform's M9K budget.
    pub fn of(platform: &Platform) -> Result<Layout, HlsError> {
        let cap = platform.capacity;
        let num_instances = platform.instances.len() as u32;
        let path_bits = bits_for(cap.paths.into());
        let point_bits = bits_for(cap.points.into());
        let inst_bits = bits_for(num_instances.into());
        let status_bits = path_bits.max(4);
        let point_region_bits = (point_bits + 3).max(status_bits + 1);
        let entry_bits = bits_for(cap.entries.max(1).into());
        let sched_region_bits = entry_bits.max(point_region_bits + 1);
        let generic = platform.is_generic();
        let plane_bits = if generic {
            bits_for(platform.planes.len() as u64)
        } else {
            0
        };
        // The plane table (generic PEs): 8 words a plane above the schedule region.
        let region_end = sched_region_bits + 1 + u32::from(generic);
        let address_bits = region_end.max(MIN_ADDRESS_BITS);
        if address_bits > MAX_ADDRESS_BITS {
            return Err(HlsError::TooLarge(format!(
                "{} paths, {} points and {} schedule entries need {address_bits} address bits, \
                 more than {MAX_ADDRESS_BITS}: lower --max-order or use fewer reflectors",
                cap.paths, cap.points, cap.entries
            )));
        }
        let sw = sched_entry_bits(path_bits, point_bits, inst_bits, plane_bits);
        let wd = bt_fixed::Widths::for_coord(platform.coord_bits);
        let word = crate::rtl::pe::point_bits(wd);
        // Point memory copies (three: the load's two neighbours, the write-back's old point),
        // job memory, slot buffer (two slots), ready queue and the plane table's words.
        let table: u64 = plane_table_words(wd, generic)
            .iter()
            .map(|&w| m9k_blocks(1 << plane_bits, w.into()))
            .sum();
        let blocks = 3 * m9k_blocks(1 << (point_bits + 1), word.into())
            + m9k_blocks(1 << entry_bits, sw.into())
            + m9k_blocks(2 << inst_bits, (sw + 2 * entry_bits).into())
            + m9k_blocks(1 << path_bits, (2 * entry_bits).into())
            + table;
        if blocks > platform.m9k_budget.into() {
            return Err(HlsError::TooLarge(format!(
                "{} paths, {} points and {} schedule entries ({} slots, {} PEs) need {blocks} M9K \
                 blocks for the point and schedule memories, more than the budget of {}: lower \
                 --max-order or use fewer reflectors",
                cap.paths, cap.points, cap.entries, cap.slots, num_instances, platform.m9k_budget
            )));
        }
        if 2 * entry_bits > 32 {
            return Err(HlsError::TooLarge(format!(
                "{} job-memory entries: a ready-queue entry (two entry indices) exceeds the \
                 32-bit bus word",
                cap.entries
            )));
        }
        if sw > 64 {
            return Err(HlsError::TooLarge(format!(
                "a schedule entry for {} paths and {} points exceeds two 32-bit words",
                cap.paths, cap.points
            )));
        }
        if num_instances > 255 {
            return Err(HlsError::TooLarge(format!(
                "{num_instances} PE instances (INFO holds 8 bits)"
            )));
        }
        Ok(Layout {
            num_instances,
            path_bits,
            point_bits,
            inst_bits,
            entry_bits,
            plane_bits,
            address_bits,
            map: AddressMap {
                status_base: 1 << status_bits,
                point_base: 1 << point_region_bits,
                sched_base: 1 << sched_region_bits,
                plane_base: generic.then_some(1 << (sched_region_bits + 1)),
            },
        })
    }
}

/// Schedule-entry fields: `{plane, column, tail, late, end, last, first, point, path, valid}`
/// from bit 0 up (`tail` marks a group's last entry, `column` the PE, `plane` the job's plane
/// on generic PEs: `plane_bits` 0 otherwise).
pub(crate) fn sched_entry_bits(
    path_bits: u32,
    point_bits: u32,
    inst_bits: u32,
    plane_bits: u32,
) -> u32 {
    6 + path_bits + point_bits + inst_bits + plane_bits
}

/// The widths of a plane-table entry's bus words (generic PEs; none on plane PEs): the
/// normal's three Q2.30 components, then the negated offset in 32-bit words, low first.
pub(crate) fn plane_table_words(wd: bt_fixed::Widths, generic: bool) -> Vec<u32> {
    if !generic {
        return Vec::new();
    }
    let mut words = vec![crate::rtl::generic::NORMAL_BITS; 3];
    let mut left = crate::rtl::generic::offset_bits(wd);
    while left > 0 {
        words.push(left.min(32));
        left -= left.min(32);
    }
    words
}

impl Design {
    pub fn new(platform: &Platform, work: &[StepWork]) -> Result<Design, HlsError> {
        let mut problems = platform.problems();
        if work.is_empty() {
            problems.push("no step to run".into());
        }
        if !problems.is_empty() {
            return Err(HlsError::InvalidInput { problems });
        }
        let model = platform_model(platform)?;
        let mut steps = Vec::with_capacity(work.len());
        for (k, w) in work.iter().enumerate() {
            steps.push(step_design(platform, k, w)?);
        }
        Ok(Design {
            platform: platform.clone(),
            model,
            steps,
            layout: Layout::of(platform)?,
        })
    }
}

/// What a generic platform cannot do: mix generic and plane PEs, or hold more multiplier
/// blocks than its budget.
fn generic_problems(platform: &Platform) -> Vec<String> {
    let generic = platform.instances.iter().filter(|i| i.is_generic()).count() as u32;
    let mut problems = Vec::new();
    if generic == 0 {
        return problems;
    }
    if generic as usize != platform.instances.len() {
        problems.push("a platform mixes generic PEs and plane PEs".into());
    }
    let wd = bt_fixed::Widths::for_coord(platform.coord_bits);
    let blocks = generic * crate::rtl::generic::generic_pe_blocks(wd);
    if blocks > platform.multiplier_budget {
        problems.push(format!(
            "{generic} generic PEs need {blocks} 18 x 18 multiplier blocks, more than the budget \
             of {} (--multiplier-budget): use fewer --generic-pes",
            platform.multiplier_budget
        ));
    }
    problems
}

/// The fixed-point model of the platform's planes alone (no path): quantised planes and
/// early-stopping boxes, which the PEs and `bt_top` bake in.
pub(crate) fn platform_model(platform: &Platform) -> Result<FixedIpc, HlsError> {
    let input = HlsInput {
        planes: platform.planes.clone(),
        paths: Vec::new(),
        init_points: Vec::new(),
        tx: [0.0; 3],
        rx: [1.0; 3],
        threshold_lsb: platform.threshold_lsb,
        max_rounds: 1,
        test_vectors: Vec::new(),
        early_stop: platform.early_stop,
        coord_bits: platform.coord_bits,
        round_order: RoundOrder::Jacobi,
    };
    input.model()
}

/// Step `k`'s work against the platform: its planes, threshold, early stopping and coordinate
/// word must be the platform's, and its TX/RX vectors must fit. Every problem at once; returns
/// the step's model.
fn check_step(platform: &Platform, k: usize, input: &HlsInput) -> Result<FixedIpc, HlsError> {
    let mut problems = Vec::new();
    if input.paths.is_empty() {
        problems.push(format!("step {k}: no candidate path"));
    }
    if input.planes != platform.planes {
        problems.push(format!(
            "step {k}: its planes differ from the platform's (a moving surface needs the host)"
        ));
    }
    if input.threshold_lsb != platform.threshold_lsb || input.early_stop != platform.early_stop {
        problems.push(format!(
            "step {k}: threshold or early stopping differs from the platform's"
        ));
    }
    if input.coord_bits != platform.coord_bits {
        problems.push(format!(
            "step {k}: its coordinate word ({} bits) differs from the platform's ({} bits)",
            input.coord_bits, platform.coord_bits
        ));
    }
    if !(1..=0xffff).contains(&input.max_rounds) {
        problems.push(format!(
            "step {k}: round cap {} outside 1..=65535 (ROUND_CAP holds 16 bits)",
            input.max_rounds
        ));
    }
    let vectors = input.vectors();
    if let Err(e) = &vectors {
        problems.push(format!("step {k} test vector: {e}"));
    }
    if !problems.is_empty() {
        return Err(HlsError::InvalidInput { problems });
    }
    let model = input.model()?;
    for [tx, rx] in vectors? {
        model.check_terminal("TX", tx)?;
        model.check_terminal("RX", rx)?;
    }
    Ok(model)
}

fn step_design(platform: &Platform, k: usize, w: &StepWork) -> Result<StepDesign, HlsError> {
    let input = &w.input;
    let schedule = &w.schedule;
    let model = check_step(platform, k, input)?;
    let problem = input.one_round_problem();
    schedule
        .check(&problem)
        .map_err(|e| HlsError::Schedule(format!("step {k}: {e}")))?;
    let groups = crate::dispatch::groups(schedule, input.paths.len())
        .map_err(|e| HlsError::Schedule(format!("step {k}: {e}")))?;
    let makespan = schedule.makespan();
    if makespan == 0 {
        return Err(HlsError::Schedule(format!(
            "step {k}: schedule holds no job"
        )));
    }
    let columns = schedule
        .instances
        .iter()
        .map(|inst| {
            platform
                .instances
                .iter()
                .position(|p| p == inst)
                .map(|c| c as u32)
                .ok_or_else(|| {
                    HlsError::Schedule(format!(
                        "step {k}: PE (plane {}, copy {}) is not on the platform",
                        inst.plane, inst.copy
                    ))
                })
        })
        .collect::<Result<Vec<u32>, HlsError>>()?;
    let mut first_point = Vec::with_capacity(input.paths.len());
    let mut num_points = 0u32;
    for p in &input.paths {
        first_point.push(num_points);
        num_points += p.len() as u32;
    }
    let num_paths = input.paths.len() as u32;
    let cap = platform.capacity;
    let entries = crate::plan::schedule_entries(schedule);
    if num_paths > cap.paths
        || num_points > cap.points
        || makespan > cap.slots
        || entries > cap.entries
    {
        return Err(HlsError::TooLarge(format!(
            "step {k}: {num_paths} paths, {num_points} points, {makespan} slots, {entries} \
             schedule entries exceed the platform's capacity of {} paths, {} points, {} slots, \
             {} entries",
            cap.paths, cap.points, cap.slots, cap.entries
        )));
    }
    Ok(StepDesign {
        work: w.clone(),
        model,
        groups,
        first_point,
        makespan,
        columns,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn platform(paths: u32, points: u32, entries: u32, pes: u32, m9k_budget: u32) -> Platform {
        Platform {
            planes: vec![PlaneSpec {
                name: "floor".into(),
                normal: [0.0, 0.0, 1.0],
                offset_m: 0.0,
                bounds_m: None,
            }],
            threshold_lsb: 16,
            early_stop: None,
            instances: (0..pes).map(|copy| PeInstance { plane: 0, copy }).collect(),
            capacity: Capacity {
                paths,
                points,
                slots: 2342,
                entries,
            },
            m9k_budget,
            multiplier_budget: 0,
            coord_bits: full_coord_bits(),
        }
    }

    #[test]
    fn m9k_blocks_take_the_best_shape() {
        // 64 K x 19 bits: 8 blocks deep x 19 wide (8K x 1) beats 16 x 10 (4K x 2).
        assert_eq!(m9k_blocks(65_536, 19), 152);
        // 512 x 120 bits: 512 x 18 shape, 7 blocks wide.
        assert_eq!(m9k_blocks(512, 120), 7);
        assert_eq!(m9k_blocks(1, 1), 1);
    }

    #[test]
    fn the_address_widens_with_the_schedule_memory() {
        // The living room at order 3: 104 paths, 270 points, ~12,000 packed schedule entries
        // (2^14): the schedule region 2^14 fits the 16-bit minimum.
        let l = Layout::of(&platform(104, 270, 12_000, 25, EP4CE115_M9K_BLOCKS)).unwrap();
        assert_eq!(
            (l.map.sched_base, l.address_bits),
            (1 << 14, MIN_ADDRESS_BITS)
        );
        // 40,000 entries (2^16) need 17 address bits instead of a refusal.
        let l = Layout::of(&platform(104, 270, 40_000, 25, EP4CE115_M9K_BLOCKS)).unwrap();
        assert_eq!((l.map.sched_base, l.address_bits), (1 << 16, 17));
        // 70,000 entries (2^17): a ready-queue entry, two entry indices, would not fit the bus
        // word.
        let e = Layout::of(&platform(104, 270, 70_000, 25, EP4CE115_M9K_BLOCKS)).unwrap_err();
        assert!(e.to_string().contains("ready-queue entry"), "{e}");
    }

    #[test]
    fn memories_over_the_m9k_budget_are_refused_with_the_numbers() {
        // Point memories 3 x 1 K x 120 bits (two banks of 270 points; 14 blocks each), job
        // memory 256 K x 26 bits ({column 5, tail, end, last, first, point 9, path 7, valid};
        // 1K x 9 shape: 256 x 3 = 768 blocks), slot buffer 64 x (26 + 2 x 18) bits (2 blocks)
        // and ready queue 128 x 36 bits (1 block): 813 blocks, over the EP4CE115's 432.
        let e = Layout::of(&platform(104, 270, 200_000, 25, EP4CE115_M9K_BLOCKS)).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, HlsError::TooLarge(_)), "{text}");
        assert!(
            text.contains("813 M9K blocks") && text.contains("budget of 432"),
            "{text}"
        );
        // 12,000 entries: 3 x 14 + 16K x 26 (1K x 9 shape: 16 x 3 = 48) + 2 + 1 = 93 blocks.
        let e = Layout::of(&platform(104, 270, 12_000, 25, 92)).unwrap_err();
        assert!(e.to_string().contains("93 M9K blocks"), "{e}");
    }
}
