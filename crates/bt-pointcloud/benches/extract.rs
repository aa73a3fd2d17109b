//! Plane extraction on a 1 000 000-point synthetic furnished room (seeded generator,
//! 5 mm noise). Run: `cargo bench -p bt-pointcloud --bench extract`.

use bt_pointcloud::{ExtractParams, extract_planes, sample_polygons};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;

#[path = "../tests/it/common/room.rs"]
mod room;

fn area(p: &[DVec3]) -> f64 {
    0.5 * (0..p.len())
        .fold(DVec3::ZERO, |a, i| a + p[i].cross(p[(i + 1) % p.len()]))
        .length()
}

fn bench(c: &mut Criterion) {
    let polys: Vec<Vec<DVec3>> = room::furnished_room().into_iter().map(|(_, p)| p).collect();
    let total: f64 = polys.iter().map(|p| area(p)).sum();
    let cloud = sample_polygons(&polys, 1.0e6 / total, 0.005, 1);
    let params = ExtractParams {
        seed: 1,
        ..ExtractParams::default()
    };
    let mut g = c.benchmark_group("extract_planes");
    g.sample_size(10);
    g.throughput(Throughput::Elements(cloud.len() as u64));
    g.bench_function("furnished_room_1M", |b| {
        b.iter(|| extract_planes(&cloud, &params).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
