//! Paths as NumPy columns: one table says which field of [`PathReport`] becomes which array.
//!
//! A new per-path field of `bt_beams::report` (say a complex `gain`) is one line in
//! [`COLUMNS`]; the Python `Paths` class exposes every column the dictionary carries.

use bt_beams::{Direction, PathReport};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// How one field of a path becomes (part of) a NumPy column.
enum Column {
    /// A count per path: `int64`, shape (n,).
    Count(fn(&PathReport) -> usize),
    /// A real number per path: `float64`, shape (n,).
    Real(fn(&PathReport) -> f64),
    /// A complex number per path: `complex128`, shape (n,).
    Complex(fn(&PathReport) -> numpy::Complex64),
    /// A direction per path: `float64`, shape (n, 2), columns azimuth and elevation (degrees).
    Direction(fn(&PathReport) -> Direction),
    /// A count every path has or none has (IPC's rounds): `int64` (n,), absent otherwise.
    OptionalCount(fn(&PathReport) -> Option<u32>),
    /// A real every path has or none has (IPC's residual): `float64` (n,), absent otherwise.
    OptionalReal(fn(&PathReport) -> Option<f64>),
    /// One value per reflection: a list of n `float64` arrays of shape (k,).
    PerReflection(fn(&PathReport) -> &[f64]),
    /// One point per reflection: a list of n `float64` arrays of shape (k, 3), metres.
    Points(fn(&PathReport) -> &[[f64; 3]]),
    /// One name per reflection: a list of n lists of `str`.
    Names(fn(&PathReport) -> &[String]),
}

/// Every column of `Paths`, in the order of `beamtrace trace --json`'s path objects.
const COLUMNS: &[(&str, Column)] = &[
    ("rank", Column::Count(|p| p.rank)),
    ("order", Column::Count(|p| p.order)),
    ("surfaces", Column::Names(|p| &p.surfaces)),
    ("points", Column::Points(|p| &p.points)),
    ("length_m", Column::Real(|p| p.length_m)),
    ("delay_s", Column::Real(|p| p.delay_s)),
    ("aod_deg", Column::Direction(|p| p.aod_deg)),
    ("aoa_deg", Column::Direction(|p| p.aoa_deg)),
    ("incidence_deg", Column::PerReflection(|p| &p.incidence_deg)),
    ("free_space_loss_db", Column::Real(|p| p.free_space_loss_db)),
    ("reflection_loss_db", Column::Real(|p| p.reflection_loss_db)),
    ("loss_db", Column::Real(|p| p.loss_db)),
    // The channel (docs/channel.md): complex gain without the propagation phase; dB and dBm
    // are −inf where the JSON has null (a path that carries no power).
    (
        "gain",
        Column::Complex(|p| numpy::Complex64::new(p.gain.re, p.gain.im)),
    ),
    (
        "gain_db",
        Column::Real(|p| p.gain_db.unwrap_or(f64::NEG_INFINITY)),
    ),
    (
        "power_dbm",
        Column::Real(|p| p.power_dbm.unwrap_or(f64::NEG_INFINITY)),
    ),
    ("iterations", Column::OptionalCount(|p| p.iterations)),
    ("residual_m", Column::OptionalReal(|p| p.residual_m)),
];

/// The names of the columns `to_dict` can produce (for the type stub test).
pub fn names() -> Vec<&'static str> {
    COLUMNS.iter().map(|(name, _)| *name).collect()
}

/// The paths as a dictionary of column name → NumPy array (or list of arrays / names).
pub fn to_dict<'py>(py: Python<'py>, paths: &[PathReport]) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (name, column) in COLUMNS {
        if let Some(value) = column_value(py, column, paths)? {
            dict.set_item(*name, value)?;
        }
    }
    Ok(dict)
}

fn column_value<'py>(
    py: Python<'py>,
    column: &Column,
    paths: &[PathReport],
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let array = |v: Vec<f64>| PyArray1::from_vec(py, v).into_any();
    Ok(Some(match column {
        Column::Count(f) => {
            PyArray1::from_vec(py, paths.iter().map(|p| f(p) as i64).collect()).into_any()
        }
        Column::Real(f) => array(paths.iter().map(f).collect()),
        Column::Complex(f) => PyArray1::from_vec(py, paths.iter().map(f).collect()).into_any(),
        Column::Direction(f) => {
            let flat = paths
                .iter()
                .flat_map(|p| {
                    let d = f(p);
                    [d.azimuth, d.elevation]
                })
                .collect();
            rows(flat, 2).into_pyarray(py).into_any()
        }
        Column::OptionalCount(f) => match paths.iter().map(f).collect::<Option<Vec<_>>>() {
            Some(v) if !paths.is_empty() => {
                PyArray1::from_vec(py, v.into_iter().map(i64::from).collect()).into_any()
            }
            _ => return Ok(None),
        },
        Column::OptionalReal(f) => match paths.iter().map(f).collect::<Option<Vec<_>>>() {
            Some(v) if !paths.is_empty() => array(v),
            _ => return Ok(None),
        },
        Column::PerReflection(f) => {
            PyList::new(py, paths.iter().map(|p| array(f(p).to_vec())))?.into_any()
        }
        Column::Points(f) => PyList::new(
            py,
            paths.iter().map(|p| {
                let flat = f(p).iter().flatten().copied().collect();
                rows(flat, 3).into_pyarray(py)
            }),
        )?
        .into_any(),
        Column::Names(f) => PyList::new(py, paths.iter().map(|p| f(p).to_vec()))?.into_any(),
    }))
}

/// `flat` as rows of `width` values (its length is a multiple of `width` by construction).
fn rows(flat: Vec<f64>, width: usize) -> Array2<f64> {
    let n = flat.len() / width;
    Array2::from_shape_vec((n, width), flat).expect("length is rows × width")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_names_are_unique() {
        let mut names = names();
        let n = names.len();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), n);
    }

    #[test]
    fn rows_reshape_row_major() {
        let a = rows(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3);
        assert_eq!(a.shape(), &[2, 3]);
        assert_eq!(a[[1, 0]], 4.0);
    }
}
