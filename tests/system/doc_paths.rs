//! Every file or directory a document cites exists in the repository (issue 11 item 7: docs
//! that cited files not in the tree).
//!
//! Documents: every `.md` file, and the doc comments (`//!`, `///`) of every `.rs` file, outside
//! `target/`, `.venv/`, `node_modules/`, `.git/` and `third_party/` (vendored upstream sources). A citation is a word made of path
//! characters that contains a `/` and ends in a file extension (`crates/bag/README.md`,
//! `nodes/thermal/src/replay.rs`, `tests/py/opencv_render.py`). It must name an existing path relative to the
//! document's directory, to one of that directory's ancestors (a crate's README citing
//! `src/lib.rs`, a test citing `tests/isolated`), or to the repository root. Words with
//! placeholders (`<node>`, `*`, `{`, a part of one to three capitals such as `DIR/model.yaml` or
//! `case_NN`) and paths under `target/` (build outputs) are not citations, nor absolute paths
//! outside a checkout (`/tmp/out.json` in an example); a path into a checkout (`/work/…`,
//! `/home/…`, `/root/…`) is machine-specific and always an error (a reader's checkout is
//! somewhere else).
//!
//! Run: `cargo test -p metrocell-system-tests --test doc_paths`

use std::path::{Path, PathBuf};

use system_tests::workspace_root;

const EXTENSIONS: &[&str] = &[
    "rs", "md", "py", "yaml", "yml", "toml", "msg", "json", "sh", "txt", "js", "csv", "html",
    "xml", "lock", "png",
];
// `third_party/` holds vendored upstream sources whose documents cite their own repositories.
const SKIPPED_DIRS: &[&str] = &["target", ".venv", "node_modules", ".git", "third_party"];

fn documents(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if p.is_dir() {
            if !SKIPPED_DIRS.contains(&name.as_str()) {
                documents(&p, out);
            }
        } else if name.ends_with(".md") || name.ends_with(".rs") {
            out.push(p);
        }
    }
}

fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

/// The words of `line` that cite a path (see the module doc), trailing punctuation removed.
fn citations(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if !is_path_char(chars[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && is_path_char(chars[i]) {
            i += 1;
        }
        let before = if start > 0 { chars[start - 1] } else { ' ' };
        let after = chars.get(i).copied().unwrap_or(' ');
        let word: String = chars[start..i].iter().collect();
        let word = word.trim_end_matches(['.', '/']).to_string();
        // placeholders, URLs (`https://host/x.html`), globs and Rust paths are not citations
        if matches!(before, '<' | '>' | '*' | '{' | '}' | '$' | '@')
            || matches!(after, '<' | '>' | '*' | '{' | '}' | ':')
        {
            continue;
        }
        if !word.contains('/')
            || word.starts_with("target/")
            || word.contains("//")
            || is_placeholder(&word)
        {
            continue;
        }
        // absolute paths: outputs in examples (/tmp/x.json) are not citations; a checkout's path is
        if word.starts_with('/')
            && !["/work/", "/home/", "/root/"]
                .iter()
                .any(|p| word.starts_with(p))
        {
            continue;
        }
        let ext = word.rsplit_once('.');
        if let Some((stem, ext)) = ext {
            if EXTENSIONS.contains(&ext) && !stem.ends_with('/') {
                out.push(word);
            }
        }
    }
    out
}

/// A path written with a placeholder in it: a part of one to three capitals (`DIR/model.yaml`,
/// `cases/case_NN/truth.yaml`, `OUT/a.b.csv`), which the reader replaces.
fn is_placeholder(word: &str) -> bool {
    word.split(['/', '_', '.', '-'])
        .any(|t| (1..=3).contains(&t.len()) && t.chars().all(|c| c.is_ascii_uppercase()))
}

/// The lines of `doc` that are documentation: all of a Markdown file, the `//!` and `///`
/// comments of Rust source.
fn doc_lines(doc: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(doc).unwrap_or_default();
    let markdown = doc.extension().is_some_and(|e| e == "md");
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            markdown || l.trim_start().starts_with("//!") || l.trim_start().starts_with("///")
        })
        .map(|(n, l)| (n + 1, l.to_string()))
        .collect()
}

