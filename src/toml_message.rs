//! Messages for TOML files that do not fit their format: serde's terse "unknown field `x`" or
//! "invalid type: floating point `48.0`, expected i64" becomes an error naming the key (with its
//! table), the value expected with its unit, and a fix ("did you mean …", "write frames = 48").

use crate::error::InputError;
use crate::suggest;
use std::path::Path;

/// Where to look for every key, its unit and default.
const FORMAT_DOC: &str = "docs/src/scenes.md";

/// The scene's top-level tables without a default (`RawScene`'s required fields).
const REQUIRED_TABLES: [&str; 3] = ["cloth", "fabric", "solver"];

/// `err`, from reading `src` (the text of `path`), as an error a user can act on.
pub fn describe(path: &Path, src: &str, err: &toml::de::Error) -> InputError {
    let start = err.span().map(|s| {
        let mut start = s.start.min(src.len());
        while !src.is_char_boundary(start) {
            start -= 1;
        }
        start
    });
    let message = err.message().trim();
    // A required table's absence belongs to no line.
    let start = start.filter(|_| !missing_table(message));
    let line = start.map(|s| src[..s].matches('\n').count() + 1);
    let place = start.map_or_else(Place::default, |s| Place::of(src, s));
    let (location, problem, fix) = explain(message, &place);
    InputError::new(path, location, problem, fix).at_line(line)
}

/// The table and key a position in a TOML text belongs to.
#[derive(Debug, Default, PartialEq)]
struct Place {
    /// The enclosing table, dotted (`cloth.grid`; `body[1]` for the second `[[body]]`).
    table: String,
    /// The key on the position's line, or the last part of the header the position is on.
    key: String,
    /// Whether the position is on a table header.
    on_header: bool,
}

impl Place {
    fn of(src: &str, offset: usize) -> Place {
        let target = src[..offset].matches('\n').count();
        let mut table = String::new();
        let mut arrays = std::collections::HashMap::<String, usize>::new();
        for (n, line) in src.lines().enumerate() {
            let t = line.trim();
            let header = header_name(t).map(|(name, is_array)| {
                if is_array {
                    let count = arrays.entry(name.clone()).or_insert(0);
                    *count += 1;
                    format!("{name}[{}]", *count - 1)
                } else {
                    name
                }
            });
            if n == target {
                return match header {
                    Some(h) => {
                        let (parent, last) = h.rsplit_once('.').unwrap_or(("", &h));
                        Place {
                            table: parent.to_string(),
                            key: last.to_string(),
                            on_header: true,
                        }
                    }
                    None => Place {
                        table,
                        key: t
                            .split('=')
                            .next()
                            .unwrap_or("")
                            .trim()
                            .trim_matches('"')
                            .into(),
                        on_header: false,
                    },
                };
            }
            if let Some(h) = header {
                table = h;
            }
        }
        Place::default()
    }

    /// `table.key`, or whichever of the two there is.
    fn dotted(&self, key: &str) -> String {
        match (self.table.is_empty(), key.is_empty()) {
            (true, _) => key.to_string(),
            (false, true) => self.table.clone(),
            (false, false) => format!("{}.{key}", self.table),
        }
    }
}

/// A header line's table name and whether it is an array of tables (`[[x]]`).
fn header_name(line: &str) -> Option<(String, bool)> {
    let (inner, is_array) = if let Some(rest) = line.strip_prefix("[[") {
        (rest.split("]]").next()?, true)
    } else {
        (line.strip_prefix('[')?.split(']').next()?, false)
    };
    let name: Vec<&str> = inner
        .split('.')
        .map(|p| p.trim().trim_matches('"'))
        .collect();
    Some((name.join("."), is_array))
}

/// Whether `message` says that one of the scene's required tables is missing. serde reports
/// it against the whole document, whose span starts on the first line, whatever table that
/// line opens (a scene starting `[cloth.grid]` without `[solver]` read "cloth.grid: the required
/// key `solver` is missing").
fn missing_table(message: &str) -> bool {
    between(message, "missing field `", "`").is_some_and(|k| REQUIRED_TABLES.contains(&k))
}

