//! Sewing patterns in the GarmentCode JSON specification: panels (2D outlines made of straight,
//! Bézier and arc edges, placed in 3D) and stitches (pairs of edges sewn together).
//! See docs/src/patterns.md for the fields drapekit reads.

pub mod curve;
pub mod duplicates;
mod format;
pub mod garment;
pub mod mesher;
pub mod transfer;
pub mod weld;

use crate::error::InputError;
use curve::{relative_point, Curve};
use glam::{DMat3, DVec2, DVec3};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One panel edge.
#[derive(Clone, Debug)]
pub struct PanelEdge {
    /// Indices into the panel's vertices.
    pub endpoints: [usize; 2],
    /// Its shape, in panel coordinates.
    pub curve: Curve,
    /// GarmentCode label, e.g. `lower_interface`.
    pub label: Option<String>,
}

/// One panel.
#[derive(Clone, Debug)]
pub struct Panel {
    /// The name it has in `pattern.panels`.
    pub name: String,
    /// Placement translation, pattern units.
    pub translation: DVec3,
    /// Placement rotation, Euler degrees (R = Rz·Ry·Rx).
    pub rotation_deg: DVec3,
    /// Outline corners, pattern units.
    pub vertices: Vec<DVec2>,
    /// Edges in loop order.
    pub edges: Vec<PanelEdge>,
}

impl Panel {
    /// The placement rotation R = Rz·Ry·Rx.
    pub fn rotation(&self) -> DMat3 {
        let r = self.rotation_deg * (std::f64::consts::PI / 180.0);
        DMat3::from_rotation_z(r.z) * DMat3::from_rotation_y(r.y) * DMat3::from_rotation_x(r.x)
    }

    /// The box around the outline's curves (`Curve::bounds`), in pattern units: corners low
    /// and high.
    pub fn outline_box(&self) -> (DVec2, DVec2) {
        (self.edges.iter()).map(|e| e.curve.bounds()).fold(
            (DVec2::INFINITY, DVec2::NEG_INFINITY),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        )
    }

    /// Twice the signed area of the corner loop (> 0: counter-clockwise).
    pub fn signed_area2(&self) -> f64 {
        let v = &self.vertices;
        (0..v.len())
            .map(|i| v[i].perp_dot(v[(i + 1) % v.len()]))
            .sum()
    }
}

/// One side of a stitch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeRef {
    /// Index into `Pattern::panels`.
    pub panel: usize,
    /// Index into that panel's edges.
    pub edge: usize,
}

/// Two edges sewn together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stitch {
    /// The two edges.
    pub sides: [EdgeRef; 2],
    /// `false` (the default): the first edge is reversed, so its start meets the second's end.
    pub right_wrong: bool,
}

/// A loaded, validated pattern.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// The file it came from.
    pub path: PathBuf,
    /// Pattern units per metre (`properties.units_in_meter`, default 100: cm).
    pub units_in_meter: f64,
    /// Panels, in file order.
    pub panels: Vec<Panel>,
    /// Stitches, in file order.
    pub stitches: Vec<Stitch>,
}

/// Python's json module writes NaN and ±Infinity as bare tokens, which are not JSON. Turn them
/// into `null` outside strings so that the value checks can name the panel and vertex.
fn non_finite_tokens_to_null(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_string = false;
    let mut escaped = false;
    let mut rest = text;
    while let Some(c) = rest.chars().next() {
        if in_string {
            in_string = c != '"' || escaped;
            escaped = c == '\\' && !escaped;
        } else if c == '"' {
            in_string = true;
        } else {
            let token = ["-Infinity", "Infinity", "NaN"]
                .into_iter()
                .find(|t| rest.starts_with(t));
            if let Some(t) = token {
                out.push_str("null");
                rest = &rest[t.len()..];
                continue;
            }
        }
        out.push(c);
        rest = &rest[c.len_utf8()..];
    }
    out
}

struct Reader<'a> {
    path: &'a Path,
}

