//! Parser of `ros2msg` schema text (a ROS 2 `.msg` definition with its dependencies), used to
//! reject a schema that does not parse before it is written, and on read.
//!
//! Layout (rosbag2 / mcap `ros2msg`): the main type's .msg text, then for each dependency a
//! separator line of `=` characters, a line `MSG: pkg/Type` (or `pkg/msg/Type`), and its .msg
//! text. Every non-builtin field type must resolve to the main type or one of these blocks;
//! a bare `Type` resolves within the package of the type that uses it (and `Header` to
//! `std_msgs/Header`, as ROS tooling does).

use std::collections::BTreeMap;

use crate::error::{BagError, Result};

pub const BUILTIN_TYPES: &[&str] = &[
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
    "uint32", "int64", "uint64", "string", "wstring", "time", "duration",
];

/// Array shape of a field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ArrayKind {
    Unbounded,
    Fixed(usize),
    Bounded(usize),
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    /// Builtin name (`float64`, `string`, ...) or fully qualified `pkg/Type`.
    pub base_type: String,
    /// Upper bound of a bounded string (`string<=N`).
    pub string_bound: Option<usize>,
    pub array: Option<ArrayKind>,
    /// Constant value text for `TYPE NAME=value` lines.
    pub constant: Option<String>,
}

/// All types of one definition, keyed by `pkg/Type`; `main` is the first block's type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MessageDefinition {
    pub main: String,
    pub types: BTreeMap<String, Vec<Field>>,
}

/// `pkg/msg/Type` or `pkg/Type` → `pkg/Type`.
fn short_name(full: &str) -> String {
    let parts: Vec<&str> = full.split('/').collect();
    match parts.as_slice() {
        [pkg, _, name] => format!("{pkg}/{name}"),
        _ => full.to_string(),
    }
}

fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic())
        && s.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

fn err(type_name: &str, line: usize, reason: impl Into<String>) -> BagError {
    BagError::Schema {
        type_name: type_name.to_string(),
        line,
        reason: reason.into(),
    }
}

/// Parse `text`, the `ros2msg` definition of `type_name` (`pkg/msg/Type`).
pub fn parse_definition(type_name: &str, text: &str) -> Result<MessageDefinition> {
    let main = short_name(type_name);
    if main.split('/').count() != 2 {
        return Err(err(type_name, 0, "type name is not pkg/msg/Type"));
    }
    let mut types: BTreeMap<String, Vec<Field>> = BTreeMap::new();
    let mut current = main.clone();
    let mut fields: Vec<Field> = Vec::new();
    let mut expect_msg_line = false;
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.trim();
        if line.len() >= 3 && line.chars().all(|c| c == '=') {
            if types
                .insert(current.clone(), std::mem::take(&mut fields))
                .is_some()
            {
                return Err(err(
                    type_name,
                    lineno,
                    format!("type {current} defined twice"),
                ));
            }
            expect_msg_line = true;
            continue;
        }
        if expect_msg_line {
            if line.is_empty() {
                continue;
            }
            let Some(dep) = line.strip_prefix("MSG:") else {
                return Err(err(
                    type_name,
                    lineno,
                    "expected 'MSG: pkg/Type' after separator line",
                ));
            };
            let dep = dep.trim();
            if dep.split('/').count() < 2 || dep.split('/').any(|p| !is_ident(p)) {
                return Err(err(
                    type_name,
                    lineno,
                    format!("bad dependency name {dep:?}"),
                ));
            }
            current = short_name(dep);
            expect_msg_line = false;
            continue;
        }
        if let Some(f) = parse_line(type_name, &current, lineno, raw)? {
            fields.push(f);
        }
    }
    if expect_msg_line {
        return Err(err(
            type_name,
            text.lines().count(),
            "separator line without a following MSG: line",
        ));
    }
    if types.insert(current.clone(), fields).is_some() {
        return Err(err(
            type_name,
            text.lines().count(),
            format!("type {current} defined twice"),
        ));
    }
    // Every complex field type must be defined in the text.
    for (owner, fs) in &types {
        for f in fs {
            if !BUILTIN_TYPES.contains(&f.base_type.as_str()) && !types.contains_key(&f.base_type) {
                return Err(err(
                    type_name,
                    0,
                    format!(
                        "field {owner}.{} uses type {} which the definition does not include",
                        f.name, f.base_type
                    ),
                ));
            }
        }
    }
    Ok(MessageDefinition { main, types })
}

