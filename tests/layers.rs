//! The module layers run one way: a top-level module of `src/` imports (`crate::x`) only from
//! its own layer or the layers below. `../shared/tools/layers.py` refuses cycles; this test
//! also refuses an upward import that does not (yet) close a cycle. The table is the one in
//! docs/src/architecture.md.

use std::collections::BTreeMap;
use std::path::Path;

const LAYERS: &[(&str, u32)] = &[
    ("error", 1),
    ("check", 1),
    ("atomic_file", 1),
    ("suggest", 1),
    ("toml_message", 1),
    ("progress", 1),
    ("notice", 1),
    ("glb", 1),
    ("mesh", 2),
    ("pattern", 2),
    ("body", 2),
    ("scene", 3),
    ("model", 4),
    ("plan", 5),
    ("solver", 5),
    ("cpu", 6),
    ("gpu", 6),
    ("metrics", 6),
    ("sim", 7),
    ("run", 8),
    ("run_folder", 8),
    ("checkpoint", 8),
    ("output", 8),
    ("health", 8),
    ("export", 8),
    ("bench", 8),
    ("plot", 8),
    ("preview", 8),
    ("batch", 8),
    // The binary's own modules (not in lib.rs): they see the library as `drapekit::`.
    ("cli", 9),
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn modules_import_only_downward() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let layer: BTreeMap<&str, u32> = LAYERS.iter().copied().collect();
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut upward = Vec::new();
    for file in files {
        let rel = file.strip_prefix(&src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_str()
            .unwrap();
        let top = top.trim_end_matches(".rs");
        if top == "lib" || top == "main" {
            continue;
        }
        let Some(&own) = layer.get(top) else {
            panic!("src/{top} has no layer: add it to LAYERS here and to docs/src/architecture.md");
        };
        let text = std::fs::read_to_string(&file).unwrap();
        // Unit tests may reach anywhere.
        let text = text.split("#[cfg(test)]").next().unwrap();
        for (at, _) in text.match_indices("crate::") {
            let name: String = text[at + 7..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if let Some(&theirs) = layer.get(name.as_str()) {
                if theirs > own {
                    upward.push(format!(
                        "{} (layer {own}) imports crate::{name} (layer {theirs})",
                        rel.display()
                    ));
                }
            }
        }
    }
    assert!(upward.is_empty(), "upward imports:\n{}", upward.join("\n"));
}