impl Reader<'_> {
    fn err(
        &self,
        location: impl Into<String>,
        problem: impl Into<String>,
        fix: &str,
    ) -> InputError {
        InputError::new(self.path, location, problem, fix)
    }

    fn number(&self, v: Option<&Value>, location: &str) -> Result<f64, InputError> {
        match v {
            Some(Value::Number(n)) => {
                let x = n.as_f64().unwrap_or(f64::NAN);
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(self.err(location, "is not a finite number", "give a finite number"))
                }
            }
            Some(Value::Null) => Err(self.err(
                location,
                "is NaN or infinite",
                "replace it with a finite coordinate",
            )),
            Some(other) => Err(self.err(
                location,
                format!("expected a number, found {other}"),
                "give a number",
            )),
            None => Err(self.err(location, "is missing", "add it")),
        }
    }

    fn vec<const N: usize>(
        &self,
        v: Option<&Value>,
        location: &str,
    ) -> Result<[f64; N], InputError> {
        let items = v.and_then(Value::as_array).ok_or_else(|| {
            self.err(
                location,
                format!("expected a list of {N} numbers"),
                "give [x, y, ...]",
            )
        })?;
        if items.len() != N {
            return Err(self.err(
                location,
                format!("has {} numbers, expected {N}", items.len()),
                "give exactly that many",
            ));
        }
        let mut out = [0.0; N];
        for (k, item) in items.iter().enumerate() {
            out[k] = self.number(Some(item), &format!("{location}[{k}]"))?;
        }
        Ok(out)
    }
}

