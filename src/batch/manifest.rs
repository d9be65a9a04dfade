//! The batch manifest: JSON Lines, one item a line,
//! `{"id": "…", "scene": "path.toml", "overrides": {…}}`. The whole file is validated before
//! anything runs, and every bad line is reported at once: a cluster job that fails on item
//! 9,000 of 10,000 for a typo costs hours.

use super::{overrides, unique_keys};
use crate::error::InputError;
use crate::scene::{BodySource, ClothSource, Scene};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Item ids become folder names; these are taken by the batch report.
const RESERVED_IDS: [&str; 2] = ["batch.csv", "batch.md"];
/// Longest id, in bytes (file names may be 255 bytes; leave room for temporary names).
const MAX_ID_LEN: usize = 128;

/// One validated manifest item.
#[derive(Clone, Debug)]
pub struct Item {
    /// The manifest file.
    pub manifest: PathBuf,
    /// 1-based line in the manifest.
    pub line: usize,
    /// 0-based position among the manifest's items (blank lines do not count): its shard key.
    pub index: usize,
    /// The item's id: its folder name under the batch's output folder.
    pub id: String,
    /// The scene as written in the manifest.
    pub scene_arg: String,
    /// The scene file, resolved against the manifest's folder.
    pub scene_path: PathBuf,
    /// The overrides (a JSON object; empty when none).
    pub overrides: serde_json::Map<String, Value>,
    /// The scene with the overrides merged, validated.
    pub scene: Scene,
    /// `fabric.preset` after the overrides, or "custom".
    pub fabric: String,
    /// The pattern's particle spacing in m (pattern scenes only).
    pub particle_distance_m: Option<f64>,
    /// The files the scene reads besides itself, with the SHA-256 of each.
    pub files: Vec<(String, PathBuf, String)>,
    /// SHA-256 over the item's inputs: its line (canonical JSON), the scene's text and the
    /// contents of every file it reads. The batch adds drapekit's version and its options.
    pub inputs_sha256: String,
    /// What looks wrong in the item but runs (`overrides::merge`'s warnings).
    pub warnings: Vec<String>,
}

/// A validated manifest.
#[derive(Clone, Debug)]
pub struct Manifest {
    /// The manifest file.
    pub path: PathBuf,
    /// Every item, in file order.
    pub items: Vec<Item>,
}

impl Manifest {
    /// Reads and validates the whole manifest. On failure the error lists every bad line.
    pub fn load(path: &Path) -> Result<Manifest, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            InputError::new(
                path,
                "",
                format!("cannot read the manifest: {e}"),
                "check the path",
            )
        })?;
        // A byte-order mark (some editors write one) is not part of the first line's JSON.
        Manifest::parse(text.strip_prefix('\u{feff}').unwrap_or(&text), path)
    }

    /// Validates manifest text; `path` locates errors and relative scene paths.
    pub fn parse(text: &str, path: &Path) -> Result<Manifest, InputError> {
        let base = path.parent().unwrap_or(Path::new(""));
        let mut items = Vec::new();
        let mut bad: Vec<String> = Vec::new();
        let mut seen: HashMap<String, usize> = HashMap::new();
        let mut files = FileHashes::default();
        let mut lines = 0;
        for (n, line) in text.lines().enumerate() {
            let line_no = n + 1;
            if line.trim().is_empty() {
                continue;
            }
            lines += 1;
            let index = items.len() + bad.len();
            match parse_line(line, (path, line_no), index, base, &mut files) {
                Ok(item) => {
                    // Case-insensitive: "A" and "a" are one folder on macOS and Windows.
                    let key = item.id.to_lowercase();
                    if let Some(first) = seen.get(&key) {
                        bad.push(format!(
                            "line {line_no}: id {:?} is already used on line {first}\n    fix: \
                             give every item its own id (ids are compared ignoring case)",
                            item.id
                        ));
                    } else {
                        seen.insert(key, line_no);
                        items.push(item);
                    }
                }
                Err(message) => bad.push(format!("line {line_no}: {message}")),
            }
        }
        if !bad.is_empty() {
            return Err(InputError::new(
                path,
                "",
                format!(
                    "{} of {lines} items are bad; nothing was simulated:\n  {}",
                    bad.len(),
                    bad.join("\n  ")
                ),
                "fix every line listed, then run again",
            ));
        }
        if items.is_empty() {
            return Err(InputError::new(
                path,
                "",
                "the manifest has no items",
                "write one JSON object a line: {\"id\": \"…\", \"scene\": \"path.toml\", \
                 \"overrides\": {…}}",
            ));
        }
        Ok(Manifest {
            path: path.to_path_buf(),
            items,
        })
    }
}

