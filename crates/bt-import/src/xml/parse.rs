//! Mitsuba XML text to the intermediate [`XmlScene`]: no files are opened here, so the parser
//! can be fuzzed. Every error names the element and its line.

use super::transform::parse_transform;
use super::{
    MAX_XML_BSDFS, MAX_XML_NODES, MAX_XML_SHAPES, MAX_XML_SUBSTITUTION, MeshKind, Primitive,
    XmlBsdf, XmlPos, XmlRadio, XmlScene, XmlShape,
};
use crate::ImportError;
use bt_geom::Real;
use glam::DMat4;
use roxmltree::{Document, Node, ParsingOptions};
use std::borrow::Cow;
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet};

/// Elements that only matter for rendering images: skipped with one warning each.
const RENDERING_ONLY: [&str; 6] = [
    "integrator",
    "sensor",
    "emitter",
    "film",
    "sampler",
    "rfilter",
];

/// Properties of the radio bsdfs that describe diffuse scattering or display colour, which
/// beamtrace (specular paths only) does not model: accepted and ignored.
const IGNORED_RADIO_PROPERTIES: [&str; 7] = [
    "color",
    "scattering_coefficient",
    "xpd_coefficient",
    "scattering_pattern",
    "alpha_r",
    "alpha_i",
    "lambda_",
];

/// Sionna RT's thickness when a radio bsdf names none, metres.
pub const SIONNA_DEFAULT_THICKNESS_M: Real = 0.1;

/// Parsing context: the text and its line starts (for positions), the file name, the
/// `<default>`s, the bsdf ids seen, and the bytes substituted for `$parameters` so far against
/// their budget.
pub(super) struct Ctx<'a> {
    text: &'a str,
    line_starts: Vec<usize>,
    file: &'a str,
    defaults: BTreeMap<String, String>,
    bsdf_ids: BTreeSet<String>,
    substituted: Cell<u64>,
    max_substituted: u64,
}

impl Ctx<'_> {
    /// An error at `node`'s start: `file: line L, column C: message`.
    pub(super) fn error(&self, node: Node<'_, '_>, message: impl Into<String>) -> ImportError {
        let pos = self.pos(node);
        ImportError::Xml {
            path: self.file.to_string(),
            line: pos.line,
            column: pos.column,
            message: message.into(),
        }
    }

    /// The line of `node`, for messages that outlive the parse.
    fn line(&self, node: Node<'_, '_>) -> u32 {
        self.pos(node).line
    }

    /// Where `node` starts, in O(log lines + line length) (roxmltree's own `text_pos_at`
    /// scans from the start of the text: quadratic over a file of many shapes).
    fn pos(&self, node: Node<'_, '_>) -> XmlPos {
        let offset = node.range().start.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset);
        let start = self.line_starts[line - 1];
        let column = self
            .text
            .get(start..offset)
            .map_or(offset - start, |t| t.chars().count());
        XmlPos {
            line: u32::try_from(line).unwrap_or(u32::MAX),
            column: u32::try_from(column + 1).unwrap_or(u32::MAX),
        }
    }

    /// Attribute `name` with `$param` substituted from the `<default>`s (`\$` is a literal `$`);
    /// borrowed from the document when there is nothing to substitute (nearly always: one
    /// `String` per attribute was a tenth of the parse of a city's XML, on the calling thread).
    pub(super) fn attr<'n>(
        &self,
        node: Node<'n, '_>,
        name: &str,
    ) -> Result<Option<Cow<'n, str>>, ImportError> {
        let Some(raw) = node.attribute(name) else {
            return Ok(None);
        };
        if !raw.contains('$') {
            return Ok(Some(Cow::Borrowed(raw)));
        }
        let mut out = String::with_capacity(raw.len());
        let mut rest = raw;
        while let Some(at) = rest.find('$') {
            if rest[..at].ends_with('\\') {
                out.push_str(&rest[..at - 1]);
                out.push('$');
                rest = &rest[at + 1..];
                continue;
            }
            out.push_str(&rest[..at]);
            let tail = &rest[at + 1..];
            let len = tail
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(tail.len());
            let key = &tail[..len];
            let value = self.defaults.get(key).ok_or_else(|| {
                self.error(
                    node,
                    format!("<{}> {name}=: undefined parameter ${key}", tag(node)),
                )
            })?;
            self.charge(node, name, key, value.len())?;
            out.push_str(value);
            rest = &tail[len..];
        }
        out.push_str(rest);
        Ok(Some(Cow::Owned(out)))
    }

    /// Count `bytes` substituted for `$key` in attribute `name` against the budget, before they
    /// are copied: `<default>`s that expand each other grow exponentially (ten levels of ten
    /// references make 10^10 copies from a 1 kB file).
    fn charge(
        &self,
        node: Node<'_, '_>,
        name: &str,
        key: &str,
        bytes: usize,
    ) -> Result<(), ImportError> {
        let total = self.substituted.get().saturating_add(bytes as u64);
        MAX_XML_SUBSTITUTION
            .with_limit(self.max_substituted)
            .check(total)
            .map_err(|e| self.error(node, format!("<{}> {name}=: ${key}: {e}", tag(node))))?;
        self.substituted.set(total);
        Ok(())
    }

    /// A required attribute.
    pub(super) fn required<'n>(
        &self,
        node: Node<'n, '_>,
        name: &str,
    ) -> Result<Cow<'n, str>, ImportError> {
        self.attr(node, name)?.ok_or_else(|| {
            self.error(
                node,
                format!("<{}> needs a {name}=\"...\" attribute", tag(node)),
            )
        })
    }

    /// A finite number from attribute `name`.
    pub(super) fn number(&self, node: Node<'_, '_>, name: &str) -> Result<Real, ImportError> {
        let text = self.required(node, name)?;
        parse_number(&text).ok_or_else(|| {
            self.error(
                node,
                format!(
                    "<{}> {name}=\"{}\" is not a finite number",
                    tag(node),
                    bt_scene::name::shown(&text)
                ),
            )
        })
    }
}