impl Pattern {
    /// Reads and validates a GarmentCode JSON pattern.
    pub fn load(path: &Path) -> Result<Pattern, InputError> {
        let bytes = std::fs::read(path).map_err(|e| {
            InputError::new(
                path,
                "",
                format!("cannot read the pattern file: {e}"),
                "check the path in the scene's [cloth.pattern] table",
            )
        })?;
        if let Some(format) = format::foreign_format(path, &bytes) {
            let (problem, fix) = format::foreign_format_message(format);
            return Err(InputError::new(path, "", problem, fix));
        }
        let text = String::from_utf8(bytes).map_err(|_| {
            InputError::new(
                path,
                "",
                "the file is not text (GarmentCode patterns are UTF-8 JSON)",
                "check the path in the scene's [cloth.pattern] table",
            )
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates pattern JSON; `path` only labels errors.
    ///
    /// ```
    /// use drapekit::pattern::garment::{Garment, GarmentOptions};
    /// use drapekit::pattern::Pattern;
    /// use std::path::Path;
    ///
    /// // Two 40 cm squares (GarmentCode units: cm), 2 cm apart, sewn along their facing sides.
    /// let json = r#"{"pattern": {
    ///     "panels": {
    ///         "left":  {"translation": [-42, 0, 0], "rotation": [0, 0, 0],
    ///                   "vertices": [[0, 0], [40, 0], [40, 40], [0, 40]],
    ///                   "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]},
    ///                             {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]},
    ///         "right": {"translation": [0, 0, 0], "rotation": [0, 0, 0],
    ///                   "vertices": [[0, 0], [40, 0], [40, 40], [0, 40]],
    ///                   "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]},
    ///                             {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}},
    ///     "stitches": [[{"panel": "left", "edge": 1}, {"panel": "right", "edge": 3}]]}}"#;
    /// let pattern = Pattern::parse(json, Path::new("squares.json"))?;
    /// assert_eq!(pattern.panels.len(), 2);
    /// let options = GarmentOptions { particle_distance: 0.05, placement: Default::default() };
    /// let garment = Garment::build(&pattern, &options)?;
    /// assert_eq!(garment.stitches, 1);
    /// // Both 40 cm edges get 8 segments at 5 cm; their 9 vertices pair up one to one.
    /// assert_eq!(garment.seam_pairs.len(), 9);
    /// # Ok::<(), drapekit::InputError>(())
    /// ```
    pub fn parse(text: &str, path: &Path) -> Result<Pattern, InputError> {
        let r = Reader { path };
        let text = &non_finite_tokens_to_null(text);
        let root: Value = serde_json::from_str(text).map_err(|e| {
            if let Some(format) = format::foreign_format(path, text.as_bytes()) {
                let (problem, fix) = format::foreign_format_message(format);
                return InputError::new(path, "", problem, fix);
            }
            InputError::new(
                path,
                "",
                format!("malformed JSON: {e}"),
                "fix the JSON syntax (a GarmentCode specification file is expected)",
            )
            .at_line(Some(e.line()))
        })?;
        // serde_json keeps the last of two equal keys: two panels of one name would lose one.
        if let Some(d) = duplicates::first_duplicate(text) {
            let problem = match d.parent.as_deref() {
                Some("panels") => format!("two panels are named '{}'", d.key),
                Some(parent) => format!("the key \"{}\" appears twice in \"{parent}\"", d.key),
                None => format!("the key \"{}\" appears twice", d.key),
            };
            let location = match d.parent.as_deref() {
                Some("panels") => format!("panel '{}'", d.key),
                _ => String::new(),
            };
            return Err(InputError::new(
                path,
                location,
                problem,
                "give every panel (and every key of an object) its own name: the second would \
                 silently replace the first",
            )
            .at_line(Some(d.line)));
        }
        let props = root.get("properties");
        let units_in_meter = match props.and_then(|p| p.get("units_in_meter")) {
            None => 100.0,
            v => r.number(v, "properties.units_in_meter")?,
        };
        if units_in_meter <= 0.0 {
            return Err(r.err(
                "properties.units_in_meter",
                "must be positive",
                "use 100 for centimetres",
            ));
        }
        let relative = match props.and_then(|p| p.get("curvature_coords")) {
            None => true,
            Some(Value::String(s)) if s == "relative" => true,
            Some(Value::String(s)) if s == "absolute" => false,
            Some(other) => {
                return Err(r.err(
                    "properties.curvature_coords",
                    format!("unknown value {other}"),
                    "use \"relative\" or \"absolute\"",
                ))
            }
        };
        let pattern = root.get("pattern").ok_or_else(|| {
            r.err(
                "pattern",
                "is missing",
                "a GarmentCode file has {\"pattern\": {\"panels\": ..., \"stitches\": ...}}",
            )
        })?;
        let panel_map = pattern
            .get("panels")
            .and_then(Value::as_object)
            .ok_or_else(|| {
                r.err(
                    "pattern.panels",
                    "is missing or not an object",
                    "map panel names to panels",
                )
            })?;
        if panel_map.is_empty() {
            return Err(r.err(
                "pattern.panels",
                "has no panels: there is no cloth to simulate",
                "add at least one panel",
            ));
        }
        let mut panels = Vec::new();
        for (name, p) in panel_map {
            panels.push(read_panel(&r, name, p, relative)?);
        }
        let mut stitches = Vec::new();
        let raw_stitches = match pattern.get("stitches") {
            None => Vec::new(),
            Some(Value::Array(a)) => a.clone(),
            Some(_) => {
                return Err(r.err(
                    "pattern.stitches",
                    "is not a list",
                    "give a list of edge pairs",
                ))
            }
        };
        let mut used: Vec<(EdgeRef, usize)> = Vec::new();
        for (k, s) in raw_stitches.iter().enumerate() {
            let loc = format!("stitch {k}");
            let items = s
                .as_array()
                .filter(|a| a.len() == 2 || a.len() == 3)
                .ok_or_else(|| {
                    r.err(
                        &loc,
                        "is not a pair of {\"panel\", \"edge\"} objects",
                        "write [{\"panel\": a, \"edge\": i}, {\"panel\": b, \"edge\": j}]",
                    )
                })?;
            let right_wrong = match items.get(2) {
                None => false,
                Some(Value::String(s)) if s == "right_wrong" => true,
                Some(other) => {
                    return Err(r.err(
                        &loc,
                        format!("unknown third element {other}"),
                        "only \"right_wrong\" is allowed",
                    ))
                }
            };
            let mut sides = [EdgeRef { panel: 0, edge: 0 }; 2];
            for (j, side) in items[..2].iter().enumerate() {
                let pname = side.get("panel").and_then(Value::as_str).ok_or_else(|| {
                    r.err(
                        &loc,
                        format!("side {j} has no \"panel\" name"),
                        "add \"panel\": \"<name>\"",
                    )
                })?;
                let panel = panels.iter().position(|p| p.name == pname).ok_or_else(|| {
                    let names: Vec<&str> = panels.iter().map(|p| p.name.as_str()).collect();
                    r.err(
                        &loc,
                        format!("unknown panel '{pname}'"),
                        &format!("use one of {names:?}"),
                    )
                })?;
                let edge = side.get("edge").and_then(Value::as_u64).ok_or_else(|| {
                    r.err(
                        &loc,
                        format!("side {j} has no \"edge\" index"),
                        "add \"edge\": <index>",
                    )
                })? as usize;
                let count = panels[panel].edges.len();
                if edge >= count {
                    return Err(r.err(
                        &loc,
                        format!("panel '{pname}' has no edge {edge} (it has {count})"),
                        &format!("use an edge index below {count}"),
                    ));
                }
                let this = EdgeRef { panel, edge };
                if let Some((_, first)) = used.iter().find(|(e, _)| *e == this) {
                    return Err(r.err(
                        &loc,
                        format!("panel '{pname}' edge {edge} is already sewn by stitch {first}"),
                        "an edge takes part in at most one stitch; split the edge or remove a stitch",
                    ));
                }
                used.push((this, k));
                sides[j] = this;
            }
            stitches.push(Stitch { sides, right_wrong });
        }
        Ok(Pattern {
            path: path.to_path_buf(),
            units_in_meter,
            panels,
            stitches,
        })
    }

    /// "panel 'name', edge i" for messages.
    pub fn edge_name(&self, e: EdgeRef) -> String {
        format!("panel '{}', edge {}", self.panels[e.panel].name, e.edge)
    }
}

/// The largest panel coordinate read, in the pattern's units: past it the geometry's squares and
/// cross products overflow. (Whether a panel fits the solver's 32-bit positions is checked once
/// it is placed, with the particle spacing.)
const MAX_COORDINATE: f64 = 1e100;

fn read_panel(r: &Reader, name: &str, p: &Value, relative: bool) -> Result<Panel, InputError> {
    let loc = format!("panel '{name}'");
    let translation = match p.get("translation") {
        None => [0.0; 3],
        v => r.vec::<3>(v, &format!("{loc}.translation"))?,
    };
    let rotation = match p.get("rotation") {
        None => [0.0; 3],
        v => r.vec::<3>(v, &format!("{loc}.rotation"))?,
    };
    let raw_vertices = p.get("vertices").and_then(Value::as_array).ok_or_else(|| {
        r.err(
            &loc,
            "has no \"vertices\" list",
            "add \"vertices\": [[x, y], ...]",
        )
    })?;
    if raw_vertices.len() < 3 {
        return Err(r.err(
            &loc,
            format!(
                "has {} vertices; a panel needs at least 3",
                raw_vertices.len()
            ),
            "give the panel a closed outline of 3 or more vertices",
        ));
    }
    let mut vertices = Vec::new();
    for (k, v) in raw_vertices.iter().enumerate() {
        let vloc = format!("{loc}, vertex {k}");
        let [x, y] = r.vec::<2>(Some(v), &vloc)?;
        // Past this every later test (zero-length edges, crossings, areas) answers nonsense.
        if x.abs().max(y.abs()) > MAX_COORDINATE {
            return Err(r.err(
                vloc,
                format!("lies at [{x:e}, {y:e}], beyond any garment"),
                "give the vertex its real coordinates, in the pattern's units (check the \
                 exponent for a slip)",
            ));
        }
        vertices.push(DVec2::new(x, y));
    }
    let raw_edges = p.get("edges").and_then(Value::as_array).ok_or_else(|| {
        r.err(
            &loc,
            "has no \"edges\" list",
            "add \"edges\": [{\"endpoints\": [0, 1]}, ...]",
        )
    })?;
    let mut edges = Vec::new();
    for (k, e) in raw_edges.iter().enumerate() {
        let eloc = format!("{loc}, edge {k}");
        let ends = e
            .get("endpoints")
            .and_then(Value::as_array)
            .filter(|a| a.len() == 2);
        let ends = ends.ok_or_else(|| {
            r.err(
                &eloc,
                "needs \"endpoints\": [i, j]",
                "give two vertex indices",
            )
        })?;
        let mut endpoints = [0usize; 2];
        for (j, v) in ends.iter().enumerate() {
            let i = v
                .as_u64()
                .map(|i| i as usize)
                .filter(|i| *i < vertices.len());
            endpoints[j] = i.ok_or_else(|| {
                r.err(
                    &eloc,
                    format!("endpoint {v} is not a vertex index"),
                    &format!("use 0..{}", vertices.len() - 1),
                )
            })?;
        }
        let (start, end) = (vertices[endpoints[0]], vertices[endpoints[1]]);
        if endpoints[0] == endpoints[1] || start.distance(end) <= 1e-9 * (1.0 + start.length()) {
            return Err(r.err(
                &eloc,
                "has zero length (its endpoints coincide)",
                "remove the edge or move one of its vertices",
            ));
        }
        let curve = read_curve(r, &eloc, e.get("curvature"), start, end, relative)?;
        let label = e.get("label").and_then(Value::as_str).map(str::to_string);
        edges.push(PanelEdge {
            endpoints,
            curve,
            label,
        });
    }
    if edges.len() < 2 {
        return Err(r.err(
            &loc,
            "has fewer than 2 edges",
            "edges must form a closed loop",
        ));
    }
    for k in 0..edges.len() {
        let next = (k + 1) % edges.len();
        if edges[k].endpoints[1] != edges[next].endpoints[0] {
            return Err(r.err(
                format!("{loc}, edge {next}"),
                format!(
                    "starts at vertex {} but edge {k} ends at vertex {}",
                    edges[next].endpoints[0], edges[k].endpoints[1]
                ),
                "list the edges in loop order, each starting where the previous one ends",
            ));
        }
    }
    Ok(Panel {
        name: name.to_string(),
        translation: DVec3::from(translation),
        rotation_deg: DVec3::from(rotation),
        vertices,
        edges,
    })
}

fn read_curve(
    r: &Reader,
    loc: &str,
    v: Option<&Value>,
    start: DVec2,
    end: DVec2,
    relative: bool,
) -> Result<Curve, InputError> {
    let point = |uv: [f64; 2]| {
        if relative {
            relative_point(start, end, uv[0], uv[1])
        } else {
            DVec2::from(uv)
        }
    };
    let cloc = format!("{loc}, curvature");
    let Some(v) = v else {
        return Ok(Curve::Line { start, end });
    };
    // The older form: a bare [u, v] means a quadratic control point.
    if v.is_array() {
        let c = point(r.vec::<2>(Some(v), &cloc)?);
        return Ok(Curve::Quadratic { start, c, end });
    }
    let kind = v.get("type").and_then(Value::as_str).unwrap_or("<missing>");
    let params = v.get("params");
    let param = |k: usize| params.and_then(|p| p.get(k));
    match kind {
        "quadratic" => {
            let c = point(r.vec::<2>(param(0), &format!("{cloc}.params[0]"))?);
            Ok(Curve::Quadratic { start, c, end })
        }
        "cubic" => {
            let c1 = point(r.vec::<2>(param(0), &format!("{cloc}.params[0]"))?);
            let c2 = point(r.vec::<2>(param(1), &format!("{cloc}.params[1]"))?);
            Ok(Curve::Cubic { start, c1, c2, end })
        }
        "circle" => {
            let radius = r.number(param(0), &format!("{cloc}.params[0] (radius)"))?;
            let flag = |k: usize, what: &str| -> Result<bool, InputError> {
                match param(k) {
                    Some(Value::Bool(b)) => Ok(*b),
                    Some(Value::Number(n)) => Ok(n.as_f64() != Some(0.0)),
                    _ => Err(r.err(
                        format!("{cloc}.params[{k}] ({what})"),
                        "expected 0, 1, true or false",
                        "give a flag",
                    )),
                }
            };
            let (large, right) = (flag(1, "large_arc")?, flag(2, "right")?);
            Curve::arc(start, end, radius, large, right).ok_or_else(|| {
                r.err(
                    &cloc,
                    format!(
                        "radius {radius} is shorter than half the chord ({})",
                        0.5 * start.distance(end)
                    ),
                    "use a radius of at least half the distance between the edge's endpoints",
                )
            })
        }
        other => Err(r.err(
            &cloc,
            format!("unknown curvature type '{other}'"),
            "use \"quadratic\", \"cubic\" or \"circle\"",
        )),
    }
}
