//! Property tests of the room generator: every room is a valid simple contour with the
//! requested number of edges at every time step, with TX and RX clear of the walls.

use bt_study::room::{self, Shape, is_clear, is_simple, is_valid};
use proptest::prelude::*;

fn shape_and_edges() -> impl Strategy<Value = (Shape, usize)> {
    prop_oneof![
        Just(Shape::L),
        Just(Shape::T),
        Just(Shape::U),
        Just(Shape::Convex)
    ]
    .prop_flat_map(|shape| {
        let (lo, hi) = shape.edge_range();
        (Just(shape), lo..=hi)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn rooms_are_simple_with_the_requested_edges(
        seed in any::<u64>(),
        index in 0usize..1000,
        (shape, edges) in shape_and_edges(),
    ) {
        let r = room::generate_shape(seed, index, shape, edges, 6).unwrap();
        prop_assert_eq!(r.contours.len(), 6);
        for (step, contour) in r.contours.iter().enumerate() {
            prop_assert_eq!(contour.len(), edges);
            prop_assert!(is_simple(contour), "step {} not simple: {:?}", step, contour);
            prop_assert!(is_valid(contour), "step {} invalid: {:?}", step, contour);
            prop_assert!(is_clear(contour, r.tx) && is_clear(contour, r.rx));
            // Only the moving vertex moves.
            for (i, (a, b)) in contour.iter().zip(&r.contours[0]).enumerate() {
                if i != r.moving_vertex {
                    prop_assert_eq!(a, b);
                }
            }
            // The 3-D embedding validates: bt-geom agrees the walls are fine polygons.
            if step == 0 || step == 5 {
                prop_assert!(bt_study::embed::scene("p", contour, r.tx, r.rx).is_ok());
            }
        }
    }
}

#[test]
fn the_vertex_really_moves() {
    let moved = (0..40)
        .filter(|&i| {
            let r = room::generate(3, i, 4).unwrap();
            r.contours[3][r.moving_vertex] != r.contours[0][r.moving_vertex]
        })
        .count();
    assert!(moved >= 36, "only {moved} of 40 rooms move");
}

#[test]
fn l_shapes_are_concave_and_convex_ones_are_not() {
    for i in 0..20 {
        let l = room::generate_shape(5, i, Shape::L, 4 + i % 3, 1).unwrap();
        let c = room::generate_shape(5, i, Shape::Convex, 4 + i % 7, 1).unwrap();
        let reflex = |p: &[bt_geom::Vec2]| {
            let n = p.len();
            (0..n)
                .filter(|&k| {
                    let (a, b, c) = (p[(k + n - 1) % n], p[k], p[(k + 1) % n]);
                    (b - a).perp_dot(c - b) < 0.0
                })
                .count()
        };
        assert_eq!(reflex(&l.contours[0]), 1);
        assert_eq!(reflex(&c.contours[0]), 0);
    }
}