/// Parses and validates one line; the error is the message after "line N: ".
fn parse_line(
    line: &str,
    (manifest, line_no): (&Path, usize),
    index: usize,
    base: &Path,
    files: &mut FileHashes,
) -> Result<Item, String> {
    const FIX_SHAPE: &str = "write {\"id\": \"…\", \"scene\": \"path.toml\", \"overrides\": {…}}";
    let value: Value = serde_json::from_str(line)
        .map_err(|e| format!("not JSON ({e})\n    fix: {FIX_SHAPE} on one line"))?;
    if let Some(repeat) = unique_keys::first_duplicate(line) {
        return Err(format!(
            "{repeat}; JSON keeps only the last, so the first would be dropped unread\n    \
             fix: write each key once (merge the two objects)"
        ));
    }
    let Value::Object(obj) = &value else {
        return Err(format!("not a JSON object\n    fix: {FIX_SHAPE}"));
    };
    if let Some(k) = obj
        .keys()
        .find(|k| !["id", "scene", "overrides"].contains(&k.as_str()))
    {
        return Err(format!(
            "unknown key {k:?}\n    fix: an item has only \"id\", \"scene\" and \"overrides\""
        ));
    }
    let id = match obj.get("id") {
        Some(Value::String(s)) => s.clone(),
        Some(_) => return Err(format!("\"id\" is not a string\n    fix: {FIX_SHAPE}")),
        None => return Err(format!("no \"id\"\n    fix: {FIX_SHAPE}")),
    };
    check_id(&id).map_err(|p| format!("id {id:?} {p}"))?;
    let scene_arg = match obj.get("scene") {
        Some(Value::String(s)) if !s.is_empty() => s.clone(),
        _ => {
            return Err(format!(
                "item {id:?}: no \"scene\" path\n    fix: {FIX_SHAPE}"
            ))
        }
    };
    let overrides = match obj.get("overrides") {
        None | Some(Value::Null) => serde_json::Map::new(),
        Some(Value::Object(o)) => o.clone(),
        Some(_) => {
            return Err(format!(
                "item {id:?}: \"overrides\" is not an object\n    fix: e.g. \
                 {{\"fabric\": {{\"preset\": \"denim\"}}}}"
            ))
        }
    };
    let scene_path = base.join(&scene_arg);
    let src = std::fs::read_to_string(&scene_path).map_err(|e| {
        format!(
            "item {id:?}: cannot read the scene {}: {e}\n    fix: scene paths are relative to \
             the manifest's folder",
            scene_path.display()
        )
    })?;
    let (scene, table, warnings) = load_scene(&src, &scene_path, &overrides).map_err(|e| {
        let lines: Vec<&str> = e.lines().map(str::trim_start).collect();
        format!("item {id:?}: {}", lines.join("\n    "))
    })?;
    let mut referenced = Vec::new();
    match &scene.cloth {
        ClothSource::Pattern { path, .. } => referenced.push(("pattern", path.clone())),
        ClothSource::Mesh { path, .. } => referenced.push(("cloth mesh", path.clone())),
        ClothSource::Grid { .. } => {}
    }
    // Every body's mesh: an edited second body must change the item's hash too.
    let bodies: Vec<(String, PathBuf)> = (scene.bodies.iter().enumerate())
        .filter_map(|(i, b)| match &b.source {
            BodySource::Mesh { path, .. } => Some((scene.body_table(i), path.clone())),
            _ => None,
        })
        .collect();
    for (table, path) in &bodies {
        referenced.push((table.as_str(), path.clone()));
    }
    let mut hasher = Sha256::new();
    let mut eat = |bytes: &[u8]| {
        hasher.update((bytes.len() as u64).to_le_bytes());
        hasher.update(bytes);
    };
    eat(overrides::canonical(&value).as_bytes());
    eat(src.as_bytes());
    let mut hashed = Vec::new();
    for (role, path) in referenced {
        let sha = files.get(&path).map_err(|e| {
            format!(
                "item {id:?}: the scene's {role} {} cannot be read: {e}\n    fix: check the \
                 path in {} (relative to the scene file)",
                path.display(),
                scene_path.display()
            )
        })?;
        eat(role.as_bytes());
        eat(sha.as_bytes());
        hashed.push((role.to_string(), path, sha));
    }
    let particle_distance_m = match &scene.cloth {
        // Rounded to µm: the scene stores it through an f32.
        ClothSource::Pattern { options, .. } => {
            Some((options.particle_distance * 1e6).round() / 1e6)
        }
        _ => None,
    };
    let fabric = (table.get("fabric").and_then(|f| f.get("preset")))
        .and_then(|p| p.as_str())
        .unwrap_or("custom")
        .to_string();
    Ok(Item {
        manifest: manifest.to_path_buf(),
        line: line_no,
        index,
        id,
        scene_arg,
        scene_path,
        overrides,
        scene,
        fabric,
        particle_distance_m,
        files: hashed,
        inputs_sha256: hex(&hasher.finalize()),
        warnings,
    })
}

