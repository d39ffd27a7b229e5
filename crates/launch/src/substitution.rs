//! `$(...)` substitutions of the ROS 2 launch frontends.
//!
//! Supported: `$(var NAME)`, `$(env NAME)`, `$(env NAME DEFAULT)`, `$(optenv NAME)`,
//! `$(optenv NAME DEFAULT)`, `$(find-pkg-share PKG)`, `$(dirname)`, `$(filename)`.
//! Arguments are separated by whitespace; an argument may be quoted with `'...'` or `"..."`
//! (taken literally, so `$(env PREFIX '')` gives an empty default) and may itself contain
//! substitutions (`$(env A $(var b))`). Anything else inside `$(` is an error naming it.

use std::path::{Path, PathBuf};

/// What substitutions read. Errors are plain messages; the caller adds file, line and key.
pub(crate) struct SubstitutionScope<'a> {
    /// Launch configurations (`arg` and `let` values) visible here.
    pub vars: &'a std::collections::BTreeMap<String, String>,
    /// The environment lookup (`env`, `optenv`).
    pub env: &'a dyn Fn(&str) -> Option<String>,
    /// The launch file being read (`dirname`, `filename`).
    pub current_file: &'a Path,
    /// `find-pkg-share` lookup.
    pub find_pkg_share: &'a dyn Fn(&str) -> Result<PathBuf, String>,
}

pub(crate) const KNOWN_SUBSTITUTIONS: &str = "var, env, optenv, find-pkg-share, dirname, filename";

/// Expand every `$(...)` in `text`.
pub(crate) fn substitute(text: &str, scope: &SubstitutionScope) -> Result<String, String> {
    if !text.contains("$(") {
        return Ok(text.to_string());
    }
    let chars: Vec<char> = text.chars().collect();
    let mut pos = 0;
    let mut out = String::new();
    while pos < chars.len() {
        if chars[pos] == '$' && chars.get(pos + 1) == Some(&'(') {
            out.push_str(&expand_one(&chars, &mut pos, scope)?);
        } else {
            out.push(chars[pos]);
            pos += 1;
        }
    }
    Ok(out)
}

/// Expand the substitution starting at `chars[*pos] == '$'`; leaves `pos` after its `)`.
fn expand_one(
    chars: &[char],
    pos: &mut usize,
    scope: &SubstitutionScope,
) -> Result<String, String> {
    let start = *pos;
    *pos += 2;
    let unterminated = || {
        let shown: String = chars[start..].iter().collect();
        format!("unterminated substitution '{shown}' (missing ')')")
    };
    let mut name = String::new();
    while *pos < chars.len() && !chars[*pos].is_whitespace() && chars[*pos] != ')' {
        name.push(chars[*pos]);
        *pos += 1;
    }
    let mut args: Vec<String> = Vec::new();
    loop {
        while *pos < chars.len() && chars[*pos].is_whitespace() {
            *pos += 1;
        }
        match chars.get(*pos) {
            None => return Err(unterminated()),
            Some(')') => {
                *pos += 1;
                break;
            }
            Some(_) => args.push(read_argument(chars, pos, scope, &unterminated)?),
        }
    }
    apply(&name, &args, scope)
}

/// One whitespace-delimited argument, made of plain runs, quoted runs and nested substitutions.
fn read_argument(
    chars: &[char],
    pos: &mut usize,
    scope: &SubstitutionScope,
    unterminated: &dyn Fn() -> String,
) -> Result<String, String> {
    let mut arg = String::new();
    while let Some(&c) = chars.get(*pos) {
        if c.is_whitespace() || c == ')' {
            break;
        }
        if c == '\'' || c == '"' {
            *pos += 1;
            loop {
                match chars.get(*pos) {
                    None => return Err(unterminated()),
                    Some(&q) if q == c => {
                        *pos += 1;
                        break;
                    }
                    Some(&other) => {
                        arg.push(other);
                        *pos += 1;
                    }
                }
            }
        } else if c == '$' && chars.get(*pos + 1) == Some(&'(') {
            arg.push_str(&expand_one(chars, pos, scope)?);
        } else {
            arg.push(c);
            *pos += 1;
        }
    }
    Ok(arg)
}

