//! Paths as NumPy columns, derived from the serialization of [`PathReport`]: the column names
//! are the keys of `beamtrace trace --json`'s path objects, in the same order, so a new field
//! of the record is a new column without an edit here.
//!
//! Each record is serialized into a typed value model ([`crate::record`]) and every field
//! becomes a column by the *shape* of its value: an integer → `int64` (n,); a real →
//! `float64` (n,), with −inf where the document has `null` (`gain_db` of a path carrying no
//! power); a struct of k reals (a direction) → `float64` (n, k) in field order; the complex
//! newtype → `complex128` (n,); a list of strings → n lists of `str`; a list of reals → n
//! `float64` (k,) arrays; a list of rows of w reals (points) → n `float64` (k, w) arrays.
//!
//! The shapes must not depend on the paths at hand (a line of sight has no points, yet its
//! `points` is a (0, 3) array; no path at all still gives every column, empty), so they come
//! from one representative record, [`PathReport::example`]: one reflection, every optional
//! field set. A record rather than the type through serde's field visitor: the visitor gives
//! the names but not the shapes, and tracing shapes through `Deserialize` would read `gain`
//! as the pair its deserializer takes, not as a complex number.
//!
//! Which columns are optional (IPC's `iterations`, `residual_m`: present only when every path
//! has them and there is a path) is asked of the document itself: a key is optional when a
//! record read back without it writes it without it again (`skip_serializing_if`), whereas a
//! `null` field (`gain_db`) is written back as `null` and its column is always there.

use crate::record::{Value, to_value};
use bt_beams::PathReport;
use numpy::ndarray::Array2;
use numpy::{Complex64, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use std::sync::OnceLock;

/// How the values of one field become a column.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    /// An integer per path: `int64` (n,).
    Int,
    /// A real per path, `null` as −inf: `float64` (n,).
    Real,
    /// A complex number per path: `complex128` (n,).
    Complex,
    /// A struct of this many reals per path: `float64` (n, width).
    Row(usize),
    /// A list of strings per path: n lists of `str`.
    Texts,
    /// A list of reals per path: n `float64` arrays (k,).
    Reals,
    /// A list of rows of this many reals per path: n `float64` arrays (k, width).
    Rows(usize),
}

/// One column: a key of the path objects and how its values become an array.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    name: &'static str,
    shape: Shape,
    /// The document may leave the key out (`skip_serializing_if`).
    optional: bool,
}

/// The columns, derived once from [`PathReport::example`]; the error names the field whose
/// value has no column shape.
fn table_of_example() -> Result<&'static [Column], String> {
    static TABLE: OnceLock<Result<Vec<Column>, String>> = OnceLock::new();
    TABLE
        .get_or_init(derive_table)
        .as_deref()
        .map_err(String::clone)
}

fn derive_table() -> Result<Vec<Column>, String> {
    let example = PathReport::example();
    let fields = fields_of(&example)?;
    let json = serde_json::to_value(&example).map_err(|e| e.to_string())?;
    fields
        .into_iter()
        .map(|(name, value)| {
            let shape = shape_of(&value).ok_or_else(|| {
                format!("field {name} of PathReport::example() has no column shape: {value:?}")
            })?;
            let optional = may_omit(&json, name);
            Ok(Column {
                name,
                shape,
                optional,
            })
        })
        .collect()
}

/// The fields `path` writes, in order.
fn fields_of(path: &PathReport) -> Result<Vec<(&'static str, Value)>, String> {
    match to_value(path).map_err(|e| e.to_string())? {
        Value::Struct(fields) => Ok(fields),
        other => Err(format!(
            "a path record serializes as {other:?}, not a struct"
        )),
    }
}

/// Whether the document may lack `key`: the record `json` read back without it writes it
/// without it again.
fn may_omit(json: &serde_json::Value, key: &str) -> bool {
    let mut without = json.clone();
    if let Some(object) = without.as_object_mut() {
        object.remove(key);
    }
    serde_json::from_value::<PathReport>(without)
        .and_then(serde_json::to_value)
        .is_ok_and(|written| written.get(key).is_none())
}

/// The column shape of an example value (lists need an element to show it).
fn shape_of(value: &Value) -> Option<Shape> {
    Some(match value {
        Value::Int(_) => Shape::Int,
        Value::Real(_) => Shape::Real,
        Value::Complex(..) => Shape::Complex,
        Value::Struct(fields) => Shape::Row(width(fields.iter().map(|(_, v)| v))?),
        Value::Seq(items) => match items.first()? {
            Value::Text(_) => Shape::Texts,
            Value::Real(_) => Shape::Reals,
            Value::Seq(row) => Shape::Rows(width(row.iter())?),
            Value::Struct(row) => Shape::Rows(width(row.iter().map(|(_, v)| v))?),
            _ => return None,
        },
        Value::Null | Value::Text(_) => return None,
    })
}

/// The number of `values` when they are reals and there is one.
fn width<'a>(mut values: impl ExactSizeIterator<Item = &'a Value>) -> Option<usize> {
    let n = values.len();
    (n > 0 && values.all(|v| matches!(v, Value::Real(_)))).then_some(n)
}

