//! Turning a launch `node` into the command line a ROS 2 node understands:
//! `EXEC [args...] --ros-args -r __node:=NAME -r __ns:=NS (-p name:=value | --params-file F)... -r from:=to...`
//!
//! Parameters keep the order in which they are declared (a later one overrides an earlier one in
//! rcl, so order matters); remaps follow them. Parameter values are written as YAML, which is what
//! rcl parses after `:=`: scalars as written, lists and maps in flow syntax (`[1, 2]`, `{a: 1}`).

use std::path::{Path, PathBuf};

/// One `param` entry of a node, in declaration order.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamArg {
    /// `-p name:=value`; `value` is already YAML text.
    Value { name: String, value: String },
    /// `--params-file path`.
    File(PathBuf),
}

/// Builds the `--ros-args ...` tail. Empty when there is nothing to say.
pub fn ros_args(
    name: Option<&str>,
    namespace: Option<&str>,
    params: &[ParamArg],
    remaps: &[(String, String)],
    extra_ros_args: &[String],
) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(name) = name {
        out.extend(["-r".to_string(), format!("__node:={name}")]);
    }
    if let Some(ns) = namespace {
        out.extend(["-r".to_string(), format!("__ns:={ns}")]);
    }
    for p in params {
        match p {
            ParamArg::Value { name, value } => {
                out.extend(["-p".to_string(), format!("{name}:={value}")])
            }
            ParamArg::File(path) => {
                out.extend(["--params-file".to_string(), path.display().to_string()])
            }
        }
    }
    for (from, to) in remaps {
        out.extend(["-r".to_string(), format!("{from}:={to}")]);
    }
    out.extend(extra_ros_args.iter().cloned());
    if !out.is_empty() {
        out.insert(0, "--ros-args".to_string());
    }
    out
}

/// The namespace a node ends up in, given the namespace pushed by enclosing groups
/// (`push-ros-namespace`) and the node's own `namespace`: an absolute node namespace wins,
/// a relative one is appended to the pushed one. `None` when neither is set.
/// The result starts with `/` and has no trailing or doubled `/` (except the root `/`).
pub fn combine_namespace(pushed: Option<&str>, own: Option<&str>) -> Option<String> {
    let joined = match (pushed, own) {
        (_, Some(own)) if own.starts_with('/') => own.to_string(),
        (Some(pushed), Some(own)) => format!("{pushed}/{own}"),
        (Some(pushed), None) => pushed.to_string(),
        (None, Some(own)) => own.to_string(),
        (None, None) => return None,
    };
    Some(normalize_namespace(&joined))
}

/// Leading `/`, no empty segments, no trailing `/`.
pub fn normalize_namespace(ns: &str) -> String {
    let parts: Vec<&str> = ns.split('/').filter(|s| !s.is_empty()).collect();
    format!("/{}", parts.join("/"))
}

/// Where executables are looked for by default: the directory of the running executable (cargo
/// puts every workspace binary there; when that directory is `deps/`, as for test binaries, its
/// parent too), then every directory on `PATH`.
pub fn default_search_path() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        if let Some(dir) = exe.parent() {
            dirs.push(dir.to_path_buf());
            if dir.file_name().is_some_and(|n| n == "deps") {
                if let Some(up) = dir.parent() {
                    dirs.push(up.to_path_buf());
                }
            }
        }
    }
    if let Some(path) = std::env::var_os("PATH") {
        dirs.extend(std::env::split_paths(&path));
    }
    dirs
}

/// Finds `exec`: a name containing `/` is a path (relative to the working directory) and is
/// used as is; a bare name is looked up in `search` in order. Only executable files count.
pub fn resolve_executable(exec: &str, search: &[PathBuf]) -> Result<PathBuf, String> {
    if exec.contains('/') {
        let path = PathBuf::from(exec);
        return if is_executable_file(&path) {
            Ok(path)
        } else if path.exists() {
            Err(format!("'{exec}' is not an executable file"))
        } else {
            Err(format!("executable '{exec}' does not exist"))
        };
    }
    search
        .iter()
        .map(|dir| dir.join(exec))
        .find(|candidate| is_executable_file(candidate))
        .ok_or_else(|| {
            let shown: Vec<String> = search.iter().map(|d| d.display().to_string()).collect();
            format!(
                "executable '{exec}' not found (searched: {})",
                shown.join(":")
            )
        })
}

fn is_executable_file(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(path)
        .map(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        .unwrap_or(false)
}

/// Splits a command string the way a POSIX shell would split words (no expansion):
/// whitespace separates, `'...'` is literal, `"..."` honours `\"` and `\\`, `\x` outside quotes is `x`.
pub fn shell_split(text: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        match c {
            c if c.is_whitespace() => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        None => return Err(format!("unterminated single quote in '{text}'")),
                        Some('\'') => break,
                        Some(c) => word.push(c),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        None => return Err(format!("unterminated double quote in '{text}'")),
                        Some('"') => break,
                        Some('\\') => match chars.next() {
                            Some(c @ ('"' | '\\' | '$' | '`')) => word.push(c),
                            Some(c) => {
                                word.push('\\');
                                word.push(c);
                            }
                            None => return Err(format!("unterminated double quote in '{text}'")),
                        },
                        Some(c) => word.push(c),
                    }
                }
            }
            '\\' => {
                in_word = true;
                if let Some(c) = chars.next() {
                    word.push(c);
                }
            }
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    if in_word {
        words.push(word);
    }
    Ok(words)
}

