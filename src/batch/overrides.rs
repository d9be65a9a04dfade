//! A manifest item's `overrides`: a JSON Merge Patch (RFC 7386) applied to the scene's TOML
//! tables before the scene is validated, so an override is checked exactly like a key written
//! in the file.

use serde_json::Value;

/// Applies `patch` to `table`: objects merge key by key, `null` removes a key (e.g. a fixed
/// density that would otherwise override a new `fabric.preset`), anything else replaces.
/// `at` is the dotted key path of `table`, for messages. Returns a warning for each null that
/// removed nothing (the merge patch allows it, but it is how a key put in the wrong table
/// looks: `"frames": null` for `solver.frames`) or removed whole tables (a null meant for one
/// key of them does that by surprise). A table the patch only removes keys from is not
/// created: an empty `[self_collision]` would switch the effect on.
pub fn merge(
    table: &mut toml::Table,
    patch: &serde_json::Map<String, Value>,
    at: &str,
) -> Result<Vec<String>, String> {
    let mut warnings = Vec::new();
    for (key, value) in patch {
        let path = dotted(at, key);
        match value {
            Value::Null => {
                let removed = table.remove(key);
                warnings.extend(removal_warning(&path, key, removed.as_ref()));
            }
            Value::Object(inner) => {
                let existed = table.get(key).is_some_and(|v| v.is_table());
                if !existed {
                    table.insert(key.clone(), toml::Value::Table(toml::Table::new()));
                }
                let Some(toml::Value::Table(sub)) = table.get_mut(key) else {
                    unreachable!("inserted above")
                };
                warnings.extend(merge(sub, inner, &path)?);
                if !existed && sub.is_empty() {
                    table.remove(key);
                }
            }
            other => {
                table.insert(key.clone(), to_toml(other, &path)?);
            }
        }
    }
    Ok(warnings)
}

/// The warning for a null at `path` that removed `removed`, if it deserves one: nothing, a
/// table, or an array of tables.
fn removal_warning(path: &str, key: &str, removed: Option<&toml::Value>) -> Option<String> {
    match removed {
        None => Some(format!(
            "overrides: {path} is null, but the scene has no {path}, so it removes nothing; \
             check which table the key belongs to"
        )),
        Some(toml::Value::Table(t)) => Some(format!(
            "overrides: {path} is null, which removes the scene's whole [{path}] table ({} \
             keys): a table with defaults falls back to them, an optional one (a body, the \
             wind, self-collision, the preview) is switched off; to remove one key, write \
             {{\"{key}\": {{\"KEY\": null}}}}",
            t.len()
        )),
        Some(toml::Value::Array(a)) if !a.is_empty() && a.iter().all(|v| v.is_table()) => {
            Some(format!(
                "overrides: {path} is null, which removes all {} of the scene's [[{path}]] \
                 tables",
                a.len()
            ))
        }
        Some(_) => None,
    }
}