/// Location, problem and fix for one of serde's messages.
fn explain(message: &str, place: &Place) -> (String, String, String) {
    if let Some((word, choices)) = unknown(message, "unknown field") {
        return unknown_key(place, word, &choices);
    }
    if let Some((word, choices)) = unknown(message, "unknown variant") {
        let best = suggest::closest(word, choices.iter().copied());
        return (
            place.dotted(&place.key),
            format!("unknown value `{word}`{}", mean(best)),
            format!("use one of {}", list(&choices)),
        );
    }
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return wrong_type(place, found, expected);
        }
    }
    if let Some(rest) = message.strip_prefix("invalid value: ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            let want = expectation(expected, &place.key);
            let literal = between(found, "`", "`").unwrap_or(found);
            return (
                place.dotted(&place.key),
                format!("{literal} is not {want}"),
                format!("give {want}"),
            );
        }
    }
    if let Some(key) = between(message, "missing field `", "`") {
        if missing_table(message) {
            return (
                String::new(),
                format!("the required table [{key}] is missing"),
                format!("add a [{key}] table (see {FORMAT_DOC})"),
            );
        }
        let table = if place.on_header {
            place.dotted(&place.key)
        } else {
            place.table.clone()
        };
        return (
            table,
            format!("the required key `{key}` is missing"),
            format!("add `{key} = …`{} (see {FORMAT_DOC})", unit_note(key)),
        );
    }
    if let Some(rest) = message.strip_prefix("invalid length ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return (
                place.dotted(&place.key),
                format!("expected {expected}, found {found} values"),
                format!(
                    "write {} numbers{} in brackets, e.g. [0.0, 1.0, 0.0]",
                    expected.rsplit(' ').next().unwrap_or("3"),
                    unit_note(&place.key)
                ),
            );
        }
    }
    (
        place.dotted(if place.on_header { "" } else { &place.key }),
        message.to_string(),
        format!("see the scene format in {FORMAT_DOC}: every key, its unit and default"),
    )
}

/// An unknown key (or table) with the keys its table takes.
fn unknown_key(place: &Place, word: &str, choices: &[&str]) -> (String, String, String) {
    let what = if place.on_header { "table" } else { "key" };
    let best = suggest::closest(word, choices.iter().copied());
    let problem = format!("unknown {what} `{word}`{}", mean(best));
    let fix = match best {
        Some(b) => format!("rename it to `{b}`"),
        None if choices.is_empty() => "remove it: this table takes no keys".to_string(),
        None => {
            let table = if place.table.is_empty() {
                "a scene".to_string()
            } else {
                format!("[{}]", place.table)
            };
            format!(
                "remove it, or use one of the {what}s of {table}: {}",
                list(choices)
            )
        }
    };
    (place.dotted(word), problem, fix)
}

/// A value of the wrong type: say what the key takes, in its unit, and how to write it.
fn wrong_type(place: &Place, found: &str, expected: &str) -> (String, String, String) {
    let key = &place.key;
    let want = expectation(expected, key);
    let problem = format!("expected {want}, found {}", value_of(found));
    let literal = between(found, "`", "`")
        .or_else(|| between(found, "\"", "\""))
        .unwrap_or("");
    let number: Option<f64> = literal.parse().ok();
    // A whole number past 2⁵³ is no count anyone means: its digits are not worth repeating.
    let count = |x: f64| x.fract() == 0.0 && x.abs() < 9.007e15;
    let quoted = found.starts_with("string");
    let fix = match (whole_number(expected), number) {
        (true, Some(x)) if count(x) && quoted => {
            format!("write `{key} = {x}`, without quotes")
        }
        (true, Some(x)) if count(x) => {
            format!("write `{key} = {x}`, without a decimal point")
        }
        (true, _) => format!("write a whole number, e.g. `{key} = 2`"),
        (false, Some(_)) if quoted && is_number(expected) => {
            format!(
                "write `{key} = {literal}` (a number{}, without quotes)",
                unit_note(key)
            )
        }
        _ if expected == "a string" => {
            format!("write `{key} = \"…\"` (see {FORMAT_DOC} for the values it takes)")
        }
        _ => format!("give {want} (see {FORMAT_DOC})"),
    };
    (place.dotted(key), problem, fix)
}

