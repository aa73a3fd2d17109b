//! Shapes shared by the unit tests of several modules.

use crate::{Polygon, Vec3};

/// The L of side 2 in the plane z = 0 (area 3); its notch around (1.5, 1.5) is outside.
pub(crate) fn l_shape() -> Polygon {
    Polygon::new(vec![
        Vec3::new(0., 0., 0.),
        Vec3::new(2., 0., 0.),
        Vec3::new(2., 1., 0.),
        Vec3::new(1., 1., 0.),
        Vec3::new(1., 2., 0.),
        Vec3::new(0., 2., 0.),
    ])
    .unwrap()
}
