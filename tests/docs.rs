//! The README and the book (docs/src): every internal link and image resolves, every anchor
//! names a heading of its page (with the ids mdBook gives headings), every page is in
//! SUMMARY.md, book links stay inside the book, the README's annotated scene is the shipped
//! scene, and the docs speak to users (no issue numbers or commit hashes). External links are
//! not fetched: CI has no network but package registries.

use pulldown_cmark::{Event, HeadingLevel, Options, Parser, Tag, TagEnd};
use std::collections::{BTreeSet, HashMap};
use std::path::{Component, Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn book_src() -> PathBuf {
    root().join("docs/src")
}

/// Every Markdown page of the book, and the README.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut dirs = vec![book_src()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            // docs/src/images is a link to docs/images: pictures, no pages.
            if path.is_dir() && !path.is_symlink() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages.sort();
    pages
}

fn parser(text: &str) -> Parser<'_> {
    Parser::new_ext(text, Options::ENABLE_TABLES)
}

/// The link and image targets of a page, with the line each is on.
fn links(text: &str) -> Vec<(String, usize)> {
    let line = |offset: usize| text[..offset].matches('\n').count() + 1;
    parser(text)
        .into_offset_iter()
        .filter_map(|(event, range)| match event {
            Event::Start(Tag::Link { dest_url, .. })
            | Event::Start(Tag::Image { dest_url, .. }) => {
                Some((dest_url.to_string(), line(range.start)))
            }
            _ => None,
        })
        .collect()
}

/// The ids mdBook gives a page's headings: the heading's text, lower case, spaces as '-',
/// only letters, digits, '-' and '_' kept; a repeated id gets "-1", "-2", … appended.
fn heading_ids(text: &str) -> BTreeSet<String> {
    let mut ids = BTreeSet::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut heading: Option<String> = None;
    for event in parser(text) {
        match event {
            Event::Start(Tag::Heading { .. }) => heading = Some(String::new()),
            Event::Text(t) | Event::Code(t) => {
                if let Some(h) = heading.as_mut() {
                    h.push_str(&t);
                }
            }
            Event::End(TagEnd::Heading(_)) => {
                let id: String = heading
                    .take()
                    .unwrap()
                    .chars()
                    .filter_map(|c| match c {
                        c if c.is_alphanumeric() || c == '_' || c == '-' => {
                            Some(c.to_lowercase().next().unwrap())
                        }
                        c if c.is_whitespace() => Some('-'),
                        _ => None,
                    })
                    .collect();
                let n = seen.entry(id.clone()).or_insert(0);
                ids.insert(if *n == 0 { id } else { format!("{id}-{n}") });
                *n += 1;
            }
            _ => {}
        }
    }
    ids
}

fn is_external(url: &str) -> bool {
    url.contains("://") || url.starts_with("mailto:")
}

/// `base.join(rel)` with `.` and `..` resolved by name, not through the file system.
fn lexical_join(base: &Path, rel: &str) -> PathBuf {
    let mut out = PathBuf::new();
    for c in base.join(rel).components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

#[test]
fn every_internal_link_and_anchor_resolves() {
    let mut problems = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let in_book = page.starts_with(book_src());
        for (url, line) in links(&text) {
            if is_external(&url) {
                continue;
            }
            checked += 1;
            let here = format!("{}:{line}: {url}", page.display());
            let (path, anchor) = url.split_once('#').unwrap_or((&url, ""));
            let target = if path.is_empty() {
                page.clone()
            } else {
                lexical_join(page.parent().unwrap(), path)
            };
            if !target.exists() {
                problems.push(format!("{here}: no such file"));
                continue;
            }
            if in_book && !target.starts_with(book_src()) {
                problems.push(format!(
                    "{here}: points outside docs/src, which the built book does not hold"
                ));
            }
            if !anchor.is_empty() {
                let ids = heading_ids(&std::fs::read_to_string(&target).unwrap());
                if !ids.contains(anchor) {
                    problems.push(format!("{here}: no heading with this id; ids: {ids:?}"));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
    // The README links into every chapter, and the chapters to each other.
    assert!(checked > 100, "only {checked} internal links found");
}

#[test]
fn summary_lists_every_page_once() {
    let summary = std::fs::read_to_string(book_src().join("SUMMARY.md")).unwrap();
    let listed: Vec<PathBuf> = links(&summary)
        .into_iter()
        .map(|(url, _)| book_src().join(url))
        .collect();
    let unique: BTreeSet<&PathBuf> = listed.iter().collect();
    assert_eq!(unique.len(), listed.len(), "a page is listed twice");
    let on_disk: BTreeSet<PathBuf> = pages()
        .into_iter()
        .filter(|p| p.starts_with(book_src()) && !p.ends_with("SUMMARY.md"))
        .collect();
    let listed: BTreeSet<PathBuf> = listed.into_iter().collect();
    assert_eq!(
        on_disk, listed,
        "pages in docs/src and SUMMARY.md's list differ"
    );
}

#[test]
fn heading_ids_follow_mdbook() {
    let ids = heading_ids(
        "# A `[cloth.pattern]` key\n## Hard cases, 10× faster\n## Hard cases, 10× faster\n",
    );
    let expected: BTreeSet<String> = [
        "a-clothpattern-key",
        "hard-cases-10-faster",
        "hard-cases-10-faster-1",
    ]
    .map(String::from)
    .into();
    assert_eq!(ids, expected);
}

/// The README's annotated scene has the keys and values of the shipped file it says it is.
#[test]
fn the_readme_scene_is_the_shipped_scene() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for event in parser(&readme) {
        match event {
            Event::Start(Tag::CodeBlock(pulldown_cmark::CodeBlockKind::Fenced(lang))) => {
                current = (lang.as_ref() == "toml").then(String::new)
            }
            Event::Text(t) => {
                if let Some(c) = current.as_mut() {
                    c.push_str(&t)
                }
            }
            Event::End(TagEnd::CodeBlock) => blocks.extend(current.take()),
            _ => {}
        }
    }
    assert_eq!(blocks.len(), 1, "the README shows one scene");
    let shown: toml::Table = toml::from_str(&blocks[0]).unwrap();
    let shipped = std::fs::read_to_string(root().join("fixtures/scenes/tshirt_drape_cotton.toml"));
    let shipped: toml::Table = toml::from_str(&shipped.unwrap()).unwrap();
    assert_eq!(shown, shipped);
}

/// Docs are for users: no development history in them.
#[test]
fn docs_name_no_issues_sessions_or_commits() {
    let banned = ["issue ", "issues ", "session", "this project's", "commit "];
    let mut problems = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (i, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for word in banned {
                if lower.contains(word) {
                    problems.push(format!("{}:{}: {line}", page.display(), i + 1));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every heading level steps down by one at most, so the book's table of contents nests.
#[test]
fn headings_nest() {
    let level = |l: HeadingLevel| l as usize;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let mut last = 0;
        for event in parser(&text) {
            if let Event::Start(Tag::Heading { level: l, .. }) = event {
                assert!(
                    level(l) <= last + 1,
                    "{}: a level-{} heading after level {last}",
                    page.display(),
                    level(l)
                );
                last = level(l);
            }
        }
    }
}
