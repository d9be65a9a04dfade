//! Where a batch item's bad input was written. An item's scene is its file with the manifest
//! line's overrides merged in, so an error found while building it (a memory budget, a pin)
//! carries a line of the merged text, which is neither file's: a key the overrides set is
//! reported at the manifest's line, any other key at its line in the scene file.

use super::manifest::Item;
use crate::check::Checker;
use crate::error::{Error, InputError};
use serde_json::Value;

/// `e`, located in the file that holds the key at fault.
pub fn locate(item: &Item, e: Error) -> Error {
    match e {
        Error::Input(e) if e.file == item.scene_path && !item.overrides.is_empty() => {
            Error::Input(locate_input(item, e))
        }
        e => e,
    }
}

fn locate_input(item: &Item, e: InputError) -> InputError {
    if overrides_set(&item.overrides, &e.location) {
        return InputError {
            file: item.manifest.clone(),
            line: Some(item.line),
            location: format!(
                "item {:?}: overrides.{} (of {})",
                item.id,
                e.location,
                item.scene_path.display()
            ),
            ..e
        };
    }
    // Not overridden: the key, as the scene file itself has it.
    let Ok(src) = std::fs::read_to_string(&item.scene_path) else {
        return InputError { line: None, ..e };
    };
    let (table, key) = e.location.rsplit_once('.').unwrap_or((&e.location, ""));
    let c = Checker {
        path: &item.scene_path,
        src: &src,
    };
    let line = c.err(table, key, "", "").line;
    InputError { line, ..e }
}

/// Whether the overrides set `location` (`cloth.grid.columns`, `pins[0].indices`) or a table
/// or list that holds it.
fn overrides_set(overrides: &serde_json::Map<String, Value>, location: &str) -> bool {
    let mut at = Value::Object(overrides.clone());
    for part in location.split('.') {
        let (name, index) = match part.split_once('[') {
            Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
            None => (part, None),
        };
        let Some(next) = at.get(name) else {
            return false;
        };
        at = match (next, index) {
            // A list is replaced whole by a merge patch: the override set every entry.
            (Value::Array(_), _) => return true,
            (v, _) if !v.is_object() => return true,
            (v, _) => v.clone(),
        };
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_is_overridden_when_the_patch_reaches_it() {
        let patch =
            serde_json::json!({"cloth": {"grid": {"columns": 9}}, "pins": [{"indices": [3]}]});
        let o = patch.as_object().unwrap();
        assert!(overrides_set(o, "cloth.grid.columns"));
        assert!(overrides_set(o, "pins[0].indices"));
        assert!(!overrides_set(o, "cloth.grid.rows"));
        assert!(!overrides_set(o, "fabric.density_kg_m2"));
    }
}
