//! Which files a `path` parameter names: a directory (every .png/.jpg/.jpeg/.tif/.tiff in it) or
//! a glob whose wildcards (`*`, `?`) are in the last path component. Sorted by name so frame order
//! is reproducible.

use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum FileListError {
    #[error("{path}: cannot list directory ({reason})")]
    Unreadable { path: String, reason: String },
    #[error("{0}: no image files (.png, .jpg, .jpeg, .tif, .tiff) match")]
    NoMatch(String),
    #[error("{0}: wildcards are only supported in the file-name part")]
    WildcardInDirectory(String),
}

const EXTENSIONS: [&str; 5] = ["png", "jpg", "jpeg", "tif", "tiff"];

fn is_image(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Shell-style match of `*` (any run) and `?` (one character).
pub fn wildcard_match(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    let (mut pi, mut ni, mut star, mut mark) = (0, 0, None, 0);
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some(pi);
            mark = ni;
            pi += 1;
        } else if let Some(s) = star {
            pi = s + 1;
            mark += 1;
            ni = mark;
        } else {
            return false;
        }
    }
    p[pi..].iter().all(|&c| c == '*')
}

/// The image files `spec` names, sorted.
pub fn list_image_files(spec: &str) -> Result<Vec<PathBuf>, FileListError> {
    let path = Path::new(spec);
    let (dir, pattern) = if path.is_dir() {
        (path.to_path_buf(), "*".to_string())
    } else {
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        if dir.to_string_lossy().contains(['*', '?']) {
            return Err(FileListError::WildcardInDirectory(spec.into()));
        }
        (
            dir.to_path_buf(),
            path.file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    };
    let entries = std::fs::read_dir(&dir).map_err(|e| FileListError::Unreadable {
        path: dir.display().to_string(),
        reason: e.to_string(),
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && is_image(p))
        .filter(|p| {
            p.file_name()
                .is_some_and(|f| wildcard_match(&pattern, &f.to_string_lossy()))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(FileListError::NoMatch(spec.into()));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_and_directories() {
        assert!(wildcard_match("view_*.png", "view_01.png"));
        assert!(wildcard_match("v?ew*", "view_01.png"));
        assert!(!wildcard_match("view_*.png", "view_01.jpg"));
        assert!(wildcard_match("*", "a"));
        let dir =
            std::env::temp_dir().join(format!("metrocell-camera-list-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for f in ["b.png", "a.PNG", "c.txt", "d.tiff"] {
            std::fs::write(dir.join(f), b"x").unwrap();
        }
        let names = |v: Vec<PathBuf>| {
            v.iter()
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            names(list_image_files(dir.to_str().unwrap()).unwrap()),
            ["a.PNG", "b.png", "d.tiff"]
        );
        assert_eq!(
            names(list_image_files(dir.join("*.png").to_str().unwrap()).unwrap()),
            ["b.png"]
        );
        assert!(matches!(
            list_image_files(dir.join("*.jpg").to_str().unwrap()),
            Err(FileListError::NoMatch(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