fn parse_line(type_name: &str, owner: &str, lineno: usize, raw: &str) -> Result<Option<Field>> {
    // Comments start with '#', except inside a string constant's value (handled below).
    let code = raw.split('#').next().unwrap_or("").trim();
    if code.is_empty() {
        return Ok(None);
    }
    let mut parts = code.splitn(2, char::is_whitespace);
    let ty = parts.next().unwrap_or("");
    let rest = parts.next().unwrap_or("").trim();
    if rest.is_empty() {
        return Err(err(
            type_name,
            lineno,
            format!("field line {code:?} has a type but no name"),
        ));
    }
    // Constant: NAME=value (value may contain '#' for strings; re-take it from the raw line).
    let (name, constant) = if let Some(eq) = rest.find('=') {
        let name = rest[..eq].trim();
        let raw_rest = raw.trim_start();
        let raw_eq = raw_rest.find('=').expect("found in prefix");
        (
            name.to_string(),
            Some(raw_rest[raw_eq + 1..].trim().to_string()),
        )
    } else {
        let name = rest.split_whitespace().next().unwrap_or("");
        (name.to_string(), None)
    };
    if !is_ident(&name) {
        return Err(err(type_name, lineno, format!("bad field name {name:?}")));
    }
    // Array suffix.
    let (base, array) =
        match ty.find('[') {
            Some(b) => {
                let inner = ty[b + 1..].strip_suffix(']').ok_or_else(|| {
                    err(
                        type_name,
                        lineno,
                        format!("unclosed array bracket in {ty:?}"),
                    )
                })?;
                let kind =
                    if inner.is_empty() {
                        ArrayKind::Unbounded
                    } else if let Some(n) = inner.strip_prefix("<=") {
                        ArrayKind::Bounded(n.parse().map_err(|_| {
                            err(type_name, lineno, format!("bad array bound {inner:?}"))
                        })?)
                    } else {
                        ArrayKind::Fixed(inner.parse().map_err(|_| {
                            err(type_name, lineno, format!("bad array size {inner:?}"))
                        })?)
                    };
                (&ty[..b], Some(kind))
            }
            None => (ty, None),
        };
    let (base, string_bound) = match base.split_once("<=") {
        Some((s, n)) if s == "string" || s == "wstring" => (
            s,
            Some(
                n.parse()
                    .map_err(|_| err(type_name, lineno, format!("bad string bound in {ty:?}")))?,
            ),
        ),
        Some(_) => {
            return Err(err(
                type_name,
                lineno,
                format!("bound on non-string type {ty:?}"),
            ))
        }
        None => (base, None),
    };
    let base_type = if BUILTIN_TYPES.contains(&base) {
        base.to_string()
    } else if base.contains('/') {
        if base.split('/').any(|p| !is_ident(p)) || base.split('/').count() > 3 {
            return Err(err(type_name, lineno, format!("bad type name {base:?}")));
        }
        short_name(base)
    } else if is_ident(base) {
        if base == "Header" {
            "std_msgs/Header".to_string()
        } else {
            let pkg = owner.split('/').next().unwrap_or("");
            format!("{pkg}/{base}")
        }
    } else {
        return Err(err(type_name, lineno, format!("bad type name {base:?}")));
    };
    let constant = match constant {
        Some(c) if base_type != "string" && base_type != "wstring" => {
            Some(c.split('#').next().unwrap_or("").trim().to_string())
        }
        other => other,
    };
    if constant.is_some() && (array.is_some() || !BUILTIN_TYPES.contains(&base_type.as_str())) {
        return Err(err(
            type_name,
            lineno,
            "constants must have a builtin non-array type",
        ));
    }
    Ok(Some(Field {
        name,
        base_type,
        string_bound,
        array,
        constant,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    pub const TEMPERATURE: &str = "std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n\
================================================================================\n\
MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\n\
MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

    #[test]
    fn temperature_parses_with_dependencies() {
        let d = parse_definition("sensor_msgs/msg/Temperature", TEMPERATURE).unwrap();
        assert_eq!(d.main, "sensor_msgs/Temperature");
        assert_eq!(d.types.len(), 3);
        assert_eq!(d.types["builtin_interfaces/Time"][1].base_type, "uint32");
    }

    #[test]
    fn arrays_bounds_constants_comments() {
        let t = "uint8 A=1 # c\nstring S=\"a#b\"\nfloat64[9] cov\nuint8[] data\nstring<=10[<=3] names\n";
        let d = parse_definition("p/msg/T", t).unwrap();
        let f = &d.types["p/T"];
        assert_eq!(f[0].constant.as_deref(), Some("1"));
        assert_eq!(f[1].constant.as_deref(), Some("\"a#b\""));
        assert_eq!(f[2].array, Some(ArrayKind::Fixed(9)));
        assert_eq!(f[3].array, Some(ArrayKind::Unbounded));
        assert_eq!(f[4].string_bound, Some(10));
        assert_eq!(f[4].array, Some(ArrayKind::Bounded(3)));
    }

    #[test]
    fn missing_dependency_and_garbage_are_errors_with_line() {
        let e = parse_definition("p/msg/T", "geometry_msgs/Point p\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("geometry_msgs/Point"), "{e}");
        let e = parse_definition("p/msg/T", "float64 x\nfloat64[ y\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2"), "{e}");
        let e = parse_definition("p/msg/T", "float64\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1"), "{e}");
    }
}
