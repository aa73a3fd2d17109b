//! Paths as NumPy columns, derived from the serialization of [`PathReport`]: the column names
//! are the keys of `beamtrace trace --json`'s path objects, in the same order, so a new field
//! of the record is a new column without an edit here.
//!
//! The shape of each field comes from its value in one example record, serialized into a
//! typed value model ([`crate::record`]); the records themselves are serialized straight
//! into flat column buffers ([`crate::sink`], [`Batch`]). By shape: an integer → `int64`
//! (n,); a real → `float64` (n,), with −inf where the document has `null` (`gain_db` of a
//! path carrying no power); a struct of k reals (a direction) → `float64` (n, k) in field
//! order; the complex newtype → `complex128` (n,). A list per path (one item per
//! interaction) is flat over all interactions, cut per path at the interaction offsets: a
//! list of strings → `uint32` indices into the batch's texts; a list of reals → `float64`
//! (N,); a list of rows of w reals (points) → `float64` (N, w).
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
use crate::sink::{Buffer, Fields, Record, Texts};
use bt_beams::PathReport;
use numpy::ndarray::Array2;
use numpy::{Complex64, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;
use std::sync::{Mutex, OnceLock, PoisonError};

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

/// The names of the columns that `keep`, in the order of the JSON path objects.
fn names_where(keep: impl Fn(&Column) -> bool) -> PyResult<Vec<&'static str>> {
    let columns = table_of_example().map_err(crate::error)?;
    Ok(columns.iter().filter(|c| keep(c)).map(|c| c.name).collect())
}

/// Every column name a [`Batch`] can hold, in the order of the JSON path objects.
pub fn names() -> PyResult<Vec<&'static str>> {
    names_where(|_| true)
}

/// The columns of texts (interaction kinds, surface names): indices into a [`Batch`]'s texts.
pub fn texts() -> PyResult<Vec<&'static str>> {
    names_where(|c| c.shape == Shape::Texts)
}

/// The columns whose values are per interaction (aligned with `points`): flat in a
/// [`Batch`], split at its interaction offsets into one list or array per path.
pub fn per_interaction() -> PyResult<Vec<&'static str>> {
    names_where(|c| c.shape.ragged())
}

/// The columns the document may leave out (IPC's), present in a [`Batch`] only when every
/// path has them, and in one receiver's paths only when it has a path.
pub fn optional() -> PyResult<Vec<&'static str>> {
    names_where(|c| c.optional)
}

impl Shape {
    /// Whether a path has one value per interaction (a list), not one value.
    fn ragged(self) -> bool {
        matches!(self, Shape::Texts | Shape::Reals | Shape::Rows(_))
    }

    /// The leaves (integers, reals, texts) a path's value writes, for `k` interactions.
    fn leaves(self, k: usize) -> (usize, usize, usize) {
        match self {
            Shape::Int => (1, 0, 0),
            Shape::Real => (0, 1, 0),
            Shape::Complex => (0, 2, 0),
            Shape::Row(width) => (0, width, 0),
            Shape::Texts => (0, 0, k),
            Shape::Reals => (0, k, 0),
            Shape::Rows(width) => (0, k * width, 0),
        }
    }

    /// The leaves of one unit of a column: a path's (one value) or, for a per-interaction
    /// column, an interaction's.
    fn per_unit(self) -> (usize, usize, usize) {
        self.leaves(self.ragged() as usize)
    }

    /// The number of interactions a ragged value with these leaves holds (`None`: it is not
    /// a whole number of this shape's items).
    fn items(self, (ints, reals, texts): (usize, usize, usize)) -> Option<usize> {
        let k = match self {
            Shape::Texts => texts,
            Shape::Reals => reals,
            Shape::Rows(width) if reals % width == 0 => reals / width,
            _ => return None,
        };
        (self.leaves(k) == (ints, reals, texts)).then_some(k)
    }
}

/// The paths of many receivers as flat columns: every path's fields appended to one buffer
/// per column, with the paths of each receiver and the interactions of each path as offsets
/// (one set of arrays for the whole call, as Sionna RT's tensors are indexed by receiver,
/// instead of a dictionary of arrays per receiver). Filled without the GIL ([`Shards`] fill
/// one per thread); [`Batch::into_dict`] makes the arrays under it.
#[derive(Debug)]
pub struct Batch {
    columns: &'static [Column],
    names: Vec<&'static str>,
    buffers: Vec<Buffer>,
    /// How many paths wrote each column.
    written: Vec<usize>,
    texts: Texts,
    /// Receiver i's paths are rows `path_offsets[i]..path_offsets[i + 1]`.
    path_offsets: Vec<i64>,
    /// Path j's interactions are rows `interaction_offsets[j]..interaction_offsets[j + 1]`
    /// of the per-interaction columns.
    interaction_offsets: Vec<i64>,
    /// Whether each receiver was traced (false: skipped on error, no paths).
    traced: Vec<bool>,
    /// The first per-interaction column, whose items count a path's interactions.
    first_ragged: Option<usize>,
    /// Scratch of [`Batch::push`]: each column's leaf counts and writers before a receiver.
    before: Vec<((usize, usize, usize), usize)>,
}

