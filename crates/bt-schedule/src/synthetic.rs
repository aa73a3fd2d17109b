//! Seeded synthetic problems for tests and benchmarks.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{PathJob, Problem};

/// A problem shaped like the paper's living-room scene: `num_paths` paths of order 1-3
/// (uniform), 5-60 rounds each (uniform), planes drawn with weights `1 / sqrt(plane + 1)`
/// (big walls, floor and ceiling take part in many more paths than furniture), never the same
/// plane at two consecutive points. A-B-A paths occur. With one plane every path has order 1.
/// Deterministic in `seed`.
pub fn living_room(seed: u64, num_planes: u32, num_paths: u32) -> Problem {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cumulative: Vec<f64> = (0..num_planes)
        .scan(0.0, |acc, q| {
            *acc += 1.0 / f64::from(q + 1).sqrt();
            Some(*acc)
        })
        .collect();
    let total = cumulative.last().copied().unwrap_or(0.0);
    let draw = |rng: &mut ChaCha8Rng| {
        let x = rng.random_range(0.0..total);
        cumulative
            .partition_point(|&c| c <= x)
            .min(num_planes as usize - 1) as u32
    };
    let paths = (0..if num_planes == 0 { 0 } else { num_paths })
        .map(|_| {
            let order = if num_planes == 1 {
                1
            } else {
                rng.random_range(1..=3)
            };
            let mut planes: Vec<u32> = Vec::with_capacity(order);
            while planes.len() < order {
                let q = draw(&mut rng);
                if planes.last() != Some(&q) {
                    planes.push(q);
                }
            }
            PathJob::jacobi(planes, rng.random_range(5..=60))
        })
        .collect();
    Problem { num_planes, paths }
}