/// The word and the accepted names of serde's "unknown field/variant `x`, expected …".
fn unknown<'a>(message: &'a str, prefix: &str) -> Option<(&'a str, Vec<&'a str>)> {
    let rest = message.strip_prefix(prefix)?;
    let word = between(rest, "`", "`")?;
    let expected = rest.split_once(", expected ").map_or("", |(_, e)| e);
    let choices = expected.split('`').skip(1).step_by(2).collect::<Vec<_>>();
    Some((word, choices))
}

/// The text between the first `open` and the next `close` after it.
fn between<'a>(s: &'a str, open: &str, close: &str) -> Option<&'a str> {
    let (_, rest) = s.split_once(open)?;
    rest.split_once(close).map(|(inside, _)| inside)
}

fn whole_number(expected: &str) -> bool {
    [
        "i8", "i16", "i32", "i64", "u8", "u16", "u32", "u64", "usize", "isize",
    ]
    .contains(&expected)
}

fn is_number(expected: &str) -> bool {
    whole_number(expected) || expected == "f32" || expected == "f64"
}

/// serde's expected type in words, with the key's unit where its name gives one.
fn expectation(expected: &str, key: &str) -> String {
    if whole_number(expected) {
        let sign = if expected.starts_with('u') {
            " ≥ 0"
        } else {
            ""
        };
        return format!("a whole number{sign}");
    }
    match expected {
        "f32" | "f64" => format!("a number{}", unit_note(key)),
        "a string" => "text in quotes".to_string(),
        "a boolean" => "true or false".to_string(),
        "a sequence" => "a list in brackets".to_string(),
        // serde names the Rust type a table is read into ("struct RawGrid"): a table to a user.
        other if other.starts_with("struct ") || other == "a map" => "a table of keys".into(),
        other => other.to_string(),
    }
}

/// serde's description of a found value in words: "floating point `48.0`" → "the decimal 48.0".
fn value_of(found: &str) -> String {
    let literal = between(found, "`", "`");
    match (found.split([' ', '`']).next().unwrap_or(""), literal) {
        ("floating", Some(v)) => format!("the decimal {v}"),
        ("integer", Some(v)) => format!("the whole number {v}"),
        ("boolean", Some(v)) => format!("the boolean {v}"),
        ("string", _) => format!("the text {}", found.trim_start_matches("string ")),
        _ => found.to_string(),
    }
}

/// " in kg/m²" for a key whose name ends in its unit, else nothing.
fn unit_note(key: &str) -> String {
    unit_of(key).map_or_else(String::new, |u| format!(" in {u}"))
}

/// The unit a key's name carries: `density_kg_m2` is in kg/m², `fov_deg` in degrees.
pub fn unit_of(key: &str) -> Option<&'static str> {
    // Bending is a moment per unit curvature (N·m); every other `_n_m` key is a force per length.
    if key == "bending_stiffness_n_m" {
        return Some("N·m");
    }
    const SUFFIXES: &[(&str, &str)] = &[
        ("_kg_m2", "kg/m²"),
        ("_kg_m3", "kg/m³"),
        ("_m_s2", "m/s²"),
        ("_m_s", "m/s"),
        ("_n_m", "N/m"),
        ("_per_s", "1/s"),
        ("_hz", "Hz"),
        ("_deg", "degrees"),
        ("_mb", "MiB"),
        ("_j", "J"),
        ("_s", "s"),
        ("_m", "m"),
    ];
    SUFFIXES
        .iter()
        .find(|(suffix, _)| key.ends_with(suffix))
        .map(|(_, unit)| *unit)
}

/// `; did you mean `x`?` or nothing.
fn mean(best: Option<&str>) -> String {
    best.map_or_else(String::new, |b| format!("; did you mean `{b}`?"))
}