impl Batch {
    /// No receiver yet; the error names a field of the example with no column shape.
    pub fn new() -> Result<Batch, String> {
        let columns = table_of_example()?;
        Ok(Batch {
            columns,
            names: columns.iter().map(|c| c.name).collect(),
            buffers: columns.iter().map(|_| Buffer::default()).collect(),
            written: vec![0; columns.len()],
            texts: Texts::default(),
            path_offsets: vec![0],
            interaction_offsets: vec![0],
            traced: Vec::new(),
            first_ragged: columns.iter().position(|c| c.shape.ragged()),
            before: Vec::with_capacity(columns.len()),
        })
    }

    /// A batch of one receiver with `paths`.
    pub fn of(paths: &[PathReport]) -> Result<Batch, String> {
        let mut batch = Batch::new()?;
        batch.push(paths)?;
        Ok(batch)
    }

    fn paths(&self) -> usize {
        self.interaction_offsets.len() - 1
    }

    /// No receiver, the memory kept.
    fn clear(&mut self) {
        for buffer in &mut self.buffers {
            buffer.clear();
        }
        self.written.fill(0);
        self.texts.clear();
        self.path_offsets.truncate(1);
        self.interaction_offsets.truncate(1);
        self.traced.clear();
    }

    /// The bytes its buffers and offsets hold (their capacity).
    fn bytes(&self) -> usize {
        let offsets = self.path_offsets.capacity() + self.interaction_offsets.capacity();
        let buffers: usize = self.buffers.iter().map(Buffer::bytes).sum();
        buffers + offsets * size_of::<i64>() + self.traced.capacity()
    }

    /// Appends a receiver with `paths`; the error names a field whose value does not have its
    /// column's shape, or a field the example does not write. The shapes are checked on the
    /// receiver's totals (each column's leaves against its writers and the receiver's
    /// interactions), not path by path: that check was a tenth of the columns' time.
    pub fn push(&mut self, paths: &[PathReport]) -> Result<(), String> {
        for (column, buffer) in self.columns.iter().zip(&mut self.buffers) {
            let (ints, reals, texts) = column.shape.leaves(0);
            buffer.ints.reserve(ints * paths.len());
            buffer.reals.reserve(reals * paths.len());
            buffer.texts.reserve(texts * paths.len());
        }
        self.before.clear();
        let counts = self.buffers.iter().map(Buffer::counts);
        self.before.extend(counts.zip(self.written.iter().copied()));
        let interactions = self.interaction_offsets[self.paths()];
        for path in paths {
            self.push_path(path)?;
        }
        let interactions = (self.interaction_offsets[self.paths()] - interactions) as usize;
        self.check_since(paths.len(), interactions)?;
        self.path_offsets.push(self.paths() as i64);
        self.traced.push(true);
        Ok(())
    }

    /// Appends a receiver that was not traced: no paths.
    pub fn push_untraced(&mut self) {
        self.path_offsets.push(self.paths() as i64);
        self.traced.push(false);
    }

    /// Appends one path, its interactions counted in the first per-interaction column.
    fn push_path(&mut self, path: &PathReport) -> Result<(), String> {
        let first = self.first_ragged;
        let before = first.map(|c| self.buffers[c].counts());
        let fields = Fields {
            names: &self.names,
            buffers: &mut self.buffers,
            written: &mut self.written,
            texts: &mut self.texts,
            next: 0,
        };
        path.serialize(Record(fields)).map_err(|e| e.to_string())?;
        let k = match (first, before) {
            (Some(c), Some(b)) => {
                let a = self.buffers[c].counts();
                let column = self.columns[c];
                let k = column.shape.items((a.0 - b.0, a.1 - b.1, a.2 - b.2));
                let name = column.name;
                k.ok_or_else(|| format!("a path's {name} differs in shape from the example's"))?
            }
            _ => 0,
        };
        let end = self.interaction_offsets[self.paths()] + k as i64;
        self.interaction_offsets.push(end);
        Ok(())
    }

