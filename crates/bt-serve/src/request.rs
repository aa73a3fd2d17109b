//! One request line, checked field by field so that every error names its field; the
//! request's `id` is read first, so even a request refused for another field is answered
//! with its `id`.

use crate::{Limits, ServeError};
use bt_geom::Vec3;
use bt_scene::PoseDesc;
use serde_json::{Map, Value};
use std::collections::BTreeMap;

/// The fields a request may have.
pub const FIELDS: [&str; 5] = ["id", "rx", "tx", "objects", "step"];

/// A checked request: positions in metres, world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// Echoed in the answer (`null` when absent).
    pub id: Value,
    /// The receivers to trace; `None`: the previous request's.
    pub rx: Option<Receivers>,
    /// A new transmitter; `None`: the previous one.
    pub tx: Option<Vec3>,
    /// New poses of objects by name, spelled as a dynamic scene's keyframes.
    pub objects: BTreeMap<String, PoseDesc>,
    /// Every object to its pose at this step of the scene file (before `objects`).
    pub step: Option<usize>,
}

impl Request {
    /// Whether the request moves the scene's geometry (`objects` or `step`).
    pub fn moves_objects(&self) -> bool {
        self.step.is_some() || !self.objects.is_empty()
    }
}

/// The receivers of a request: one (`[x, y, z]`, answered at the top level) or a list
/// (`[[x, y, z], ...]`, answered as `results`, one entry each).
#[derive(Debug, Clone, PartialEq)]
pub enum Receivers {
    /// `"rx": [x, y, z]`.
    One(Vec3),
    /// `"rx": [[x, y, z], ...]`.
    Many(Vec<Vec3>),
}

impl Receivers {
    /// The positions, in request order.
    pub fn positions(&self) -> &[Vec3] {
        match self {
            Receivers::One(p) => std::slice::from_ref(p),
            Receivers::Many(list) => list,
        }
    }
}

/// The `id` of a line if it is a JSON object with one (so an error about another field can
/// still echo it), else `null`.
pub fn id_of(value: &Value) -> Value {
    value.get("id").cloned().unwrap_or(Value::Null)
}

/// Parse one request line (JSON) and check every field against `limits`.
pub fn parse(line: &[u8], limits: &Limits) -> Result<Request, (Value, ServeError)> {
    let value: Value = serde_json::from_slice(line).map_err(|e| {
        let message = format!("not valid JSON: {e}");
        (Value::Null, ServeError::request("request", message))
    })?;
    let id = id_of(&value);
    from_value(value, limits).map_err(|e| (id, e))
}

/// A request from its JSON value.
pub fn from_value(value: Value, limits: &Limits) -> Result<Request, ServeError> {
    let Value::Object(map) = value else {
        let message = format!("expected a JSON object, got {}", kind(&value));
        return Err(ServeError::request("request", message));
    };
    if let Some(unknown) = map.keys().find(|k| !FIELDS.contains(&k.as_str())) {
        let message = format!(
            "unknown field (a request has {})",
            FIELDS.map(|f| format!("\"{f}\"")).join(", ")
        );
        return Err(ServeError::request(shown_key(unknown), message));
    }
    Ok(Request {
        id: map.get("id").cloned().unwrap_or(Value::Null),
        rx: map.get("rx").map(|v| receivers(v, limits)).transpose()?,
        tx: map.get("tx").map(|v| position(v, "tx")).transpose()?,
        objects: objects(&map)?,
        step: map.get("step").map(step).transpose()?,
    })
}