/// `a`, `b`, `c` as a readable list.
fn list(choices: &[&str]) -> String {
    choices
        .iter()
        .map(|c| format!("`{c}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = "[cloth.grid]\nwidth_m = 1.0\n\n[[body]]\nshape = \"sphere\"\n\n[[body]]\nradius_m = 0.2\n[solver]\nframes = 48.0\n";

    fn at(line: usize, column: usize) -> usize {
        SCENE
            .lines()
            .take(line - 1)
            .map(|l| l.len() + 1)
            .sum::<usize>()
            + column
    }

    #[test]
    fn a_missing_table_is_named_as_a_table_on_no_line() {
        let src = "[cloth.grid]\nwidth_m = 1.0\nheight_m = 1.0\ncolumns = 3\nrows = 3\n\
                   [fabric]\npreset = \"cotton\"\n";
        let err = crate::scene::Scene::parse(src, Path::new("s.toml")).unwrap_err();
        assert_eq!(err.location, "");
        assert_eq!(err.problem, "the required table [solver] is missing");
        assert!(err.fix.starts_with("add a [solver] table"), "{}", err.fix);
        assert!(!err.to_string().contains("s.toml:1"), "{err}");
    }

    #[test]
    fn places_name_the_table_and_key() {
        let p = Place::of(SCENE, at(2, 0));
        assert_eq!(
            (p.table.as_str(), p.key.as_str(), p.on_header),
            ("cloth.grid", "width_m", false)
        );
        let p = Place::of(SCENE, at(8, 11));
        assert_eq!((p.table.as_str(), p.key.as_str()), ("body[1]", "radius_m"));
        let p = Place::of(SCENE, at(1, 1));
        assert_eq!(
            (p.table.as_str(), p.key.as_str(), p.on_header),
            ("cloth", "grid", true)
        );
        assert_eq!(
            Place::of(SCENE, at(10, 9)).dotted("frames"),
            "solver.frames"
        );
    }

    #[test]
    fn units_come_from_key_names() {
        assert_eq!(unit_of("density_kg_m2"), Some("kg/m²"));
        assert_eq!(unit_of("stretch_stiffness_n_m"), Some("N/m"));
        assert_eq!(unit_of("bending_stiffness_n_m"), Some("N·m"));
        assert_eq!(unit_of("settle_speed_m_s"), Some("m/s"));
        assert_eq!(unit_of("gravity_m_s2"), Some("m/s²"));
        assert_eq!(unit_of("air_damping_per_s"), Some("1/s"));
        assert_eq!(unit_of("seam_sewing_time_s"), Some("s"));
        assert_eq!(unit_of("thickness_m"), Some("m"));
        assert_eq!(unit_of("fov_deg"), Some("degrees"));
        assert_eq!(unit_of("frames"), None);
    }

    #[test]
    fn a_decimal_for_a_count_names_key_and_fix() {
        let place = Place::of(SCENE, at(10, 9));
        let (location, problem, fix) =
            explain("invalid type: floating point `48.0`, expected i64", &place);
        assert_eq!(location, "solver.frames");
        assert_eq!(problem, "expected a whole number, found the decimal 48.0");
        assert_eq!(fix, "write `frames = 48`, without a decimal point");
        let (_, problem, fix) = explain("invalid type: string \"1\", expected u32", &place);
        assert_eq!(problem, "expected a whole number ≥ 0, found the text \"1\"");
        assert_eq!(fix, "write `frames = 1`, without quotes");
        let (_, _, fix) = explain("invalid type: floating point `1e30`, expected i64", &place);
        assert_eq!(fix, "write a whole number, e.g. `frames = 2`");
    }

    #[test]
    fn a_table_is_named_a_table_not_the_type_it_is_read_into() {
        let place = Place {
            table: "cloth".into(),
            key: "grid".into(),
            on_header: false,
        };
        let (_, problem, fix) = explain("invalid type: sequence, expected struct RawGrid", &place);
        assert_eq!(problem, "expected a table of keys, found sequence");
        assert!(!fix.contains("Raw"), "{fix}");
    }

    #[test]
    fn quoted_numbers_and_unknown_keys() {
        let place = Place {
            table: "fabric".into(),
            key: "density_kg_m2".into(),
            on_header: false,
        };
        let (_, problem, fix) = explain("invalid type: string \"0.2\", expected f64", &place);
        assert_eq!(
            problem,
            "expected a number in kg/m², found the text \"0.2\""
        );
        assert_eq!(
            fix,
            "write `density_kg_m2 = 0.2` (a number in kg/m², without quotes)"
        );
        let (location, problem, fix) = explain(
            "unknown field `densty_kg_m2`, expected one of `preset`, `density_kg_m2`",
            &place,
        );
        assert_eq!(location, "fabric.densty_kg_m2");
        assert_eq!(
            problem,
            "unknown key `densty_kg_m2`; did you mean `density_kg_m2`?"
        );
        assert_eq!(fix, "rename it to `density_kg_m2`");
    }
}
