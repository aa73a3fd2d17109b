//! Property tests: IPC (both update orders) finds exactly the image method's valid paths, to
//! 1e-9 m, and every reported path obeys the law of reflection and lies inside its polygons.

use crate::common::*;
use bt_solve::{Solver, UpdateOrder};
use proptest::prelude::*;

proptest! {
    #![proptest_config(random_scene_config())]

    #[test]
    fn ipc_equals_image_method_on_random_scenes(seed in 0u64..1_000_000, n in 1usize..6) {
        let scene = random_scene(seed, n);
        let reference = run(&scene, 3, Solver::Image);
        for order in [UpdateOrder::GaussSeidel, UpdateOrder::Jacobi] {
            let paths = run(&scene, 3, ipc(&scene, order));
            prop_assert_eq!(sequences(&paths), sequences(&reference), "{:?}", order);
            let d = max_point_distance(&paths, &reference);
            prop_assert!(d < 1e-9, "{:?}: points differ by {} m", order, d);
        }
        let tol = scene.length_tolerance();
        let direct = scene.tx().distance(scene.rx());
        for p in &reference {
            prop_assert!(reflection_law_error(&scene, p) < 1e-9);
            for (pt, id) in p.points.iter().zip(&p.surfaces) {
                prop_assert!(scene.surface(*id).polygon.contains(*pt, tol));
            }
            let mut v = vec![scene.tx()];
            v.extend_from_slice(&p.points);
            v.push(scene.rx());
            let length: f64 = v.windows(2).map(|w| w[0].distance(w[1])).sum();
            prop_assert!(length >= direct - 1e-12);
        }
    }
}

#[test]
fn builtin_living_room_ipc_equals_image_method() {
    let scene = bt_scene::builtin_scene("living-room", Default::default())
        .unwrap()
        .unwrap();
    let reference = run(&scene, 3, Solver::Image);
    assert!(reference.len() > 20);
    for order in [UpdateOrder::GaussSeidel, UpdateOrder::Jacobi] {
        let paths = run(&scene, 3, ipc(&scene, order));
        assert_eq!(sequences(&paths), sequences(&reference), "{order:?}");
        let d = max_point_distance(&paths, &reference);
        assert!(d < 1e-9, "{order:?}: {d}");
    }
}
