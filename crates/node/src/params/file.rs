//! ROS 2 parameters files (the `--params-file` format of rcl):
//!
//! ```yaml
//! /**:                      # every node; also `talker:` (= `/talker`), `/ns/talker:`, `/ns/*:`
//!   ros__parameters:
//!     rate_hz: 20.0
//!     tracker:              # nested maps are flattened with `.`: `tracker.port`
//!       port: 5000
//! ```
//!
//! Node keys may also be nested (`/ns:` → `talker:` → `ros__parameters:`). A key without a leading
//! `/` is taken as absolute (rcl prefixes `/`). `*` matches one name token, `**` any number.

use std::path::{Path, PathBuf};

use super::value::ParamValue;

/// The parameters one section of a params file gives to the nodes its key matches.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamsFileSection {
    /// Node name pattern, normalised to start with `/` (e.g. `/**`, `/ns/talker`).
    pub node_pattern: String,
    /// Flattened parameter names (`a.b.c`) and their values, in file order.
    pub params: Vec<(String, ParamValue)>,
}

/// Errors reading a parameters file; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ParamsFileError {
    #[error("parameters file '{}' cannot be read: {source}; check the path given to --params-file (relative paths are taken from the current directory)", path.display())]
    Missing {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("parameters file '{}': YAML syntax error at line {line}, column {column}: {message}", path.display())]
    Syntax {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("parameters file '{}': at '{key}': {message}", path.display())]
    Structure {
        path: PathBuf,
        key: String,
        message: String,
    },
}

/// Read and parse a parameters file.
pub fn read_params_file(path: &Path) -> Result<Vec<ParamsFileSection>, ParamsFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| ParamsFileError::Missing {
        path: path.to_path_buf(),
        source,
    })?;
    parse_params_file(&text, path)
}

/// Parse parameters-file text; `path` is only used in error messages.
pub fn parse_params_file(
    text: &str,
    path: &Path,
) -> Result<Vec<ParamsFileSection>, ParamsFileError> {
    let doc: serde_yaml::Value = serde_yaml::from_str(text).map_err(|e| {
        let (line, column) = e
            .location()
            .map(|l| (l.line(), l.column()))
            .unwrap_or((0, 0));
        ParamsFileError::Syntax {
            path: path.to_path_buf(),
            line,
            column,
            message: e.to_string(),
        }
    })?;
    let structure = |key: &str, message: &str| ParamsFileError::Structure {
        path: path.to_path_buf(),
        key: key.to_string(),
        message: message.to_string(),
    };
    let mut sections = Vec::new();
    match doc {
        serde_yaml::Value::Null => {}
        serde_yaml::Value::Mapping(map) => collect_sections(&map, "", &mut sections, &structure)?,
        _ => {
            return Err(structure(
                "<top level>",
                "expected a mapping of node names to `ros__parameters:`",
            ))
        }
    }
    Ok(sections)
}

fn key_text(key: &serde_yaml::Value) -> String {
    match key {
        serde_yaml::Value::String(s) => s.clone(),
        other => serde_yaml::to_string(other)
            .unwrap_or_default()
            .trim()
            .to_string(),
    }
}

fn collect_sections(
    map: &serde_yaml::Mapping,
    prefix: &str,
    out: &mut Vec<ParamsFileSection>,
    structure: &dyn Fn(&str, &str) -> ParamsFileError,
) -> Result<(), ParamsFileError> {
    for (key, value) in map {
        let key = key_text(key);
        if key == "ros__parameters" {
            if prefix.is_empty() {
                return Err(structure(
                    "ros__parameters",
                    "`ros__parameters:` must be under a node name such as `/**:`",
                ));
            }
            let mut params = Vec::new();
            match value {
                serde_yaml::Value::Mapping(m) => flatten(m, "", &mut params, prefix, structure)?,
                serde_yaml::Value::Null => {}
                _ => {
                    return Err(structure(
                        &format!("{prefix}/ros__parameters"),
                        "expected a mapping of parameter names to values",
                    ))
                }
            }
            out.push(ParamsFileSection {
                node_pattern: prefix.to_string(),
                params,
            });
            continue;
        }
        let node = join_node_path(prefix, &key);
        match value {
            serde_yaml::Value::Mapping(m) => collect_sections(m, &node, out, structure)?,
            _ => {
                return Err(structure(
                    &node,
                    "expected `ros__parameters:` (or a nested node name) under a node name",
                ))
            }
        }
    }
    Ok(())
}

fn join_node_path(prefix: &str, key: &str) -> String {
    let key = key.trim_matches('/');
    if prefix.is_empty() {
        format!("/{key}")
    } else {
        format!("{}/{key}", prefix.trim_end_matches('/'))
    }
}