/// A finite decimal number.
pub(super) fn parse_number(text: &str) -> Option<Real> {
    text.trim().parse::<Real>().ok().filter(|v| v.is_finite())
}

/// The element's tag name.
pub(super) fn tag<'a>(node: Node<'a, '_>) -> &'a str {
    node.tag_name().name()
}

/// Child elements (text and comments skipped).
pub(super) fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(|n| n.is_element())
}

/// Parse Mitsuba XML `text` (named `file` in errors) into the intermediate form. Checks the
/// element count ([`MAX_XML_NODES`]), the shape and bsdf counts, every reference, and the bytes
/// substituted for `$parameters` ([`MAX_XML_SUBSTITUTION`], default limit).
pub fn parse_xml(text: &str, file: &str) -> Result<XmlScene, ImportError> {
    parse_xml_with(text, file, MAX_XML_SUBSTITUTION.limit)
}

/// [`parse_xml`] with at most `max_substituted` bytes substituted for `$parameters` in all
/// (CLI `--max-xml-substitution`).
pub fn parse_xml_with(
    text: &str,
    file: &str,
    max_substituted: u64,
) -> Result<XmlScene, ImportError> {
    let options = ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_XML_NODES,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, options).map_err(|e| {
        let pos = e.pos();
        ImportError::Xml {
            path: file.to_string(),
            line: pos.row,
            column: pos.col,
            message: format!("not well-formed XML: {e}"),
        }
    })?;
    let line_starts = std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect();
    let mut ctx = Ctx {
        text,
        line_starts,
        file,
        defaults: BTreeMap::new(),
        bsdf_ids: BTreeSet::new(),
        substituted: Cell::new(0),
        max_substituted,
    };
    let root = doc.root_element();
    if tag(root) != "scene" {
        return Err(ctx.error(
            root,
            format!("the root element is <{}>, expected <scene>", tag(root)),
        ));
    }
    for node in elements(root).filter(|n| tag(*n) == "default") {
        let name = ctx.required(node, "name")?;
        let value = ctx.required(node, "value")?;
        ctx.defaults
            .entry(name.into_owned())
            .or_insert(value.into_owned());
    }
    let mut scene = XmlScene::default();
    let mut skipped: BTreeMap<String, u32> = BTreeMap::new();
    for node in elements(root) {
        match tag(node) {
            "default" => {}
            "bsdf" => {
                let id = ctx.required(node, "id")?.into_owned();
                add_bsdf(&mut ctx, &mut scene, node, id)?;
            }
            "shape" => {
                if scene.shapes.len() >= MAX_XML_SHAPES {
                    return Err(ctx.error(
                        node,
                        format!("more than {MAX_XML_SHAPES} shapes: scene too large"),
                    ));
                }
                let shape = parse_shape(&mut ctx, &mut scene, node)?;
                scene.shapes.push(shape);
            }
            t if RENDERING_ONLY.contains(&t) => {
                skipped.entry(t.to_string()).or_insert(ctx.line(node));
            }
            other => {
                return Err(ctx.error(node, format!("unsupported element <{other}> in <scene>")));
            }
        }
    }
    for (element, line) in skipped {
        scene.warnings.push(format!(
            "{file}: line {line}: <{element}> ignored (rendering only, no effect on radio paths)"
        ));
    }
    check_refs(&ctx, &scene)?;
    Ok(scene)
}

