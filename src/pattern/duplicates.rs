//! JSON objects with a key given twice. serde_json keeps the last of them silently, so a
//! pattern with two panels of one name would lose the first; this pass finds the repeat (with
//! its line) before the pattern is read.

use serde::de::{DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use std::collections::HashSet;
use std::fmt;

/// A key given twice in one object: the key, the object's own key (`None` at the top), and
/// the 1-based line of the repeat.
#[derive(Debug, PartialEq)]
pub struct Duplicate {
    /// The repeated key.
    pub key: String,
    /// The key of the object holding it, e.g. `panels`.
    pub parent: Option<String>,
    /// Line of the second occurrence.
    pub line: usize,
}

/// The first key repeated within one object of `text`, if any. Text that is not JSON has
/// none (the JSON parser reports it).
pub fn first_duplicate(text: &str) -> Option<Duplicate> {
    let mut de = serde_json::Deserializer::from_str(text);
    match (Walk { parent: None }).deserialize(&mut de) {
        Ok(()) => None,
        Err(e) => {
            let message = e.to_string();
            let rest = message.strip_prefix(MARK)?;
            let (parent, key) = rest.split_once('\u{0}')?;
            let key = key.rsplit_once(" at line ").map_or(key, |(k, _)| k);
            Some(Duplicate {
                key: key.to_string(),
                parent: (!parent.is_empty()).then(|| parent.to_string()),
                line: e.line(),
            })
        }
    }
}

/// Starts the custom error that carries a duplicate (parent and key, NUL-separated).
const MARK: &str = "duplicate key\u{0}";

/// Visits any JSON value, failing at the first key repeated within one object.
struct Walk {
    parent: Option<String>,
}

impl<'de> DeserializeSeed<'de> for Walk {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Walk {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while seq
            .next_element_seed(Walk {
                parent: self.parent.clone(),
            })?
            .is_some()
        {}
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut seen = HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if !seen.insert(key.clone()) {
                let parent = self.parent.as_deref().unwrap_or("");
                return Err(serde::de::Error::custom(format!(
                    "{MARK}{parent}\u{0}{key}"
                )));
            }
            map.next_value_seed(Walk { parent: Some(key) })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_repeated_panel_name_and_its_line() {
        let text = "{\"pattern\": {\"panels\": {\n\"front\": {\"a\": 1},\n\"front\": {}}}}";
        assert_eq!(
            first_duplicate(text),
            Some(Duplicate {
                key: "front".into(),
                parent: Some("panels".into()),
                line: 3
            })
        );
        // The same key in two different objects is not a repeat.
        assert_eq!(first_duplicate("[{\"a\": 1}, {\"a\": [{\"a\": 2}]}]"), None);
        assert_eq!(
            first_duplicate("{\"a\": "),
            None,
            "not JSON: not ours to report"
        );
    }
}