fn flatten(
    map: &serde_yaml::Mapping,
    prefix: &str,
    out: &mut Vec<(String, ParamValue)>,
    node: &str,
    structure: &dyn Fn(&str, &str) -> ParamsFileError,
) -> Result<(), ParamsFileError> {
    for (key, value) in map {
        let name = if prefix.is_empty() {
            key_text(key)
        } else {
            format!("{prefix}.{}", key_text(key))
        };
        match value {
            serde_yaml::Value::Mapping(m) => flatten(m, &name, out, node, structure)?,
            other => {
                let v = ParamValue::from_yaml(other)
                    .map_err(|m| structure(&format!("{node} ros__parameters {name}"), &m))?;
                out.push((name, v));
            }
        }
    }
    Ok(())
}

/// Does a section's node pattern apply to the node with fully qualified name `node_fqn`?
pub fn pattern_matches_node(pattern: &str, node_fqn: &str) -> bool {
    let pat: Vec<&str> = pattern.split('/').filter(|t| !t.is_empty()).collect();
    let name: Vec<&str> = node_fqn.split('/').filter(|t| !t.is_empty()).collect();
    glob_tokens(&pat, &name)
}

fn glob_tokens(pat: &[&str], name: &[&str]) -> bool {
    match pat.split_first() {
        None => name.is_empty(),
        Some((&"**", rest)) => (0..=name.len()).any(|skip| glob_tokens(rest, &name[skip..])),
        Some((p, rest)) => match name.split_first() {
            Some((n, name_rest)) => (*p == "*" || p == n) && glob_tokens(rest, name_rest),
            None => false,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"
/**:
  ros__parameters:
    use_sim_time: false
    rate_hz: 20
talker:
  ros__parameters:
    topic: chatter
    tracker:
      port: 5000
      hosts: [a, b]
/cell:
  probe:
    ros__parameters:
      gain: 1.5
"#;

    #[test]
    fn sections_and_flattening() {
        let s = parse_params_file(FILE, Path::new("p.yaml")).unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(s[0].node_pattern, "/**");
        assert_eq!(
            s[0].params,
            vec![
                ("use_sim_time".into(), ParamValue::Bool(false)),
                ("rate_hz".into(), ParamValue::Integer(20))
            ]
        );
        assert_eq!(s[1].node_pattern, "/talker");
        assert_eq!(
            s[1].params[1],
            ("tracker.port".into(), ParamValue::Integer(5000))
        );
        assert_eq!(
            s[1].params[2],
            (
                "tracker.hosts".into(),
                ParamValue::StringArray(vec!["a".into(), "b".into()])
            )
        );
        assert_eq!(s[2].node_pattern, "/cell/probe");
        assert_eq!(s[2].params, vec![("gain".into(), ParamValue::Double(1.5))]);
    }

    #[test]
    fn node_patterns() {
        assert!(pattern_matches_node("/**", "/talker"));
        assert!(pattern_matches_node("/**", "/a/b/talker"));
        assert!(pattern_matches_node("/talker", "/talker"));
        assert!(!pattern_matches_node("/talker", "/ns/talker"));
        assert!(pattern_matches_node("/ns/*", "/ns/talker"));
        assert!(!pattern_matches_node("/ns/*", "/ns/a/talker"));
        assert!(pattern_matches_node("/**/talker", "/ns/a/talker"));
        assert!(!pattern_matches_node("/**/talker", "/ns/listener"));
    }

    #[test]
    fn syntax_error_names_file_and_line() {
        let bad = "/**:\n  ros__parameters:\n    a: [1, 2\n    b: 3\n";
        match parse_params_file(bad, Path::new("/cfg/bad.yaml")) {
            Err(e @ ParamsFileError::Syntax { line, .. }) => {
                assert!(line >= 3, "line {line}");
                assert!(e.to_string().contains("/cfg/bad.yaml"));
                assert!(e.to_string().contains(&format!("line {line}")));
            }
            other => panic!("expected syntax error, got {other:?}"),
        }
    }

    #[test]
    fn structure_errors_name_the_key() {
        let e = parse_params_file("talker:\n  rate: 3\n", Path::new("f.yaml")).unwrap_err();
        assert!(e.to_string().contains("/talker/rate"), "{e}");
        let e = parse_params_file(
            "/**:\n  ros__parameters:\n    a: [1, x]\n",
            Path::new("f.yaml"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("ros__parameters a"), "{e}");
    }

    #[test]
    fn missing_file_says_what_to_do() {
        let e = read_params_file(Path::new("/nonexistent/params.yaml")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("/nonexistent/params.yaml") && m.contains("--params-file"),
            "{m}"
        );
    }
}