    /// Whether the columns' leaves since [`Batch::push`]'s snapshot are what their shapes
    /// make of `paths` paths with `interactions` interactions in all; the error names the
    /// first column whose leaves are not.
    fn check_since(&self, paths: usize, interactions: usize) -> Result<(), String> {
        for (c, column) in self.columns.iter().enumerate() {
            let ((ints, reals, texts), written) = self.before[c];
            if self.written[c] - written != paths {
                // Some path lacks it: the column is left out of the call's result.
                continue;
            }
            let a = self.buffers[c].counts();
            let added = (a.0 - ints, a.1 - reals, a.2 - texts);
            let per = column.shape.per_unit();
            let units = if column.shape.ragged() {
                interactions
            } else {
                paths
            };
            if added != (per.0 * units, per.1 * units, per.2 * units) {
                let name = column.name;
                return Err(match column.shape.ragged() {
                    true => format!("a path's {name} is not aligned with its other lists"),
                    false => format!("a path's {name} differs in shape from the example's"),
                });
            }
        }
        Ok(())
    }

    /// Appends a receiver whose paths are `paths` of `shard`.
    fn append_rows(&mut self, shard: &Batch, paths: Range<usize>) {
        let at = |j: usize| shard.interaction_offsets[j];
        let mut end = self.interaction_offsets[self.paths()];
        for j in paths {
            end += at(j + 1) - at(j);
            self.interaction_offsets.push(end);
        }
        self.path_offsets.push(self.paths() as i64);
        self.traced.push(true);
    }

    /// The dictionary of column name → array: each column present when every path wrote it
    /// (an optional one also needs a path), flat over all receivers, a text column as
    /// `uint32` indices into `texts` (the distinct texts, a list of `str`: as Sionna RT gives
    /// interaction types and objects as integers); beside them `path_offsets` (m + 1,),
    /// `interaction_offsets` (n + 1,), `receiver` (n,) and `traced` (m,).
    pub fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let dict = PyDict::new(py);
        let n = self.paths();
        for ((column, buffer), written) in self.columns.iter().zip(self.buffers).zip(self.written) {
            if written != n || (n == 0 && column.optional) {
                continue;
            }
            dict.set_item(column.name, column_array(py, column.shape, buffer)?)?;
        }
        dict.set_item("texts", PyList::new(py, &self.texts.list)?)?;
        let receiver = (self.path_offsets.windows(2).enumerate())
            .flat_map(|(i, w)| std::iter::repeat_n(i as i64, (w[1] - w[0]) as usize));
        dict.set_item("receiver", PyArray1::from_iter(py, receiver))?;
        dict.set_item("path_offsets", PyArray1::from_vec(py, self.path_offsets))?;
        dict.set_item(
            "interaction_offsets",
            PyArray1::from_vec(py, self.interaction_offsets),
        )?;
        dict.set_item("traced", PyArray1::from_vec(py, self.traced))?;
        Ok(dict)
    }
}

/// Where a receiver's paths are in the shard that reported them ([`Shards::push`]).
#[derive(Debug, Clone)]
pub struct Rows {
    shard: usize,
    paths: Range<usize>,
}

/// One [`Batch`] per thread of a many-receiver call: each task appends its receiver's paths to
/// its thread's batch (growing, so no allocation per receiver), and [`Shards::gather`] copies
/// them into one batch in receiver order.
pub struct Shards(Vec<Mutex<Batch>>);

impl Shards {
    /// One empty batch per thread of the current rayon pool, and one for other threads.
    pub fn new() -> Result<Shards, String> {
        let count = rayon::current_num_threads() + 1;
        let shards = (0..count).map(|_| Batch::new().map(Mutex::new));
        Ok(Shards(shards.collect::<Result<_, _>>()?))
    }

    /// Appends a receiver with `paths` to the calling thread's shard ([`Batch::push`]'s
    /// errors); where they are.
    pub fn push(&self, paths: &[PathReport]) -> Result<Rows, String> {
        let others = self.0.len() - 1;
        let shard = rayon::current_thread_index().map_or(others, |i| i % others.max(1));
        let mut batch = self.0[shard].lock().unwrap_or_else(PoisonError::into_inner);
        let start = batch.paths();
        batch.push(paths)?;
        Ok(Rows {
            shard,
            paths: start..batch.paths(),
        })
    }