fn add_bsdf(
    ctx: &mut Ctx<'_>,
    scene: &mut XmlScene,
    node: Node<'_, '_>,
    id: String,
) -> Result<(), ImportError> {
    if scene.bsdfs.len() >= MAX_XML_BSDFS {
        return Err(ctx.error(
            node,
            format!("more than {MAX_XML_BSDFS} bsdfs: scene too large"),
        ));
    }
    if !ctx.bsdf_ids.insert(id.clone()) {
        return Err(ctx.error(
            node,
            format!(
                "<bsdf id=\"{}\"> is defined twice",
                bt_scene::name::shown(&id)
            ),
        ));
    }
    let radio = parse_bsdf(ctx, node)?;
    scene.bsdfs.push(XmlBsdf {
        id,
        radio,
        line: ctx.line(node),
    });
    Ok(())
}

/// A bsdf's radio meaning: Sionna's radio materials by their properties, any other (visual)
/// Mitsuba bsdf by its id (Sionna 0.x: `mat-itu_concrete`, `itu_glass`), contents ignored.
fn parse_bsdf(ctx: &Ctx<'_>, node: Node<'_, '_>) -> Result<XmlRadio, ImportError> {
    let kind = ctx.required(node, "type")?;
    let radio = kind == "itu-radio-material" || kind == "radio-material";
    if !radio {
        return Ok(XmlRadio::Visual {
            kind: kind.into_owned(),
        });
    }
    let mut itu: Option<String> = None;
    let mut thickness = None;
    let mut permittivity = None;
    let mut conductivity = None;
    for child in elements(node) {
        let name = ctx.required(child, "name")?;
        match (tag(child), name.as_ref(), kind.as_ref()) {
            ("string", "type", "itu-radio-material") => {
                itu = Some(ctx.required(child, "value")?.into_owned());
            }
            ("float", "thickness", _) => thickness = Some(ctx.number(child, "value")?),
            ("float", "relative_permittivity", "radio-material") => {
                permittivity = Some(ctx.number(child, "value")?);
            }
            ("float", "conductivity", "radio-material") => {
                conductivity = Some(ctx.number(child, "value")?);
            }
            (_, n, _) if IGNORED_RADIO_PROPERTIES.contains(&n) => {}
            (t, n, k) => {
                return Err(ctx.error(
                    child,
                    format!(
                        "unsupported property <{t} name=\"{}\"> in <bsdf type=\"{k}\">",
                        bt_scene::name::shown(n)
                    ),
                ));
            }
        }
    }
    let thickness_m = thickness.unwrap_or(SIONNA_DEFAULT_THICKNESS_M);
    let invalid =
        |e: bt_channel::ChannelError| ctx.error(node, format!("<bsdf type=\"{kind}\">: {e}"));
    if kind == "radio-material" {
        let relative_permittivity = permittivity.unwrap_or(1.0);
        let conductivity = conductivity.unwrap_or(0.0);
        bt_channel::RadioMaterial::custom(relative_permittivity, conductivity, Some(thickness_m))
            .map_err(invalid)?;
        return Ok(XmlRadio::Custom {
            relative_permittivity,
            conductivity,
            thickness_m,
        });
    }
    let itu = itu.ok_or_else(|| {
        ctx.error(
            node,
            "<bsdf type=\"itu-radio-material\"> needs <string name=\"type\" value=\"...\"/>",
        )
    })?;
    bt_channel::RadioMaterial::itu(&itu, Some(thickness_m)).map_err(invalid)?;
    Ok(XmlRadio::Itu {
        name: itu,
        thickness_m,
    })
}

fn parse_shape(
    ctx: &mut Ctx<'_>,
    scene: &mut XmlScene,
    node: Node<'_, '_>,
) -> Result<XmlShape, ImportError> {
    let kind = match ctx.required(node, "type")?.as_ref() {
        "ply" => MeshKind::Ply,
        "obj" => MeshKind::Obj,
        "rectangle" => MeshKind::Primitive(Primitive::Rectangle),
        "cube" => MeshKind::Primitive(Primitive::Cube),
        other => {
            return Err(ctx.error(
                node,
                format!(
                    "<shape type=\"{}\"> is not supported (only ply and obj meshes, rectangle and cube)",
                    bt_scene::name::shown(other)
                ),
            ));
        }
    };
    let name = match ctx.attr(node, "id")? {
        Some(id) => id.into_owned(),
        None => format!("shape-{}", scene.shapes.len()),
    };
    let mut shape = XmlShape {
        name,
        kind,
        filename: None,
        bsdf: None,
        to_world: DMat4::IDENTITY,
        at: ctx.pos(node),
    };
    for child in elements(node) {
        shape_child(ctx, scene, &mut shape, child)?;
    }
    if !matches!(kind, MeshKind::Primitive(_)) && shape.filename.is_none() {
        return Err(ctx.error(
            node,
            "<shape> needs <string name=\"filename\" value=\"...\"/>",
        ));
    }
    Ok(shape)
}