/// The scene with `overrides` merged into its tables, validated, the merged TOML table and the
/// merge's warnings. Without overrides the file's own text is validated, so errors point at its
/// lines.
fn load_scene(
    src: &str,
    path: &Path,
    overrides: &serde_json::Map<String, Value>,
) -> Result<(Scene, toml::Table, Vec<String>), String> {
    let mut table: toml::Table = match toml::from_str(src) {
        Ok(t) => t,
        // Let the scene parser word the syntax error, with its line.
        Err(_) => {
            return Err(Scene::parse(src, path).err().map_or_else(
                || "the scene is not valid TOML".to_string(),
                |e| e.to_string(),
            ))
        }
    };
    if overrides.is_empty() {
        let scene = Scene::parse(src, path).map_err(|e| e.to_string())?;
        return Ok((scene, table, Vec::new()));
    }
    let warnings = overrides::merge(&mut table, overrides, "")
        .map_err(|e| format!("overrides: {e}\n  fix: see \"overrides\" in docs/src/batches.md"))?;
    let merged = toml::to_string(&table).map_err(|e| format!("overrides: {e}"))?;
    // Relative paths in the scene (and in overrides) still resolve against the scene file.
    let scene = Scene::parse(&merged, path).map_err(|e| {
        let at = if e.location.is_empty() {
            String::new()
        } else {
            format!("{}: ", e.location)
        };
        format!(
            "{} with this item's overrides: {at}{}\n  fix: {}",
            path.display(),
            e.problem,
            e.fix
        )
    })?;
    Ok((scene, table, warnings))
}

/// Why an id cannot be a folder name, if it cannot.
fn check_id(id: &str) -> Result<(), String> {
    const FIX: &str =
        "\n    fix: use letters, digits, '.', '_' and '-', not starting with '.' or '-'";
    if id.is_empty() {
        return Err(format!("is empty{FIX}"));
    }
    if id.len() > MAX_ID_LEN {
        return Err(format!("is longer than {MAX_ID_LEN} bytes{FIX}"));
    }
    if let Some(c) = id
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Err(format!(
            "contains {c:?}, which is not safe in a folder name{FIX}"
        ));
    }
    if id.starts_with('.') || id.starts_with('-') {
        return Err(format!(
            "starts with {:?} (hidden folders hold unfinished items){FIX}",
            &id[..1]
        ));
    }
    if RESERVED_IDS.contains(&id.to_lowercase().as_str()) {
        return Err(format!("is the name of a report file{FIX}"));
    }
    Ok(())
}

/// File contents hashed once per manifest: 24 items of one pattern read it once.
#[derive(Default)]
struct FileHashes(HashMap<PathBuf, Result<String, String>>);

impl FileHashes {
    fn get(&mut self, path: &Path) -> Result<String, String> {
        self.0
            .entry(path.to_path_buf())
            .or_insert_with(|| {
                std::fs::read(path)
                    .map(|bytes| hex(&Sha256::digest(&bytes)))
                    .map_err(|e| e.to_string())
            })
            .clone()
    }
}

/// Lower-case hexadecimal.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_byte_order_mark_before_the_first_line_is_not_json() {
        // Some editors save UTF-8 with a byte-order mark; scenes read past it, and so does a
        // manifest. The scene need not exist: the line is refused for it, not for the mark.
        let dir = std::env::temp_dir().join(format!("drapekit-bom-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.jsonl");
        std::fs::write(&path, "\u{feff}{\"id\": \"a\", \"scene\": \"none.toml\"}\n").unwrap();
        let e = Manifest::load(&path).unwrap_err().to_string();
        assert!(!e.contains("not JSON"), "{e}");
        assert!(e.contains("none.toml"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn ids_must_be_safe_folder_names() {
        for ok in ["a", "skirt_denim-0.02", "A.b_c-9"] {
            assert!(check_id(ok).is_ok(), "{ok}");
        }
        for bad in [
            "",
            ".",
            "..",
            ".hidden",
            "-x",
            "a/b",
            "a\\b",
            "a b",
            "é",
            "batch.csv",
        ] {
            assert!(check_id(bad).is_err(), "{bad:?} accepted");
        }
        assert!(check_id(&"x".repeat(MAX_ID_LEN + 1)).is_err());
    }
}