    /// Empties every shard, keeping the memory of those that hold at most `keep_bytes`: a
    /// call's shards reused by the next call need no fresh pages (each first touch of a page
    /// is a fault, ~1 µs here).
    pub fn clear(&mut self, keep_bytes: usize) -> Result<(), String> {
        for shard in &mut self.0 {
            let shard = shard.get_mut().unwrap_or_else(PoisonError::into_inner);
            match shard.bytes() <= keep_bytes {
                true => shard.clear(),
                false => *shard = Batch::new()?,
            }
        }
        Ok(())
    }

    /// The receivers `rows` (`None`: not traced), in order, in one batch. Each column is
    /// sized once and filled by its own task, on all cores when `parallel`: 1,000 receivers
    /// of the living room at order 3 make ~14 MB of columns, whose fresh pages fault in as
    /// they are written.
    pub fn gather(&mut self, rows: &[Option<Rows>], parallel: bool) -> Result<Batch, String> {
        let shards: Vec<&Batch> = (self.0.iter_mut())
            .map(|m| &*m.get_mut().unwrap_or_else(PoisonError::into_inner))
            .collect();
        let mut all = Batch::new()?;
        let mut codes = Vec::with_capacity(shards.len());
        for shard in &shards {
            let texts = shard.texts.list.iter().map(|text| all.texts.code(text));
            codes.push(
                texts
                    .collect::<Result<Vec<u32>, _>>()
                    .map_err(|e| e.to_string())?,
            );
        }
        for row in rows {
            match row {
                Some(row) => all.append_rows(shards[row.shard], row.paths.clone()),
                None => all.push_untraced(),
            }
        }
        // A column is there when every path wrote it: every path of every shard.
        let n = all.paths();
        for (c, written) in all.written.iter_mut().enumerate() {
            let complete = shards.iter().all(|s| s.written[c] == s.paths());
            *written = if complete { n } else { 0 };
        }
        let rows: Vec<&Rows> = rows.iter().flatten().collect();
        let (columns, written) = (all.columns, &all.written);
        let copy = |(c, buffer): (usize, &mut Buffer)| {
            if written[c] == n {
                *buffer = gathered(columns[c].shape, c, &shards, &rows, &codes);
            }
        };
        match parallel {
            true => all.buffers.par_iter_mut().enumerate().for_each(copy),
            false => all.buffers.iter_mut().enumerate().for_each(copy),
        }
        Ok(all)
    }
}

/// Column `c` (of `shape`) of `rows`, in order, their texts coded as `codes` says for each
/// shard.
fn gathered(
    shape: Shape,
    c: usize,
    shards: &[&Batch],
    rows: &[&Rows],
    codes: &[Vec<u32>],
) -> Buffer {
    let (ints, reals, texts) = shape.per_unit();
    let units = |row: &Rows| {
        let shard = &shards[row.shard];
        match shape.ragged() {
            true => {
                let at = |j: usize| shard.interaction_offsets[j] as usize;
                at(row.paths.start)..at(row.paths.end)
            }
            false => row.paths.clone(),
        }
    };
    let part = |row: &&Rows, width: usize| {
        let units = units(row);
        (
            &shards[row.shard].buffers[c],
            units.start * width..units.end * width,
        )
    };
    let ints = rows
        .iter()
        .map(|row| part(row, ints))
        .map(|(b, r)| b.ints[r].iter().copied());
    let reals = rows
        .iter()
        .map(|row| part(row, reals))
        .map(|(b, r)| b.reals[r].iter().copied());
    let texts = rows.iter().map(|row| {
        let (buffer, range) = part(row, texts);
        let codes = &codes[row.shard];
        buffer.texts[range].iter().map(move |&t| codes[t as usize])
    });
    Buffer {
        ints: joined(ints),
        reals: joined(reals),
        texts: joined(texts),
    }
}

/// The items of `pieces`, in order, in one vector sized once.
fn joined<T, I>(pieces: impl Iterator<Item = I> + Clone) -> Vec<T>
where
    I: ExactSizeIterator<Item = T>,
{
    let mut all = Vec::with_capacity(pieces.clone().map(|p| p.len()).sum());
    for piece in pieces {
        all.extend(piece);
    }
    all
}

