//! The generator's input, its validation, and the derived design parameters.

use bt_fixed::{
    BoundsM, EarlyStop, FixedIpc, FixedPoint, PROPORTION_ITERATIONS, PathResult, PlaneInput,
    quantize_point,
};
use bt_schedule::{PathJob, Problem, Schedule};

use crate::HlsError;

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
        )?;
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

/// Latency of one PE evaluation in cycles, from `start` to a valid `s_sum`: `d_prev`,
/// `d_next`, `t_prev`, `t_next` through the shared CSD networks (4), Algorithm 3 set-up (1),
/// [`PROPORTION_ITERATIONS`] halving steps. The result is combinational from the registers,
/// so no output cycle.
pub const PE_LATENCY: u32 = 5 + PROPORTION_ITERATIONS;

/// Largest word address the 16-bit Avalon address port can reach.
pub const ADDRESS_BITS: u32 = 16;

/// Whether `num_paths` paths with `num_points` points in all fit the Avalon-MM address space
/// of [`ADDRESS_BITS`] bits (status words and four words per point). Cheap: callers check it
/// before scheduling, which can take long on a design that would be refused anyway.
pub fn check_capacity(num_paths: u64, num_points: u64) -> Result<(), HlsError> {
    let path_bits = bits_for(num_paths);
    let point_bits = bits_for(num_points);
    let status_bits = path_bits.max(4);
    let point_region_bits = (point_bits + 2).max(status_bits + 1);
    if point_region_bits + 1 > ADDRESS_BITS {
        return Err(HlsError::TooLarge(format!(
            "{num_points} points and {num_paths} paths need more than {ADDRESS_BITS} address bits \
             (at most {} points): lower --max-order or use fewer reflectors",
            1u64 << (ADDRESS_BITS - 3)
        )));
    }
    Ok(())
}

/// `ceil(log2(n))`, at least 1.
pub(crate) fn bits_for(n: u64) -> u32 {
    (64 - n.saturating_sub(1).leading_zeros()).max(1)
}

/// The validated design: input, model, schedule and every derived size.
#[derive(Debug, Clone)]
pub(crate) struct Design {
    pub input: HlsInput,
    pub model: FixedIpc,
    pub schedule: Schedule,
    /// Round budget of each path (rounds its schedule holds).
    pub budgets: Vec<u32>,
    /// Global index of the first point of each path.
    pub first_point: Vec<u32>,
    pub num_points: u32,
    pub num_paths: u32,
    pub num_instances: u32,
    pub makespan: u32,
    /// Bits of a path index, point index, instance index, slot index.
    pub path_bits: u32,
    pub point_bits: u32,
    pub inst_bits: u32,
    pub slot_bits: u32,
    /// Word address of the first path status and of the first point word.
    pub status_base: u32,
    pub point_base: u32,
}

impl Design {
    pub fn new(input: &HlsInput, schedule: &Schedule) -> Result<Design, HlsError> {
        let model = input.model()?;
        let mut problems = Vec::new();
        if input.paths.is_empty() {
            problems.push("no candidate path".to_string());
        }
        for (i, p) in input.planes.iter().enumerate() {
            if p.name.is_empty() {
                problems.push(format!("plane {i} has an empty name"));
            }
        }
        if let Err(e) = input.vectors() {
            problems.push(format!("test vector: {e}"));
        }
        if !problems.is_empty() {
            return Err(HlsError::InvalidInput { problems });
        }
        let mut budgets = vec![0u32; input.paths.len()];
        for row in &schedule.slots {
            for job in row.iter().flatten() {
                if let Some(b) = budgets.get_mut(job.path as usize) {
                    *b = (*b).max(job.round + 1);
                }
            }
        }
        let problem = Problem {
            num_planes: input.planes.len() as u32,
            paths: input
                .paths
                .iter()
                .zip(&budgets)
                .map(|(planes, &rounds)| PathJob {
                    planes: planes.clone(),
                    rounds,
                })
                .collect(),
        };
        schedule
            .check(&problem)
            .map_err(|e| HlsError::Schedule(e.to_string()))?;
        let makespan = schedule.makespan();
        let mut first_point = Vec::with_capacity(input.paths.len());
        let mut num_points = 0u32;
        for p in &input.paths {
            first_point.push(num_points);
            num_points += p.len() as u32;
        }
        let num_paths = input.paths.len() as u32;
        let num_instances = schedule.instances.len() as u32;
        let path_bits = bits_for(num_paths.into());
        let point_bits = bits_for(num_points.into());
        let status_bits = path_bits.max(4);
        let point_region_bits = (point_bits + 2).max(status_bits + 1);
        check_capacity(num_paths.into(), num_points.into())?;
        if makespan == 0 {
            return Err(HlsError::Schedule("schedule holds no job".into()));
        }
        Ok(Design {
            input: input.clone(),
            model,
            schedule: schedule.clone(),
            budgets,
            first_point,
            num_points,
            num_paths,
            num_instances,
            makespan,
            path_bits,
            point_bits,
            inst_bits: bits_for(num_instances.into()),
            slot_bits: bits_for(makespan.into()),
            status_base: 1 << status_bits,
            point_base: 1 << point_region_bits,
        })
    }

    /// Cycles from the start command to `done` (the `CYCLES` register): initialise the point
    /// memory (one point per cycle), then per slot load operands (instances + 1), run the PEs
    /// ([`PE_LATENCY`]) and write back (instances + 1).
    pub fn predicted_cycles(&self) -> u64 {
        crate::plan::run_cycles(self.num_points.into(), self.num_instances, self.makespan)
    }

    /// Cycles of one schedule slot.
    pub fn cycles_per_slot(&self) -> u32 {
        crate::plan::cycles_per_slot(self.num_instances) as u32
    }
}