/// A JSON value as TOML. TOML has no null, so a null inside an array or a new table is an
/// error (a null directly under a table removes the key instead; see [`merge`]).
fn to_toml(value: &Value, path: &str) -> Result<toml::Value, String> {
    Ok(match value {
        Value::Null => {
            return Err(format!(
                "{path} is null inside an array or a new table; TOML has no null \
                 (null directly under a table removes that key)"
            ))
        }
        Value::Bool(b) => toml::Value::Boolean(*b),
        Value::Number(n) => match n.as_i64() {
            Some(i) => toml::Value::Integer(i),
            None => toml::Value::Float(n.as_f64().ok_or(format!("{path}: {n} is not a number"))?),
        },
        Value::String(s) => toml::Value::String(s.clone()),
        Value::Array(items) => toml::Value::Array(
            (items.iter().enumerate())
                .map(|(i, v)| to_toml(v, &format!("{path}[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
        Value::Object(map) => toml::Value::Table(
            map.iter()
                .map(|(k, v)| Ok((k.clone(), to_toml(v, &dotted(path, k))?)))
                .collect::<Result<_, String>>()?,
        ),
    })
}

fn dotted(at: &str, key: &str) -> String {
    if at.is_empty() {
        key.to_string()
    } else {
        format!("{at}.{key}")
    }
}

/// `value` as JSON with object keys sorted at every level, so that the same item hashes the
/// same however its line was written.
pub fn canonical(value: &Value) -> String {
    match value {
        Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort();
            let fields: Vec<String> = keys
                .iter()
                .map(|k| format!("{}:{}", Value::String((*k).clone()), canonical(&map[*k])))
                .collect();
            format!("{{{}}}", fields.join(","))
        }
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(canonical).collect();
            format!("[{}]", items.join(","))
        }
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_deeply_replaces_and_removes() {
        let mut table: toml::Table = toml::from_str(
            "[fabric]\ndensity_kg_m2 = 0.15\nstretch_stiffness_n_m = 300.0\n\
             [cloth.pattern]\npath = \"p.json\"\nparticle_distance_m = 0.02\n",
        )
        .unwrap();
        let patch = serde_json::json!({
            "fabric": {"preset": "denim", "density_kg_m2": null, "stretch_stiffness_n_m": null},
            "cloth": {"pattern": {"particle_distance_m": 0.03}},
            "solver": {"frames": 2}
        });
        let warnings = merge(&mut table, patch.as_object().unwrap(), "").unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let expect: toml::Table = toml::from_str(
            "[fabric]\npreset = \"denim\"\n\
             [cloth.pattern]\npath = \"p.json\"\nparticle_distance_m = 0.03\n\
             [solver]\nframes = 2\n",
        )
        .unwrap();
        assert_eq!(table, expect);
    }

    #[test]
    fn warns_of_nulls_that_remove_nothing_or_a_whole_table() {
        let mut table: toml::Table =
            toml::from_str("[solver]\nframes = 48\nsubsteps = 8\n").unwrap();
        let patch = serde_json::json!({"frames": null});
        let warnings = merge(&mut table, patch.as_object().unwrap(), "").unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].contains("no frames, so it removes nothing"),
            "{warnings:?}"
        );
        let patch = serde_json::json!({"solver": null});
        let warnings = merge(&mut table, patch.as_object().unwrap(), "").unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].contains("whole [solver] table (2 keys)"),
            "{warnings:?}"
        );
        assert!(table.is_empty());
    }

    #[test]
    fn a_null_inside_a_missing_table_creates_no_table_and_arrays_of_tables_are_warned() {
        // An empty [self_collision] would switch self-collision on.
        let mut table: toml::Table =
            toml::from_str("[[pins]]\ncorners = [\"top-left\"]\n[[pins]]\nindices = [3]\n")
                .unwrap();
        let patch = serde_json::json!({"self_collision": {"thickness_m": null}});
        let warnings = merge(&mut table, patch.as_object().unwrap(), "").unwrap();
        assert!(!table.contains_key("self_collision"), "{table:?}");
        assert!(
            warnings[0].contains("self_collision.thickness_m is null, but the scene has no"),
            "{warnings:?}"
        );
        let patch = serde_json::json!({"pins": null});
        let warnings = merge(&mut table, patch.as_object().unwrap(), "").unwrap();
        assert!(
            warnings[0].contains("removes all 2 of the scene's [[pins]]"),
            "{warnings:?}"
        );
    }

    #[test]
    fn refuses_a_null_toml_cannot_hold() {
        let mut table = toml::Table::new();
        let patch = serde_json::json!({"pins": [{"indices": [0, null]}]});
        let err = merge(&mut table, patch.as_object().unwrap(), "").unwrap_err();
        assert!(err.contains("pins[0].indices[1]"), "{err}");
    }

    #[test]
    fn canonical_json_ignores_key_order() {
        let a: Value = serde_json::from_str(r#"{"b": 1, "a": {"y": [1, 2], "x": "s"}}"#).unwrap();
        let b: Value = serde_json::from_str(r#"{"a":{"x":"s","y":[1,2]},"b":1}"#).unwrap();
        assert_eq!(canonical(&a), canonical(&b));
        assert_eq!(canonical(&a), r#"{"a":{"x":"s","y":[1,2]},"b":1}"#);
    }
}