/// `"rx"`: one position or a non-empty list of at most `limits.max_receivers`.
fn receivers(value: &Value, limits: &Limits) -> Result<Receivers, ServeError> {
    let Value::Array(items) = value else {
        return Err(ServeError::request(
            "rx",
            format!(
                "expected [x, y, z] or [[x, y, z], ...], got {}",
                kind(value)
            ),
        ));
    };
    if !items.first().is_some_and(Value::is_array) {
        return position(value, "rx").map(Receivers::One);
    }
    if items.len() > limits.max_receivers {
        let message = format!(
            "{} receivers, more than the budget of {} per request; split the request",
            items.len(),
            limits.max_receivers
        );
        return Err(ServeError::request("rx", message));
    }
    let list = items
        .iter()
        .enumerate()
        .map(|(i, p)| position(p, &format!("rx[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Receivers::Many(list))
}

/// A position `[x, y, z]` of three finite numbers, metres.
fn position(value: &Value, field: &str) -> Result<Vec3, ServeError> {
    let wrong = || {
        let message = format!("expected [x, y, z] (three numbers), got {}", kind(value));
        ServeError::request(field, message)
    };
    let Value::Array(items) = value else {
        return Err(wrong());
    };
    if items.len() != 3 {
        return Err(wrong());
    }
    let mut p = [0.0; 3];
    for (slot, item) in p.iter_mut().zip(items) {
        *slot = item.as_f64().filter(|x| x.is_finite()).ok_or_else(wrong)?;
    }
    Ok(Vec3::from_array(p))
}

/// `"objects"`: poses by object name, each read by the scene file's own pose type.
fn objects(map: &Map<String, Value>) -> Result<BTreeMap<String, PoseDesc>, ServeError> {
    let Some(value) = map.get("objects") else {
        return Ok(BTreeMap::new());
    };
    let Value::Object(poses) = value else {
        let message = format!("expected {{\"NAME\": pose, ...}}, got {}", kind(value));
        return Err(ServeError::request("objects", message));
    };
    let mut out = BTreeMap::new();
    for (name, pose) in poses {
        let field = format!("objects.{}", shown_key(name));
        let pose: PoseDesc = serde_json::from_value(pose.clone())
            .map_err(|e| ServeError::request(field, format!("{e}")))?;
        out.insert(name.clone(), pose);
    }
    Ok(out)
}

/// `"step"`: a step index.
fn step(value: &Value) -> Result<usize, ServeError> {
    value
        .as_u64()
        .and_then(|k| usize::try_from(k).ok())
        .ok_or_else(|| {
            let message = format!("expected a step number (0, 1, ...), got {}", kind(value));
            ServeError::request("step", message)
        })
}

/// A short description of a JSON value for messages: its kind, and small values themselves.
fn kind(value: &Value) -> String {
    match value {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the string {}", bt_scene::name::shown(s)),
        Value::Array(a) => format!("an array of {} items", a.len()),
        Value::Object(_) => "an object".into(),
    }
}

/// A key from the request as a field name in a message: escaped and cut like every name
/// from input (`bt_scene::name::shown`).
fn shown_key(key: &str) -> String {
    bt_scene::name::shown(key).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(line: &str) -> (Value, String) {
        let (id, e) = parse(line.as_bytes(), &Limits::default()).unwrap_err();
        (id, e.to_string())
    }

    #[test]
    fn every_field_parses() {
        let line = r#"{"id": "a", "rx": [[1, 2, 3], [4, 5, 6]], "tx": [0, 0.5, 1],
            "objects": {"door": {"angle_deg": 30}, "person": {"offset": [1, 0, 0]}}, "step": 2}"#;
        let r = parse(line.as_bytes(), &Limits::default()).unwrap();
        assert_eq!(r.id, Value::from("a"));
        let rx = r.rx.unwrap();
        assert_eq!(
            rx.positions(),
            [Vec3::new(1., 2., 3.), Vec3::new(4., 5., 6.)]
        );
        assert_eq!(r.tx, Some(Vec3::new(0.0, 0.5, 1.0)));
        assert_eq!(r.objects["door"].angle_deg, Some(30.0));
        assert_eq!(r.objects["person"].offset, Some([1.0, 0.0, 0.0]));
        assert_eq!(r.step, Some(2));
        let r = parse(b"{\"rx\": [1, 2, 3]}", &Limits::default()).unwrap();
        assert_eq!(r.rx, Some(Receivers::One(Vec3::new(1., 2., 3.))));
        assert_eq!(r.id, Value::Null);
    }

    #[test]
    fn each_error_names_its_field_and_keeps_the_id() {
        let cases = [
            (r#"{"id": 7, "rx": [1, 2]}"#, "rx: expected [x, y, z]"),
            (r#"{"id": 7, "rx": "here"}"#, "rx: expected [x, y, z] or"),
            (
                r#"{"id": 7, "rx": [[1, 2, 3], [1, "a", 3]]}"#,
                "rx[1]: expected",
            ),
            (r#"{"id": 7, "rx": [1e999, 0, 0]}"#, "not valid JSON"),
            (r#"{"id": 7, "tx": [1, 2, null]}"#, "tx: expected [x, y, z]"),
            (r#"{"id": 7, "rxx": [1, 2, 3]}"#, "rxx: unknown field"),
            (r#"{"id": 7, "step": -1}"#, "step: expected a step number"),
            (r#"{"id": 7, "objects": []}"#, "objects: expected {"),
            (
                r#"{"id": 7, "objects": {"door": {"angle": 3}}}"#,
                "objects.door: unknown field `angle`",
            ),
            (
                r#"{"id": 7, "objects": {"door": {"offset": [1, 2]}}}"#,
                "objects.door: invalid length 2",
            ),
            ("[1, 2, 3]", "request: expected a JSON object, got an array"),
            ("{\"id\": 7,", "request: not valid JSON"),
        ];
        for (line, needle) in cases {
            let (id, text) = refused(line);
            assert!(text.contains(needle), "{line}: {text}");
            let expected = match text.starts_with("request:") {
                true => Value::Null,
                false => Value::from(7),
            };
            assert_eq!(id, expected, "{line}");
        }
    }

    #[test]
    fn too_many_receivers_are_refused_before_they_are_read() {
        let limits = Limits {
            max_receivers: 2,
            ..Limits::default()
        };
        let line = br#"{"rx": [[1, 2, 3], [1, 2, 3], [1, 2, "not even read"]]}"#;
        let (_, e) = parse(line, &limits).unwrap_err();
        let text = e.to_string();
        assert!(
            text.starts_with("rx: 3 receivers, more than the budget of 2"),
            "{text}"
        );
    }
}
