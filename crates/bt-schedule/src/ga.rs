//! The paper's three-pass scheduler: GA, PE duplication, ASAP fill (section V, Fig. 12).

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::asap;
use crate::check::lower_bound;
use crate::decode::{self, Fitness, Placement};
use crate::error::ScheduleError;
use crate::problem::{InstanceSet, Prepared};
use crate::{Budget, Problem, Schedule};

/// Parameters of [`schedule_ga`]. The defaults schedule a living-room-size problem (25
/// planes, 10,000 paths of order 1-3, 5-60 rounds) in a few seconds of release build.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GaParams {
    /// Seed of the ChaCha8 RNG; the same problem, budget and parameters give the same schedule.
    pub seed: u64,
    /// Chromosomes per generation (>= 1). Three of the initial ones are fixed orders (index,
    /// rounds descending, jobs descending), the rest random permutations.
    pub population: u32,
    /// Generations after the initial population. Each costs `population - elite` decodes of
    /// O(jobs) each.
    pub generations: u32,
    /// Tournament size for parent selection (>= 1).
    pub tournament: u32,
    /// Best chromosomes copied unchanged into the next generation (<= population).
    pub elite: u32,
    /// Probability of order crossover (OX1) for a child, in [0, 1]; else it copies a parent.
    pub crossover_rate: f64,
    /// Probability a child is mutated (random swaps or one segment inversion), in [0, 1].
    pub mutation_rate: f64,
    /// Slots a round may be delayed to put all its jobs in one slot (latency factor 0), in
    /// slots. 0 aligns a round only when that costs it nothing.
    pub align_slack: u32,
}

impl Default for GaParams {
    fn default() -> Self {
        GaParams {
            seed: 0x5eed,
            population: 12,
            generations: 12,
            tournament: 3,
            elite: 2,
            crossover_rate: 0.9,
            mutation_rate: 0.3,
            align_slack: 0,
        }
    }
}

impl GaParams {
    fn validate(&self) -> Result<(), ScheduleError> {
        let bad = |name, reason| Err(ScheduleError::InvalidGaParams { name, reason });
        if self.population == 0 {
            return bad("population", "must be at least 1");
        }
        if self.tournament == 0 {
            return bad("tournament", "must be at least 1");
        }
        if self.elite > self.population {
            return bad("elite", "must not exceed the population");
        }
        if self.population > MAX_GA_POPULATION {
            return bad(
                "population",
                "must be at most 1000 (each chromosome holds every job)",
            );
        }
        let decodes = u64::from(self.population) * (u64::from(self.generations) + 1);
        if decodes > MAX_GA_DECODES {
            return bad(
                "population × (generations + 1)",
                "must be at most 100000 schedule decodes, each O(jobs): a budget against runs \
                 of hours",
            );
        }
        if !(0.0..=1.0).contains(&self.crossover_rate) {
            return bad("crossover_rate", "must be a probability in [0, 1]");
        }
        if !(0.0..=1.0).contains(&self.mutation_rate) {
            return bad("mutation_rate", "must be a probability in [0, 1]");
        }
        Ok(())
    }
}

/// Most chromosomes per generation (each holds every job: 1000 × 10,000 jobs is 40 MB).
pub const MAX_GA_POPULATION: u32 = 1000;

/// Most schedule decodes a GA run may make, population × (generations + 1), each O(jobs)
/// (the defaults make 156).
pub const MAX_GA_DECODES: u64 = 100_000;

/// Duplication steps always evaluated; beyond them only steps that lower the makespan bound.
const DENSE_DUPLICATION_STEPS: usize = 64;

