use bt_paths::{AllVisible, enumerate};
use bt_solve::*;
#[test]
fn scratch() {
    for line in std::fs::read_to_string("/tmp/jac.txt").unwrap().lines() {
        let v: Vec<usize> = line.split_whitespace().map(|x| x.parse().unwrap()).collect();
        let r = bt_study::room::generate(1, v[0], 10).unwrap();
        let scene = bt_study::embed::scene("x", &r.contours[v[1]], r.tx, r.rx).unwrap();
        let c = enumerate(&scene, 3, &AllVisible);
        let img = trace(&scene, &c, &Solver::Image, false);
        let sol = Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::Jacobi));
        let ipc = trace(&scene, &c, &sol, false);
        for p in &img.paths { if !ipc.paths.iter().any(|q| q.surfaces == p.surfaces) {
            let mut pts = vec![bt_geom::Vec3::ZERO; p.surfaces.len()]; let mut s = pts.clone();
            let o = solve_candidate(&scene, &p.surfaces, &sol, &mut pts, &mut s);
            let gap = p.points.windows(2).map(|w| w[0].distance(w[1])).fold(f64::INFINITY, f64::min);
            println!("{:?} {:?} min point gap {gap:.2e} m: {o:?}", v, p.surfaces);
        }}
    }
}
