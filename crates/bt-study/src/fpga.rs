//! A scene as the accelerator's input: the bridge from `bt-scene` to `bt-hls`, shared by
//! `beamtrace hls gen` and the living-room study.

use bt_hls::{HlsInput, PlaneSpec};
use bt_paths::{AllVisible, enumerate};
use bt_scene::{Scene, SurfaceId};

/// The HLS input of a scene: one plane per reflector (PE `bt_pe_<i>` for the `i`-th
/// reflector), every candidate path of order 1 to `max_order` (exhaustive enumeration with
/// the side test, as the paper computes *all* paths on the FPGA), starting points at the
/// polygon centroids; `threshold_lsb` in 1/256 mm, `max_rounds` the round cap. Also returns
/// the surface sequence of every input path (`input.paths[p]` is `sequences[p]`).
pub fn hls_input(
    scene: &Scene,
    max_order: usize,
    threshold_lsb: u32,
    max_rounds: u32,
) -> (HlsInput, Vec<Vec<SurfaceId>>) {
    let reflectors: Vec<SurfaceId> = scene.reflectors().collect();
    // Candidates consist of reflectors only, so every id has a plane index.
    let mut plane_of = vec![u32::MAX; scene.surfaces().len()];
    for (i, id) in reflectors.iter().enumerate() {
        plane_of[id.0 as usize] = i as u32;
    }
    let candidates = enumerate(scene, max_order, &AllVisible);
    let mut paths = Vec::new();
    let mut init_points = Vec::new();
    let mut sequences = Vec::new();
    for seq in candidates.iter() {
        if seq.is_empty() {
            continue;
        }
        debug_assert!(seq.iter().all(|id| plane_of[id.0 as usize] != u32::MAX));
        paths.push(seq.iter().map(|id| plane_of[id.0 as usize]).collect());
        init_points.push(
            seq.iter()
                .map(|id| scene.surface(*id).polygon.centroid().to_array())
                .collect(),
        );
        sequences.push(seq.to_vec());
    }
    let planes = reflectors
        .iter()
        .map(|id| {
            let s = scene.surface(*id);
            let p = s.polygon.plane();
            PlaneSpec {
                name: s.name.clone(),
                normal: p.normal.to_array(),
                offset_m: p.offset,
            }
        })
        .collect();
    let input = HlsInput {
        planes,
        paths,
        init_points,
        tx: scene.tx().to_array(),
        rx: scene.rx().to_array(),
        threshold_lsb,
        max_rounds,
        test_vectors: Vec::new(),
    };
    (input, sequences)
}
