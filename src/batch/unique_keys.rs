//! A check that a JSON text names no key twice in one object. `serde_json` keeps the last of
//! two equal keys without a word, so `{"fabric": {"preset": "denim"}, "fabric": {…}}` would
//! drop the first override silently; a manifest line is checked with this before it is read.

use serde::de::{Deserialize, Deserializer, Error, MapAccess, SeqAccess, Visitor};
use std::collections::HashSet;
use std::fmt;

/// Which key the first object of `json` that repeats one repeats, and the column where the
/// repeat is; `None` when no object does. Text that is not JSON passes: the real parse words
/// that error.
pub fn first_duplicate(json: &str) -> Option<String> {
    match serde_json::from_str::<Unique>(json) {
        Err(e) if e.is_data() => Some(e.to_string()),
        _ => None,
    }
}

/// Walks any JSON value, failing on an object that repeats a key.
struct Unique;

impl<'de> Deserialize<'de> for Unique {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Unique, D::Error> {
        d.deserialize_any(UniqueVisitor)
    }
}

struct UniqueVisitor;

impl<'de> Visitor<'de> for UniqueVisitor {
    type Value = Unique;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Unique, A::Error> {
        let mut seen = HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if !seen.insert(key.clone()) {
                return Err(A::Error::custom(format!(
                    "key {key:?} appears twice in one object"
                )));
            }
            map.next_value::<Unique>()?;
        }
        Ok(Unique)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Unique, A::Error> {
        while seq.next_element::<Unique>()?.is_some() {}
        Ok(Unique)
    }

    // Scalars carry no keys.
    fn visit_bool<E>(self, _: bool) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_str<E>(self, _: &str) -> Result<Unique, E> {
        Ok(Unique)
    }
    fn visit_unit<E>(self) -> Result<Unique, E> {
        Ok(Unique)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_key_repeated_at_any_depth() {
        let top = first_duplicate(r#"{"id": "a", "id": "b"}"#).unwrap();
        assert!(top.contains("\"id\" appears twice"), "{top}");
        let deep = first_duplicate(
            r#"{"overrides": {"fabric": [{"preset": "denim"}, {"x": 1, "x": 2}]}}"#,
        )
        .unwrap();
        assert!(deep.contains("\"x\" appears twice"), "{deep}");
    }

    #[test]
    fn passes_equal_keys_in_different_objects_and_text_that_is_not_json() {
        assert_eq!(
            first_duplicate(r#"{"a": {"k": 1}, "b": {"k": 1}, "k": null}"#),
            None
        );
        assert_eq!(first_duplicate(r#"{"a": "#), None);
    }
}