/// One column's array (texts as their indices).
fn column_array(py: Python<'_>, shape: Shape, buffer: Buffer) -> PyResult<Bound<'_, PyAny>> {
    let rows = |reals: Vec<f64>, width: usize| {
        let rows = reals.len() / width;
        let array = Array2::from_shape_vec((rows, width), reals);
        array.map_err(|e| crate::error(format!("column rows: {e}")))
    };
    Ok(match shape {
        Shape::Int => PyArray1::from_vec(py, buffer.ints).into_any(),
        Shape::Real | Shape::Reals => PyArray1::from_vec(py, buffer.reals).into_any(),
        Shape::Complex => {
            let pairs = buffer.reals.chunks_exact(2);
            PyArray1::from_iter(py, pairs.map(|p| Complex64::new(p[0], p[1]))).into_any()
        }
        Shape::Row(width) | Shape::Rows(width) => {
            PyArray2::from_owned_array(py, rows(buffer.reals, width)?).into_any()
        }
        Shape::Texts => PyArray1::from_vec(py, buffer.texts).into_any(),
    })
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

    /// The names of the columns a batch of one receiver with `paths` presents.
    fn present(paths: &[PathReport]) -> Vec<&'static str> {
        let batch = Batch::of(paths).unwrap();
        let n = batch.paths();
        (batch.columns.iter().zip(&batch.written))
            .filter(|(c, written)| **written == n && !(n == 0 && c.optional))
            .map(|(c, _)| c.name)
            .collect()
    }

    #[test]
    fn no_path_gives_the_columns_every_path_has_empty() {
        let columns = table_of_example().unwrap();
        let always: Vec<&str> = columns
            .iter()
            .filter(|c| !c.optional)
            .map(|c| c.name)
            .collect();
        assert_eq!(present(&[]), always);
        // IPC's columns are optional; a field written as null is not.
        assert!(always.len() < columns.len());
        assert!(
            (columns.iter())
                .any(|c| !c.optional && c.shape == Shape::Real && may_read_without(c.name))
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
            assert!(present(std::slice::from_ref(&example)).contains(&column.name));
            let lacking = without(column.name);
            assert!(!present(&[example.clone(), lacking.clone()]).contains(&column.name));
            assert!(!present(&[lacking]).contains(&column.name));
        }
    }

    /// The example with `n` interactions (its first repeated), and `rank`.
    fn with_interactions(n: usize, rank: usize) -> PathReport {
        let mut path = PathReport::example();
        let k = path.points.len();
        assert!(k > 0);
        for _ in k..n {
            path.interactions.push(path.interactions[0]);
            path.surfaces.push(path.surfaces[0].clone());
            path.points.push(path.points[0]);
            path.incidence_deg.push(None);
        }
        path.interactions.truncate(n);
        path.surfaces.truncate(n);
        path.points.truncate(n);
        path.incidence_deg.truncate(n);
        path.order = n;
        path.rank = rank;
        path
    }

    #[test]
    fn batches_append_with_offsets_texts_and_nulls() {
        // Two shards (as two threads fill them), gathered in receiver order.
        let mut shards = Shards((0..2).map(|_| Mutex::new(Batch::new().unwrap())).collect());
        let on = |shard: usize, paths: &[PathReport]| {
            let mut batch = shards.0[shard].lock().unwrap();
            let start = batch.paths();
            batch.push(paths).unwrap();
            Some(Rows {
                shard,
                paths: start..batch.paths(),
            })
        };
        let last = on(1, &[with_interactions(3, 7)]);
        let first = on(0, &[with_interactions(2, 1), with_interactions(0, 2)]);
        let batch = shards.gather(&[first, None, last], true).unwrap();
        assert_eq!(batch.path_offsets, [0, 2, 2, 3]);
        assert_eq!(batch.interaction_offsets, [0, 2, 2, 5]);
        assert_eq!(batch.traced, [true, false, true]);
        assert_eq!(batch.written, vec![3; batch.columns.len()]);
        let column = |name| {
            let c = batch.names.iter().position(|n| *n == name).unwrap();
            (&batch.buffers[c], batch.columns[c].shape)
        };
        assert_eq!(column("rank").0.ints, [1, 2, 7]);
        let (points, shape) = column("points");
        assert_eq!((points.reals.len(), shape), (5 * 3, Shape::Rows(3)));
        // The texts of both batches share one table, and null is −inf.
        let surfaces = &column("surfaces").0.texts;
        assert_eq!(surfaces.len(), 5);
        assert!(surfaces.iter().all(|&t| t == surfaces[0]));
        assert_eq!(batch.texts.list.len(), 1 + 1, "{:?}", batch.texts.list);
        assert_eq!(column("incidence_deg").0.reals[1], f64::NEG_INFINITY);
    }

    #[test]
    fn a_path_whose_lists_disagree_is_an_error() {
        let mut path = with_interactions(2, 1);
        path.surfaces.pop();
        let error = Batch::of(&[path]).unwrap_err();
        assert!(error.contains("not aligned"), "{error}");
    }
}