fn apply(name: &str, args: &[String], scope: &SubstitutionScope) -> Result<String, String> {
    let arity = |min: usize, max: usize, usage: &str| {
        if args.len() < min || args.len() > max {
            Err(format!(
                "$({name}) takes {usage}, got {} argument(s)",
                args.len()
            ))
        } else {
            Ok(())
        }
    };
    match name {
        "var" => {
            arity(1, 1, "one argument: the launch configuration name")?;
            scope.vars.get(&args[0]).cloned().ok_or_else(|| {
                format!(
                    "launch configuration '{}' is not defined (by arg or let)",
                    args[0]
                )
            })
        }
        "env" => {
            arity(1, 2, "NAME [DEFAULT]")?;
            match ((scope.env)(&args[0]), args.get(1)) {
                (Some(v), _) => Ok(v),
                (None, Some(default)) => Ok(default.clone()),
                (None, None) => Err(format!(
                    "environment variable '{}' is not set and $(env) has no default",
                    args[0]
                )),
            }
        }
        "optenv" => {
            arity(1, 2, "NAME [DEFAULT]")?;
            Ok((scope.env)(&args[0])
                .or_else(|| args.get(1).cloned())
                .unwrap_or_default())
        }
        "find-pkg-share" => {
            arity(1, 1, "one argument: the package name")?;
            (scope.find_pkg_share)(&args[0]).map(|p| p.display().to_string())
        }
        "dirname" => {
            arity(0, 0, "no arguments")?;
            let dir = scope.current_file.parent().unwrap_or(Path::new("."));
            Ok(if dir.as_os_str().is_empty() {
                ".".into()
            } else {
                dir.display().to_string()
            })
        }
        "filename" => {
            arity(0, 0, "no arguments")?;
            Ok(scope
                .current_file
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default())
        }
        "" => Err("empty substitution '$()'".to_string()),
        other => Err(format!(
            "unknown substitution '$({other})' (known: {KNOWN_SUBSTITUTIONS})"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn run(text: &str) -> Result<String, String> {
        let mut vars = BTreeMap::new();
        vars.insert("robot".to_string(), "cell_a".to_string());
        vars.insert("key".to_string(), "HOME_X".to_string());
        let env = |k: &str| (k == "HOME_X").then(|| "/home/x".to_string());
        let share = |p: &str| {
            if p == "metrocell" {
                Ok(PathBuf::from("/repo"))
            } else {
                Err(format!("package '{p}' not found"))
            }
        };
        let scope = SubstitutionScope {
            vars: &vars,
            env: &env,
            current_file: Path::new("/repo/launch-configs/cell.launch.yaml"),
            find_pkg_share: &share,
        };
        substitute(text, &scope)
    }

    #[test]
    fn expands_every_kind() {
        assert_eq!(run("ns_$(var robot)/x").unwrap(), "ns_cell_a/x");
        assert_eq!(run("$(env HOME_X)").unwrap(), "/home/x");
        assert_eq!(run("$(env NOPE fallback)").unwrap(), "fallback");
        assert_eq!(run("[$(env NOPE '')]").unwrap(), "[]");
        assert_eq!(run("$(optenv NOPE)").unwrap(), "");
        assert_eq!(run("$(optenv HOME_X d)").unwrap(), "/home/x");
        assert_eq!(
            run("$(find-pkg-share metrocell)/launch-configs").unwrap(),
            "/repo/launch-configs"
        );
        assert_eq!(
            run("$(dirname)/p.yaml").unwrap(),
            "/repo/launch-configs/p.yaml"
        );
        assert_eq!(run("$(filename)").unwrap(), "cell.launch.yaml");
        assert_eq!(run("no substitution").unwrap(), "no substitution");
    }

    #[test]
    fn nests() {
        assert_eq!(run("$(env $(var key))").unwrap(), "/home/x");
        assert_eq!(run("$(env NOPE \"a b\")").unwrap(), "a b");
        assert_eq!(run("$(env NOPE pre$(var robot))").unwrap(), "precell_a");
    }

    #[test]
    fn errors_name_the_problem() {
        assert!(run("$(eval 1+1)")
            .unwrap_err()
            .contains("unknown substitution '$(eval)'"));
        assert!(run("$(var missing)")
            .unwrap_err()
            .contains("'missing' is not defined"));
        assert!(run("$(env NOPE)")
            .unwrap_err()
            .contains("'NOPE' is not set"));
        assert!(run("$(var robot").unwrap_err().contains("unterminated"));
        assert!(run("$(find-pkg-share other)")
            .unwrap_err()
            .contains("package 'other' not found"));
        assert!(run("$(var a b)")
            .unwrap_err()
            .contains("takes one argument"));
    }
}