/// Every column name `to_dict` can produce, in the order of the JSON path objects.
pub fn names() -> PyResult<Vec<&'static str>> {
    let columns = table_of_example().map_err(crate::error)?;
    Ok(columns.iter().map(|c| c.name).collect())
}

/// The paths as a dictionary of column name → NumPy array (or list of arrays / of names).
pub fn to_dict<'py>(py: Python<'py>, paths: &[PathReport]) -> PyResult<Bound<'py, PyDict>> {
    dict_of(
        py,
        present(paths).map_err(crate::error)?,
        &mut Texts::default(),
    )
}

/// The columns of some paths before they become arrays ([`cells_of`]): plain Rust values, made
/// without the GIL (in parallel, by `trace_many`).
pub struct Cells(Vec<(Column, Vec<Value>)>);

/// The columns of `paths` as [`Cells`]; the error names a field the example does not write.
pub fn cells_of(paths: &[PathReport]) -> Result<Cells, String> {
    present(paths).map(Cells)
}

/// The dictionary of column name → array of [`Cells`] (the GIL's part of [`to_dict`]), its
/// names and kinds taken from `texts` (one cache for the dictionaries of one call).
pub fn cells_dict<'py>(
    py: Python<'py>,
    cells: Cells,
    texts: &mut Texts<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    dict_of(py, cells.0, texts)
}

/// The Python strings made for the text columns (surface names, interaction kinds), by text:
/// a receiver's paths name the same few surfaces and kinds hundreds of times, and each
/// string is made once per call and shared (strings are immutable, so sharing is invisible).
#[derive(Default)]
pub struct Texts<'py>(std::collections::HashMap<String, Bound<'py, PyString>>);

impl<'py> Texts<'py> {
    /// The string `text`, made on first use.
    fn get(&mut self, py: Python<'py>, text: &str) -> Bound<'py, PyString> {
        if let Some(made) = self.0.get(text) {
            return made.clone();
        }
        let made = PyString::new(py, text);
        self.0.insert(text.to_owned(), made.clone());
        made
    }
}

/// The dictionary of column name → array of each column's values.
fn dict_of<'py>(
    py: Python<'py>,
    columns: Vec<(Column, Vec<Value>)>,
    texts: &mut Texts<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (column, cells) in columns {
        let value = column_value(py, column.shape, &cells, texts).ok_or_else(|| {
            let name = column.name;
            crate::error(format!(
                "a path's {name} differs in shape from the example's"
            ))
        })??;
        dict.set_item(column.name, value)?;
    }
    Ok(dict)
}

/// The columns of `paths`, each with one value per path, in order: an optional column when
/// every path has it and there is a path, the others always.
fn present(paths: &[PathReport]) -> Result<Vec<(Column, Vec<Value>)>, String> {
    let columns = table_of_example()?;
    let mut cells: Vec<Vec<Value>> = vec![Vec::with_capacity(paths.len()); columns.len()];
    for path in paths {
        let mut fields = fields_of(path)?.into_iter().peekable();
        for (column, cells) in columns.iter().zip(&mut cells) {
            if let Some((_, value)) = fields.next_if(|(name, _)| *name == column.name) {
                cells.push(value);
            }
        }
        if let Some((name, _)) = fields.next() {
            return Err(format!(
                "path field {name} is not written by PathReport::example()"
            ));
        }
    }
    Ok(columns
        .iter()
        .zip(cells)
        .filter(|(column, cells)| {
            cells.len() == paths.len() && !(paths.is_empty() && column.optional)
        })
        .map(|(column, cells)| (*column, cells))
        .collect())
}

/// One column's array (or list); `None` when a value does not have the column's shape.
fn column_value<'py>(
    py: Python<'py>,
    shape: Shape,
    cells: &[Value],
    texts: &mut Texts<'py>,
) -> Option<PyResult<Bound<'py, PyAny>>> {
    Some(Ok(match shape {
        // Every array is copied into memory NumPy allocates: one Python object, where an
        // array over a Rust vector is two (the array and the owner of its memory).
        Shape::Int => PyArray1::from_slice(py, &collect(cells, int)?).into_any(),
        Shape::Real => PyArray1::from_slice(py, &collect(cells, real)?).into_any(),
        Shape::Complex => PyArray1::from_slice(py, &collect(cells, complex)?).into_any(),
        Shape::Row(width) => PyArray2::from_array(py, &rows(cells, width)?).into_any(),
        Shape::Texts => {
            let mut lists = Vec::with_capacity(cells.len());
            for cell in cells {
                let strings: Option<Vec<_>> = (items(cell)?.iter())
                    .map(|t| Some(texts.get(py, text(t)?)))
                    .collect();
                lists.push(PyList::new(py, strings?));
            }
            let lists = lists.into_iter().collect::<PyResult<Vec<_>>>();
            return Some(
                lists
                    .and_then(|lists| PyList::new(py, lists))
                    .map(Bound::into_any),
            );
        }
        Shape::Reals => {
            let arrays = collect(cells, |v| collect(items(v)?, real))?;
            let arrays = arrays.iter().map(|a| PyArray1::from_slice(py, a));
            return Some(PyList::new(py, arrays).map(Bound::into_any));
        }
        Shape::Rows(width) => {
            let arrays = collect(cells, |v| rows(items(v)?, width))?;
            let arrays = arrays.iter().map(|a| PyArray2::from_array(py, a));
            return Some(PyList::new(py, arrays).map(Bound::into_any));
        }
    }))
}

