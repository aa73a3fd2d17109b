//! A seeded synthetic city: box buildings on a ground plane, written as a triangle mesh and
//! imported like any OBJ (welding, coplanar merging), so it exercises the mesh pipeline and
//! the candidate generator at city scale. `builtin:city` is 3,900 buildings (39,002 triangles,
//! about 19,500 surfaces over 2.3 km × 2.3 km) with TX on a 10 m street mast and RX at handset height 180 m down the same street.

use bt_geom::{Real, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write;

/// Shape of a synthetic city.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CityOptions {
    /// Seed of the layout.
    pub seed: u64,
    /// Lots per side of the square grid (one building per lot).
    pub lots: usize,
    /// Lot size, metres.
    pub lot_m: Real,
    /// Every `block` lots a street of `street_m` metres runs between blocks.
    pub block: usize,
    /// Street width, metres.
    pub street_m: Real,
}

impl Default for CityOptions {
    /// The built-in city: 63 × 63 lots of 30 m, a 20 m street every 3 lots (3,969 lots).
    fn default() -> Self {
        CityOptions {
            seed: 1,
            lots: 63,
            lot_m: 30.0,
            block: 3,
            street_m: 20.0,
        }
    }
}

impl CityOptions {
    /// South-west corner of lot `(i, j)`, metres.
    fn lot_origin(&self, i: usize, j: usize) -> (Real, Real) {
        let at = |k: usize| k as Real * self.lot_m + (k / self.block) as Real * self.street_m;
        (at(i), at(j))
    }

    /// Side length of the whole city, metres.
    pub fn size_m(&self) -> Real {
        let (x, _) = self.lot_origin(self.lots, 0);
        x
    }

    /// A point in the middle of the street east of block column `bi`, at `y` and height `z`.
    pub fn street_point(&self, bi: usize, y: Real, z: Real) -> Vec3 {
        let (x, _) = self.lot_origin((bi + 1) * self.block, 0);
        Vec3::new(x - self.street_m * 0.5, y, z)
    }
}

/// The city as Wavefront OBJ text: a ground quad (2 triangles) and, per lot, a box building of
/// random footprint and height with 4 walls and a roof (10 triangles; no floor, it would lie
/// in the ground).
pub fn city_obj(options: &CityOptions) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut obj = String::with_capacity(options.lots * options.lots * 400);
    let size = options.size_m();
    let margin = 50.0;
    let _ = writeln!(obj, "# beamtrace synthetic city, seed {}", options.seed);
    let mut v = 0usize;
    let mut quad = |obj: &mut String, corners: [[Real; 3]; 4]| {
        for c in corners {
            let _ = writeln!(obj, "v {} {} {}", c[0], c[1], c[2]);
        }
        let _ = writeln!(obj, "f {} {} {}", v + 1, v + 2, v + 3);
        let _ = writeln!(obj, "f {} {} {}", v + 1, v + 3, v + 4);
        v += 4;
    };
    let (lo, hi) = (-margin, size + margin);
    quad(
        &mut obj,
        [[lo, lo, 0.], [hi, lo, 0.], [hi, hi, 0.], [lo, hi, 0.]],
    );
    for i in 0..options.lots {
        for j in 0..options.lots {
            let (x0, y0) = options.lot_origin(i, j);
            let w = rng.random_range(0.45..0.85) * options.lot_m;
            let d = rng.random_range(0.45..0.85) * options.lot_m;
            let (ox, oy) = (
                rng.random_range(0.05..0.95 - w / options.lot_m) * options.lot_m,
                rng.random_range(0.05..0.95 - d / options.lot_m) * options.lot_m,
            );
            let h = rng.random_range(6.0..45.0);
            let (a, b) = (x0 + ox, y0 + oy);
            let (c, e) = (a + w, b + d);
            quad(&mut obj, [[a, b, 0.], [c, b, 0.], [c, b, h], [a, b, h]]);
            quad(&mut obj, [[c, b, 0.], [c, e, 0.], [c, e, h], [c, b, h]]);
            quad(&mut obj, [[c, e, 0.], [a, e, 0.], [a, e, h], [c, e, h]]);
            quad(&mut obj, [[a, e, 0.], [a, b, 0.], [a, b, h], [a, e, h]]);
            quad(&mut obj, [[a, b, h], [c, b, h], [c, e, h], [a, e, h]]);
        }
    }
    obj
}

/// The city as a validated scene (mesh import with the default merge options; `terminals` must
/// give TX and RX).
pub fn city_scene(
    options: &CityOptions,
    terminals: bt_scene::Terminals,
) -> Result<bt_scene::Scene, crate::ImportError> {
    let obj = city_obj(options);
    let source = "builtin:city";
    let load = crate::LoadOptions {
        terminals,
        ..crate::LoadOptions::default()
    };
    let import = crate::mesh::read_obj(obj.as_bytes(), Some(source), &load.merge).map_err(|e| {
        crate::ImportError::Parse {
            path: source.to_string(),
            message: e.to_string(),
        }
    })?;
    crate::mesh::scene::from_mesh(import, "city", source, &load).map(|loaded| loaded.scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_city_has_about_forty_thousand_triangles() {
        let o = CityOptions::default();
        let text = city_obj(&o);
        let faces = text.lines().filter(|l| l.starts_with("f ")).count();
        assert_eq!(faces, 2 + 63 * 63 * 10);
        assert_eq!(text, city_obj(&o), "deterministic");
        assert!((o.size_m() - (63.0 * 30.0 + 21.0 * 20.0)).abs() < 1e-9);
    }
}