/// The paper's three-pass PE scheduling (section V).
///
/// 1. **GA.** A chromosome is a priority permutation of the paths. The decoder places paths
///    in that order, rounds in Jacobi order; it puts all jobs of a round into one slot
///    (latency factor 0) when that slot is at most [`GaParams::align_slack`] slots after the
///    earliest end of placing the jobs one by one, else places them one by one. It is
///    O(jobs) with a per-instance union-find "next free slot". Fitness is the makespan first,
///    then the latency factor ([`crate::ScheduleStats::latency_factor`]). The initial
///    population holds the index order, longest-rounds-first and most-jobs-first orders, and
///    random permutations; then tournament selection, order crossover, swap/inversion
///    mutation, elitism. The GA runs with one PE per used plane.
/// 2. **Duplication.** While the instances stay within `budget`, the plane with the most jobs
///    per copy gets one more copy (ties: lower plane index); the best chromosome is decoded
///    again with each instance set.
/// 3. **ASAP fill** of every candidate (see the crate docs): jobs move into earlier empty
///    cells where the Jacobi order allows, trailing empty slots go.
///
/// The result is the best candidate by (makespan, latency factor, instances); the list
/// schedule ([`crate::schedule_list`], after ASAP fill) is a candidate too, so
/// `makespan(schedule_ga) <= makespan(schedule_list)`. The duplication sequence does not
/// depend on the budget, so a larger budget never gives a longer makespan. Steps of the
/// sequence beyond the first 64 are evaluated only when they lower the makespan lower bound.
pub fn schedule_ga(
    problem: &Problem,
    budget: &Budget,
    params: &GaParams,
) -> Result<Schedule, ScheduleError> {
    let prep = Prepared::new(problem)?;
    prep.check_budget(budget)?;
    params.validate()?;
    let placement = Placement::Aligned {
        slack: params.align_slack,
    };
    let base_copies = prep.base_copies();
    let base = InstanceSet::from_copies(&base_copies);

    // Pass 1.
    let best_order = evolve(&prep, &base, placement, params);

    // Pass 2: candidate instance sets. Candidate 0 is the list schedule.
    let steps = duplication_steps(&prep, &base_copies, budget.max_instances);
    let identity: Vec<u32> = (0..problem.paths.len() as u32).collect();
    let run = |candidate: usize| {
        let (order, copies, placement) = match candidate {
            0 => (&identity, &base_copies, Placement::Individual),
            c => (&best_order, &steps[c - 1], placement),
        };
        let inst = InstanceSet::from_copies(copies);
        let (_, mut pos) = decode::decode_positions(&prep, &inst, order, placement);
        // Pass 3.
        let fitness = asap::asap_fill(&prep, &inst, &mut pos);
        (fitness, inst, pos)
    };
    let keys: Vec<(Fitness, usize)> = (0..=steps.len())
        .into_par_iter()
        .map(|c| {
            let (fitness, inst, _) = run(c);
            (fitness, inst.len())
        })
        .collect();
    let best = (0..keys.len()).min_by_key(|&c| (keys[c], c)).unwrap_or(0);
    let (_, inst, pos) = run(best);
    Ok(decode::build(&prep, &inst, &pos))
}

/// Copies per plane after each duplication step (step 0 = one per used plane). Independent
/// of the budget except for its length, which is what makes the result monotone in the
/// budget.
fn duplication_steps(prep: &Prepared<'_>, base: &[u32], max_instances: u32) -> Vec<Vec<u32>> {
    let mut copies = base.to_vec();
    let mut total: u64 = copies.iter().map(|&c| u64::from(c)).sum();
    let mut bound = lower_bound(prep.problem, &copies);
    let mut steps = vec![copies.clone()];
    let mut step = 0usize;
    while total < u64::from(max_instances) {
        let busiest = prep
            .used_planes
            .iter()
            .copied()
            .filter(|&q| prep.load[q as usize] > u64::from(copies[q as usize]))
            .max_by(|&a, &b| {
                let ra = u128::from(prep.load[a as usize]) * u128::from(copies[b as usize]);
                let rb = u128::from(prep.load[b as usize]) * u128::from(copies[a as usize]);
                ra.cmp(&rb).then(b.cmp(&a))
            });
        let Some(plane) = busiest else { break };
        copies[plane as usize] += 1;
        total += 1;
        step += 1;
        let new_bound = lower_bound(prep.problem, &copies);
        if step <= DENSE_DUPLICATION_STEPS || new_bound < bound {
            steps.push(copies.clone());
        }
        bound = bound.min(new_bound);
    }
    steps
}

