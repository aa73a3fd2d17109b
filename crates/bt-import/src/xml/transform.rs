//! `<transform name="to_world">`: translate, rotate, scale, matrix and lookat, composed in document
//! order as Mitsuba does (each operation multiplies from the left: the first listed acts first).

use super::parse::{Ctx, elements, parse_number, tag};
use crate::ImportError;
use bt_geom::{Real, Vec3};
use glam::{DMat3, DMat4};
use roxmltree::Node;

/// Smallest |det| of the linear part accepted: a transform that flattens space would turn
/// every polygon into a zero-area one.
const MIN_ABS_DETERMINANT: Real = 1e-12;

/// The affine map of a `<transform>` element (metres to metres).
pub(super) fn parse_transform(ctx: &Ctx<'_>, node: Node<'_, '_>) -> Result<DMat4, ImportError> {
    let mut m = DMat4::IDENTITY;
    for op in elements(node) {
        let step = match tag(op) {
            "translate" => DMat4::from_translation(vector(ctx, op, 0.0)?),
            "scale" => DMat4::from_scale(vector(ctx, op, 1.0)?),
            "rotate" => rotation(ctx, op)?,
            "matrix" => matrix(ctx, op)?,
            "lookat" => look_at(ctx, op)?,
            other => {
                return Err(ctx.error(
                    op,
                    format!("unsupported element <{other}> in <transform> (translate, rotate, scale, matrix, lookat)"),
                ));
            }
        };
        m = step * m;
        if !m.is_finite() {
            return Err(ctx.error(op, "the transform is no longer finite after this element"));
        }
    }
    let det = DMat3::from_mat4(m).determinant();
    if det.abs() < MIN_ABS_DETERMINANT || !det.is_finite() {
        return Err(ctx.error(
            node,
            format!("<transform> is singular (determinant {det:e}): it would flatten every shape"),
        ));
    }
    Ok(m)
}

/// `x`/`y`/`z` attributes (missing ones `default`), or `value` with one number (all three) or
/// three; commas or spaces separate.
fn vector(ctx: &Ctx<'_>, op: Node<'_, '_>, default: Real) -> Result<Vec3, ImportError> {
    if let Some(value) = ctx.attr(op, "value")? {
        if ["x", "y", "z"].iter().any(|a| op.attribute(*a).is_some()) {
            return Err(ctx.error(op, format!("<{}> mixes value= with x/y/z", tag(op))));
        }
        let v = numbers(ctx, op, &value)?;
        return match v.as_slice() {
            [s] => Ok(Vec3::splat(*s)),
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(ctx.error(
                op,
                format!("<{}> value= needs 1 or 3 numbers, got {}", tag(op), v.len()),
            )),
        };
    }
    let mut out = [default; 3];
    for (slot, name) in out.iter_mut().zip(["x", "y", "z"]) {
        if op.attribute(name).is_some() {
            *slot = ctx.number(op, name)?;
        }
    }
    Ok(Vec3::from_array(out))
}

/// `<rotate x=".." y=".." z=".." angle="degrees"/>`: right-handed about the axis.
fn rotation(ctx: &Ctx<'_>, op: Node<'_, '_>) -> Result<DMat4, ImportError> {
    let axis = vector(ctx, op, 0.0)?;
    let angle_deg = ctx.number(op, "angle")?;
    let len = axis.length();
    if !(len.is_finite() && len > 0.0) {
        return Err(ctx.error(op, "<rotate> axis must be a finite non-zero vector"));
    }
    Ok(DMat4::from_axis_angle(axis / len, angle_deg.to_radians()))
}

/// `<matrix value="16 numbers"/>` (or 9 for the linear part), row by row as Mitsuba reads it.
fn matrix(ctx: &Ctx<'_>, op: Node<'_, '_>) -> Result<DMat4, ImportError> {
    let value = ctx.required(op, "value")?;
    let v = numbers(ctx, op, &value)?;
    let n = match v.len() {
        16 => 4,
        9 => 3,
        k => {
            return Err(ctx.error(op, format!("<matrix> needs 16 or 9 numbers, got {k}")));
        }
    };
    let mut rows = DMat4::IDENTITY.transpose().to_cols_array_2d();
    for (i, row) in rows.iter_mut().enumerate().take(n) {
        row[..n].copy_from_slice(&v[i * n..(i + 1) * n]);
    }
    // `rows` holds rows; glam stores columns.
    let m = DMat4::from_cols_array_2d(&rows).transpose();
    if n == 4 && m.row(3) != glam::DVec4::new(0.0, 0.0, 0.0, 1.0) {
        return Err(ctx.error(
            op,
            "<matrix> last row must be 0 0 0 1 (projective maps are not supported)",
        ));
    }
    Ok(m)
}

/// `<lookat origin="x, y, z" target="x, y, z" up="x, y, z"/>`, as Mitsuba builds it: the
/// object frame's `+z` turned towards `target`, its `+y` as near `up` as that allows (its `+x`
/// is `up × z`), and its origin moved to `origin` (metres).
fn look_at(ctx: &Ctx<'_>, op: Node<'_, '_>) -> Result<DMat4, ImportError> {
    let point = |name: &str| -> Result<Vec3, ImportError> {
        let text = ctx.required(op, name)?;
        match numbers(ctx, op, &text)?.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            v => Err(ctx.error(
                op,
                format!("<lookat> {name}= needs 3 numbers, got {}", v.len()),
            )),
        }
    };
    let (origin, target, up) = (point("origin")?, point("target")?, point("up")?);
    let dir = (target - origin).normalize_or_zero();
    let left = up.cross(dir).normalize_or_zero();
    if dir == Vec3::ZERO || left == Vec3::ZERO {
        return Err(ctx.error(
            op,
            "<lookat> needs a target apart from the origin and an up not along target - origin",
        ));
    }
    let new_up = dir.cross(left);
    Ok(DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

fn numbers(ctx: &Ctx<'_>, op: Node<'_, '_>, text: &str) -> Result<Vec<Real>, ImportError> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| {
            parse_number(t).ok_or_else(|| {
                ctx.error(
                    op,
                    format!(
                        "<{}>: \"{}\" is not a finite number",
                        tag(op),
                        bt_scene::name::shown(t)
                    ),
                )
            })
        })
        .collect()
}