/// `f` of every value, or `None` when one has another shape.
fn collect<T>(cells: &[Value], f: impl Fn(&Value) -> Option<T>) -> Option<Vec<T>> {
    cells.iter().map(f).collect()
}

fn int(value: &Value) -> Option<i64> {
    match value {
        Value::Int(i) => Some(*i),
        _ => None,
    }
}

/// A real; `null` (a path carrying no power has no dB) as −inf.
fn real(value: &Value) -> Option<f64> {
    match value {
        Value::Real(x) => Some(*x),
        Value::Null => Some(f64::NEG_INFINITY),
        _ => None,
    }
}

fn complex(value: &Value) -> Option<Complex64> {
    match value {
        Value::Complex(re, im) => Some(Complex64::new(*re, *im)),
        _ => None,
    }
}

fn text(value: &Value) -> Option<&str> {
    match value {
        Value::Text(s) => Some(s),
        _ => None,
    }
}

fn items(value: &Value) -> Option<&[Value]> {
    match value {
        Value::Seq(items) => Some(items),
        _ => None,
    }
}

/// Rows of `width` reals (each a struct of reals or a list of reals) as an array (k, width).
fn rows(cells: &[Value], width: usize) -> Option<Array2<f64>> {
    let mut flat = Vec::with_capacity(cells.len() * width);
    for cell in cells {
        let start = flat.len();
        match cell {
            Value::Struct(fields) => flat.extend(fields.iter().map(|(_, v)| real(v))),
            Value::Seq(items) => flat.extend(items.iter().map(real)),
            _ => return None,
        }
        if flat.len() - start != width {
            return None;
        }
    }
    let flat = flat.into_iter().collect::<Option<Vec<f64>>>()?;
    Array2::from_shape_vec((cells.len(), width), flat).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example_json() -> serde_json::Value {
        serde_json::to_value(PathReport::example()).unwrap()
    }

    /// The example read back from its JSON without `key`.
    fn without(key: &str) -> PathReport {
        let mut json = example_json();
        json.as_object_mut().unwrap().remove(key);
        serde_json::from_value(json).unwrap()
    }

    #[test]
    fn every_key_of_the_example_is_a_column_in_json_order() {
        let names = names().unwrap();
        let json = serde_json::to_string(&PathReport::example()).unwrap();
        let at: Vec<usize> = names
            .iter()
            .map(|name| json.find(&format!("\"{name}\":")).unwrap())
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{names:?} in {json}");
        assert_eq!(names.len(), example_json().as_object().unwrap().len());
    }

    #[test]
    fn no_path_gives_the_columns_every_path_has_empty() {
        let columns = table_of_example().unwrap();
        let present = present(&[]).unwrap();
        let always: Vec<Column> = columns.iter().filter(|c| !c.optional).copied().collect();
        assert_eq!(present.iter().map(|(c, _)| *c).collect::<Vec<_>>(), always);
        assert!(present.iter().all(|(_, cells)| cells.is_empty()));
        // IPC's columns are optional; a field written as null is not.
        assert!(always.len() < columns.len());
        assert!(
            always
                .iter()
                .any(|c| c.shape == Shape::Real && may_read_without(c.name))
        );
    }

    fn may_read_without(key: &str) -> bool {
        let mut json = example_json();
        json.as_object_mut().unwrap().remove(key);
        serde_json::from_value::<PathReport>(json).is_ok()
    }

    #[test]
    fn an_optional_column_needs_every_path() {
        let example = PathReport::example();
        for column in table_of_example().unwrap().iter().filter(|c| c.optional) {
            let names = |paths: &[PathReport]| -> Vec<&str> {
                present(paths)
                    .unwrap()
                    .iter()
                    .map(|(c, _)| c.name)
                    .collect()
            };
            assert!(names(std::slice::from_ref(&example)).contains(&column.name));
            let lacking = without(column.name);
            assert!(!names(&[example.clone(), lacking.clone()]).contains(&column.name));
            assert!(!names(&[lacking]).contains(&column.name));
        }
    }

    #[test]
    fn null_is_minus_infinity_in_real_columns() {
        assert_eq!(real(&Value::Null), Some(f64::NEG_INFINITY));
        assert_eq!(int(&Value::Null), None);
    }

    #[test]
    fn rows_keep_their_width_when_there_are_none() {
        let row = |a: f64| Value::Seq(vec![Value::Real(a), Value::Real(a + 1.0)]);
        let a = rows(&[row(1.0), row(3.0)], 2).unwrap();
        assert_eq!((a.shape(), a[[1, 0]]), (&[2, 2][..], 3.0));
        assert_eq!(rows(&[], 3).unwrap().shape(), &[0, 3]);
        assert!(rows(&[row(1.0)], 3).is_none());
    }
}