/// Pass 1: the GA. Returns the best chromosome (ties: earliest in the population).
fn evolve(
    prep: &Prepared<'_>,
    inst: &InstanceSet,
    placement: Placement,
    params: &GaParams,
) -> Vec<u32> {
    let paths = &prep.problem.paths;
    let n = paths.len();
    let identity: Vec<u32> = (0..n as u32).collect();
    if n <= 1 {
        return identity;
    }
    let fitness_of = |order: &Vec<u32>| decode::decode(prep, inst, order, placement, |_, _, _| {});
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let population = params.population as usize;

    let mut by_rounds = identity.clone();
    by_rounds.sort_by_key(|&p| std::cmp::Reverse(paths[p as usize].rounds));
    let mut by_jobs = identity.clone();
    by_jobs.sort_by_key(|&p| {
        let path = &paths[p as usize];
        std::cmp::Reverse(path.rounds as u64 * path.planes.len() as u64)
    });
    let mut pop: Vec<Vec<u32>> = [identity.clone(), by_rounds, by_jobs]
        .into_iter()
        .take(population)
        .collect();
    while pop.len() < population {
        let mut order = identity.clone();
        order.shuffle(&mut rng);
        pop.push(order);
    }
    let mut fit: Vec<Fitness> = pop.par_iter().map(fitness_of).collect();

    let elite = params.elite as usize;
    for _ in 0..params.generations {
        let mut ranked: Vec<usize> = (0..pop.len()).collect();
        ranked.sort_by_key(|&i| (fit[i], i));
        let mut children = Vec::with_capacity(population - elite);
        while children.len() + elite < population {
            let a = tournament(&fit, params.tournament, &mut rng);
            let b = tournament(&fit, params.tournament, &mut rng);
            let mut child = if rng.random_bool(params.crossover_rate) {
                order_crossover(&pop[a], &pop[b], &mut rng)
            } else {
                pop[a].clone()
            };
            if rng.random_bool(params.mutation_rate) {
                mutate(&mut child, &mut rng);
            }
            children.push(child);
        }
        let child_fit: Vec<Fitness> = children.par_iter().map(fitness_of).collect();
        let mut next_pop: Vec<Vec<u32>> = ranked[..elite].iter().map(|&i| pop[i].clone()).collect();
        let mut next_fit: Vec<Fitness> = ranked[..elite].iter().map(|&i| fit[i]).collect();
        next_pop.extend(children);
        next_fit.extend(child_fit);
        pop = next_pop;
        fit = next_fit;
    }
    let best = (0..pop.len()).min_by_key(|&i| (fit[i], i)).unwrap_or(0);
    pop.swap_remove(best)
}

/// Index of the fittest of `size` uniformly drawn chromosomes.
fn tournament(fit: &[Fitness], size: u32, rng: &mut ChaCha8Rng) -> usize {
    (0..size)
        .map(|_| rng.random_range(0..fit.len()))
        .min_by_key(|&i| (fit[i], i))
        .unwrap_or(0)
}

/// OX1: a random segment of `a` kept in place, the other genes in `b`'s order from the
/// segment's end on, wrapping around.
fn order_crossover(a: &[u32], b: &[u32], rng: &mut ChaCha8Rng) -> Vec<u32> {
    let n = a.len();
    let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
    let (lo, hi) = (i.min(j), i.max(j) + 1);
    let mut taken = vec![false; n];
    let mut child = vec![0u32; n];
    for k in lo..hi {
        child[k] = a[k];
        taken[a[k] as usize] = true;
    }
    let mut at = hi % n;
    for k in 0..n {
        let gene = b[(hi + k) % n];
        if !taken[gene as usize] {
            child[at] = gene;
            at = (at + 1) % n;
        }
    }
    child
}

/// A few random swaps (1 + n/256) or one segment inversion, with equal odds.
fn mutate(order: &mut [u32], rng: &mut ChaCha8Rng) {
    let n = order.len();
    if rng.random_bool(0.5) {
        for _ in 0..1 + n / 256 {
            order.swap(rng.random_range(0..n), rng.random_range(0..n));
        }
    } else {
        let len = rng.random_range(1..=n.div_ceil(8).max(2).min(n));
        let start = rng.random_range(0..=n - len);
        order[start..start + len].reverse();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_crossover_gives_a_permutation() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let a: Vec<u32> = (0..50).collect();
        let mut b = a.clone();
        b.shuffle(&mut rng);
        for _ in 0..100 {
            let mut child = order_crossover(&a, &b, &mut rng);
            mutate(&mut child, &mut rng);
            let mut sorted = child.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, a);
        }
    }
}