/// True when a string, written bare after `name:=`, would be read by a YAML parser as something
/// other than that same string (a bool, number, null, collection, or a syntax error).
pub fn yaml_string_needs_quotes(s: &str) -> bool {
    if s.is_empty() || s.trim() != s {
        return true;
    }
    let lower = s.to_ascii_lowercase();
    if matches!(
        lower.as_str(),
        "true"
            | "false"
            | "yes"
            | "no"
            | "on"
            | "off"
            | "y"
            | "n"
            | "null"
            | "~"
            | ".inf"
            | "+.inf"
            | "-.inf"
            | ".nan"
    ) {
        return true;
    }
    if looks_numeric(s) {
        return true;
    }
    let first = s.chars().next().unwrap_or(' ');
    if "[]{},&*!|>'\"%@`#".contains(first)
        || s.starts_with("- ")
        || s.starts_with("? ")
        || s.starts_with(": ")
    {
        return true;
    }
    s.contains(": ") || s.contains(" #") || s.ends_with(':')
}

fn looks_numeric(s: &str) -> bool {
    let t = s.strip_prefix(['+', '-']).unwrap_or(s);
    if t.starts_with("0x") || t.starts_with("0o") {
        return true;
    }
    s.replace('_', "").parse::<f64>().is_ok()
}

/// Single-quoted YAML string (`'` doubled inside).
pub fn yaml_single_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "''"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros_args_order_and_shape() {
        let params = vec![
            ParamArg::Value {
                name: "rate".into(),
                value: "5.0".into(),
            },
            ParamArg::File("/p/cam.yaml".into()),
        ];
        let remaps = vec![("image".to_string(), "/cam0/image".to_string())];
        assert_eq!(
            ros_args(Some("cam"), Some("/cell"), &params, &remaps, &[]),
            [
                "--ros-args",
                "-r",
                "__node:=cam",
                "-r",
                "__ns:=/cell",
                "-p",
                "rate:=5.0",
                "--params-file",
                "/p/cam.yaml",
                "-r",
                "image:=/cam0/image"
            ]
        );
        assert!(ros_args(None, None, &[], &[], &[]).is_empty());
    }

    #[test]
    fn namespaces_combine_like_push_ros_namespace() {
        assert_eq!(combine_namespace(None, None), None);
        assert_eq!(
            combine_namespace(None, Some("cell")).as_deref(),
            Some("/cell")
        );
        assert_eq!(
            combine_namespace(Some("/a"), Some("b/")).as_deref(),
            Some("/a/b")
        );
        assert_eq!(
            combine_namespace(Some("/a"), Some("/abs")).as_deref(),
            Some("/abs")
        );
        assert_eq!(
            combine_namespace(Some("a//b"), None).as_deref(),
            Some("/a/b")
        );
        assert_eq!(combine_namespace(None, Some("/")).as_deref(), Some("/"));
    }

    #[test]
    fn shell_split_handles_quotes() {
        assert_eq!(
            shell_split(r#"a 'b c' "d \"e\"" f\ g"#).unwrap(),
            ["a", "b c", "d \"e\"", "f g"]
        );
        assert_eq!(shell_split("  ").unwrap(), Vec::<String>::new());
        assert_eq!(shell_split("x ''").unwrap(), ["x", ""]);
        assert!(shell_split("a 'b")
            .unwrap_err()
            .contains("unterminated single quote"));
    }

    #[test]
    fn quoting_decisions() {
        for s in [
            "1", "2.5", "-3", "1e3", "true", "No", "null", "", " a", "[1]", "a: b", "#x", "0x1f",
        ] {
            assert!(yaml_string_needs_quotes(s), "{s:?} should need quotes");
        }
        for s in ["hello", "/cam0/image", "a_b", "cell-1", "v1.2.3"] {
            assert!(!yaml_string_needs_quotes(s), "{s:?} should not need quotes");
        }
        assert_eq!(yaml_single_quote("it's"), "'it''s'");
    }

    #[test]
    fn resolves_bare_names_in_search_order_and_rejects_missing() {
        let dir =
            std::env::temp_dir().join(format!("metrocell-launch-resolve-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let exe = dir.join("tool");
        std::fs::write(&exe, "#!/bin/sh\n").unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).unwrap();
        std::fs::write(dir.join("plain"), "x").unwrap();
        let search = vec![PathBuf::from("/nonexistent"), dir.clone()];
        assert_eq!(resolve_executable("tool", &search).unwrap(), exe);
        assert!(resolve_executable("plain", &search)
            .unwrap_err()
            .contains("not found"));
        assert!(
            resolve_executable(dir.join("plain").to_str().unwrap(), &search)
                .unwrap_err()
                .contains("not an executable file")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