fn resolves(root: &Path, doc: &Path, cited: &str) -> bool {
    let mut dir = doc.parent();
    while let Some(d) = dir {
        if d.join(cited).exists() {
            return true;
        }
        if d == root {
            break;
        }
        dir = d.parent();
    }
    root.join(cited).exists()
}

#[test]
fn every_path_a_document_cites_exists() {
    let root = workspace_root();
    let mut docs = Vec::new();
    documents(&root, &mut docs);
    assert!(
        docs.iter().any(|d| d.ends_with("README.md")),
        "no documents found under {}",
        root.display()
    );
    let mut missing = Vec::new();
    let mut checked = 0;
    for doc in &docs {
        for (n, line) in doc_lines(doc) {
            for cited in citations(&line) {
                checked += 1;
                let rel = doc.strip_prefix(&root).unwrap().display().to_string();
                if cited.starts_with('/') {
                    // absolute: "/work/x/tests/isolated" → machine-specific
                    missing.push(format!(
                        "{rel}:{n}: {cited} (an absolute path: cite it from the repository root)"
                    ));
                } else if !resolves(&root, doc, &cited) {
                    missing.push(format!("{rel}:{n}: {cited}"));
                }
            }
        }
    }
    eprintln!("{checked} citations in {} documents", docs.len());
    assert!(
        checked > 100,
        "only {checked} citations found: the scanner is broken"
    );
    assert!(
        missing.is_empty(),
        "documents cite paths that do not exist:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_scanner_finds_citations_and_skips_what_is_not_one() {
    assert_eq!(
        citations("see `crates/bag/README.md`, and src/replay.rs."),
        vec!["crates/bag/README.md", "src/replay.rs"]
    );
    assert_eq!(
        citations("run /work/main/tests/isolated.sh now"),
        vec!["/work/main/tests/isolated.sh"]
    );
    assert!(citations(
        "-o /tmp/suite_results.json, then DIR/index.html and bags/cases/case_NN/truth.yaml"
    )
    .is_empty());
    // topics, types, placeholders, URLs, globs, build outputs: not citations
    assert!(citations("`tracker/measurements` (`metrocell_msgs/TrackerMeasurement`)").is_empty());
    assert!(citations(
        "nodes/<node>/src/main.rs https://example.org/a/b.html views/*.png target/release/x.json"
    )
    .is_empty());
    let root = workspace_root();
    assert!(
        resolves(&root, &root.join("crates/bagtools/README.md"), "src/lib.rs"),
        "relative to the document's directory"
    );
    assert!(
        resolves(
            &root,
            &root.join("nodes/tracker/tests/tcp_backend.rs"),
            "tests/isolated"
        ),
        "relative to the repository root"
    );
    assert!(
        !resolves(
            &root,
            &root.join("README.md"),
            "launch-configs/cell.launch.yaml"
        ),
        "a file that is not there"
    );
}

/// The directories holding a package of the workspace (a `Cargo.toml` with `[package]`).
fn packages(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for parent in ["crates", "nodes"] {
        for e in std::fs::read_dir(root.join(parent)).unwrap() {
            let dir = e.unwrap().path();
            if dir.join("Cargo.toml").exists() {
                out.push(dir);
            }
        }
    }
    out.extend(["cli", "msgs", "tests"].iter().map(|d| root.join(d)));
    out.sort();
    out
}

#[test]
fn every_package_has_a_readme_and_every_crate_is_in_the_layout_table() {
    let root = workspace_root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let mut problems = Vec::new();
    for dir in packages(&root) {
        let rel = dir.strip_prefix(&root).unwrap().display().to_string();
        if !dir.join("README.md").exists() {
            problems.push(format!(
                "{rel} has no README.md (what it is, its modules, how to test it)"
            ));
        }
        if rel.starts_with("crates/") && !readme.contains(&format!("| `{rel}` |")) {
            problems.push(format!(
                "{rel} is missing from the layout table of README.md"
            ));
        }
    }
    assert!(
        packages(&root).len() >= 20,
        "the package scan is broken: {:?}",
        packages(&root)
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