fn shape_child(
    ctx: &mut Ctx<'_>,
    scene: &mut XmlScene,
    shape: &mut XmlShape,
    child: Node<'_, '_>,
) -> Result<(), ImportError> {
    match tag(child) {
        "string" if ctx.required(child, "name")? == "filename" => {
            if let MeshKind::Primitive(_) = shape.kind {
                return Err(ctx.error(
                    child,
                    "a <shape type=\"rectangle\"> or <shape type=\"cube\"> has no filename",
                ));
            }
            let value = ctx.required(child, "value")?;
            if value.is_empty() {
                return Err(ctx.error(child, "<string name=\"filename\"> is empty"));
            }
            shape.filename = Some(value.into_owned());
        }
        "boolean" => {
            let name = ctx.required(child, "name")?;
            let value = ctx.required(child, "value")?;
            if !matches!(
                name.as_ref(),
                "face_normals" | "flip_normals" | "flip_tex_coords"
            ) {
                return Err(ctx.error(
                    child,
                    format!(
                        "unsupported property <boolean name=\"{}\"> in <shape>",
                        bt_scene::name::shown(&name)
                    ),
                ));
            }
            if !matches!(value.as_ref(), "true" | "false") {
                return Err(ctx.error(
                    child,
                    format!(
                        "<boolean name=\"{}\"> value must be true or false",
                        bt_scene::name::shown(&name)
                    ),
                ));
            }
        }
        "ref" => {
            if let Some(name) = ctx.attr(child, "name")?
                && name != "bsdf"
            {
                return Err(ctx.error(
                    child,
                    format!(
                        "<ref name=\"{}\"> is not supported in <shape> (only bsdf)",
                        bt_scene::name::shown(&name)
                    ),
                ));
            }
            let id = ctx.required(child, "id")?.into_owned();
            set_bsdf(ctx, shape, id, child)?;
        }
        "bsdf" => {
            let id = match ctx.attr(child, "id")? {
                Some(id) => id.into_owned(),
                None => format!("{}.bsdf", shape.name),
            };
            add_bsdf(ctx, scene, child, id.clone())?;
            set_bsdf(ctx, shape, id, child)?;
        }
        "transform" => {
            let name = ctx.required(child, "name")?;
            if name != "to_world" {
                return Err(ctx.error(
                    child,
                    format!(
                        "<transform name=\"{}\"> is not supported in <shape> (only to_world)",
                        bt_scene::name::shown(&name)
                    ),
                ));
            }
            shape.to_world = parse_transform(ctx, child)?;
        }
        "emitter" => {}
        other => {
            let name = child.attribute("name").unwrap_or("");
            return Err(ctx.error(
                child,
                format!(
                    "unsupported element <{other} name=\"{}\"> in <shape>",
                    bt_scene::name::shown(name)
                ),
            ));
        }
    }
    Ok(())
}

/// Record the shape's bsdf: one per shape.
fn set_bsdf(
    ctx: &Ctx<'_>,
    shape: &mut XmlShape,
    id: String,
    at: Node<'_, '_>,
) -> Result<(), ImportError> {
    if shape.bsdf.is_some() {
        return Err(ctx.error(at, "<shape> has more than one bsdf"));
    }
    shape.bsdf = Some((id, ctx.pos(at)));
    Ok(())
}

/// Every shape's bsdf reference names a bsdf of the file.
fn check_refs(ctx: &Ctx<'_>, scene: &XmlScene) -> Result<(), ImportError> {
    for shape in &scene.shapes {
        if let Some((id, at)) = &shape.bsdf
            && !ctx.bsdf_ids.contains(id)
        {
            return Err(ImportError::Xml {
                path: ctx.file.to_string(),
                line: at.line,
                column: at.column,
                message: format!(
                    "<shape id=\"{}\"> refers to bsdf \"{}\", which the file does not define",
                    bt_scene::name::shown(&shape.name),
                    bt_scene::name::shown(id)
                ),
            });
        }
    }
    Ok(())
}
