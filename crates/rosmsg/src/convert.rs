//! YAML/JSON ⇄ [`Value`], following a type spec, the way `ros2 topic pub` / `ros2 topic echo`
//! read and print messages: a mapping per message, fields by name, missing fields take their
//! defaults, integers are accepted for float fields, sequences as lists.
//!
//! JSON cannot hold NaN or ±∞: [`to_json`] writes them as the strings `"nan"`, `"inf"`, `"-inf"`,
//! and [`from_json`] accepts those strings (and `.nan`/`.inf`) for float fields.

use crate::cdr::{default_element, default_field, default_message};
use crate::registry::{Registry, RegistryError};
use crate::spec::{ArrayKind, BaseType, FieldType, MessageSpec, Primitive};
use crate::value::{StructValue, Value};

/// Input that does not fit the type: the field path, what was expected and what was given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{type_name}{}: expected {expected}, got {given}", if path.is_empty() { String::new() } else { format!(" field {path}") })]
pub struct ConvertError {
    pub type_name: String,
    pub path: String,
    pub expected: String,
    pub given: String,
}

fn join(path: &str, part: &str) -> String {
    if path.is_empty() {
        part.to_string()
    } else {
        format!("{path}.{part}")
    }
}

fn describe(v: &serde_json::Value) -> String {
    let s = v.to_string();
    let s = if s.len() > 60 {
        format!("{}...", &s[..s.floor_char_boundary_compat(57)])
    } else {
        s
    };
    let kind = match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "bool",
        serde_json::Value::Number(_) => "number",
        serde_json::Value::String(_) => "string",
        serde_json::Value::Array(_) => "list",
        serde_json::Value::Object(_) => "mapping",
    };
    format!("{kind} {s}")
}

trait FloorCharBoundary {
    fn floor_char_boundary_compat(&self, i: usize) -> usize;
}
impl FloorCharBoundary for str {
    fn floor_char_boundary_compat(&self, mut i: usize) -> usize {
        while i > 0 && !self.is_char_boundary(i) {
            i -= 1;
        }
        i
    }
}

/// Converts a JSON value to a message [`Value`] of `type_name`. `null` or a missing field
/// means the field's default; an empty input (`null`) gives the default message.
pub fn from_json(
    registry: &Registry,
    type_name: &str,
    json: &serde_json::Value,
) -> Result<Value, ConvertError> {
    let spec = registry
        .spec(type_name)
        .map_err(|e| reg_err(type_name, "", e))?;
    let mut c = Converter {
        registry,
        type_name: spec.type_name.to_string(),
    };
    c.message(spec, json, "")
}

/// Converts a YAML value (e.g. parsed from `ros2 topic pub` style text
/// `{header: {frame_id: a}, point: {x: 1.0}}`) to a message [`Value`] of `type_name`.
pub fn from_yaml(
    registry: &Registry,
    type_name: &str,
    yaml: &serde_yaml::Value,
) -> Result<Value, ConvertError> {
    let json = serde_json::to_value(yaml).map_err(|e| ConvertError {
        type_name: type_name.to_string(),
        path: String::new(),
        expected: "YAML with string keys and finite numbers".to_string(),
        given: e.to_string(),
    })?;
    from_json(registry, type_name, &json)
}

/// Parses YAML (or JSON, which is YAML) text and converts it; empty text gives the default message.
pub fn from_yaml_str(
    registry: &Registry,
    type_name: &str,
    text: &str,
) -> Result<Value, ConvertError> {
    let yaml: serde_yaml::Value = if text.trim().is_empty() {
        serde_yaml::Value::Null
    } else {
        serde_yaml::from_str(text).map_err(|e| ConvertError {
            type_name: type_name.to_string(),
            path: String::new(),
            expected: "YAML text".to_string(),
            given: format!("unparsable text ({e})"),
        })?
    };
    from_yaml(registry, type_name, &yaml)
}

fn reg_err(type_name: &str, path: &str, e: RegistryError) -> ConvertError {
    ConvertError {
        type_name: type_name.to_string(),
        path: path.to_string(),
        expected: "a known message type".into(),
        given: e.to_string(),
    }
}

struct Converter<'a> {
    registry: &'a Registry,
    type_name: String,
}

impl Converter<'_> {
    fn err(
        &self,
        path: &str,
        expected: impl Into<String>,
        given: &serde_json::Value,
    ) -> ConvertError {
        ConvertError {
            type_name: self.type_name.clone(),
            path: path.to_string(),
            expected: expected.into(),
            given: describe(given),
        }
    }

    fn message(
        &mut self,
        spec: &MessageSpec,
        json: &serde_json::Value,
        path: &str,
    ) -> Result<Value, ConvertError> {
        let obj = match json {
            serde_json::Value::Null => {
                return default_message(self.registry, spec)
                    .map_err(|e| reg_err(&self.type_name, path, e))
            }
            serde_json::Value::Object(o) => o,
            other => {
                return Err(self.err(
                    path,
                    format!("a mapping of {} fields", spec.type_name),
                    other,
                ))
            }
        };
        for key in obj.keys() {
            if spec.field(key).is_none() {
                let names: Vec<&str> = spec.fields.iter().map(|f| f.name.as_str()).collect();
                return Err(ConvertError {
                    type_name: self.type_name.clone(),
                    path: join(path, key),
                    expected: format!(
                        "one of the fields of {}: {}",
                        spec.type_name,
                        names.join(", ")
                    ),
                    given: format!("unknown field {key:?}"),
                });
            }
        }
        let mut fields = Vec::with_capacity(spec.fields.len());
        for f in &spec.fields {
            let fpath = join(path, &f.name);
            let v = match obj.get(&f.name) {
                None | Some(serde_json::Value::Null) => match &f.default {
                    Some(d) => d.clone(),
                    None => default_field(self.registry, &f.ty)
                        .map_err(|e| reg_err(&self.type_name, &fpath, e))?,
                },
                Some(j) => self.field(&f.ty, j, &fpath)?,
            };
            fields.push((f.name.clone(), v));
        }
        Ok(Value::Struct(StructValue {
            type_name: spec.type_name.to_string(),
            fields,
        }))
    }

    fn field(
        &mut self,
        ty: &FieldType,
        json: &serde_json::Value,
        path: &str,
    ) -> Result<Value, ConvertError> {
        if ty.array == ArrayKind::Single {
            return self.element(&ty.base, json, path);
        }
        let items = match json {
            serde_json::Value::Array(a) => a,
            other => return Err(self.err(path, format!("a list ({ty})"), other)),
        };
        match ty.array {
            ArrayKind::Fixed(n) if items.len() != n => {
                return Err(self.err(path, format!("exactly {n} elements ({ty})"), json));
            }
            ArrayKind::Bounded(n) if items.len() > n => {
                return Err(self.err(path, format!("at most {n} elements ({ty})"), json));
            }
            _ => {}
        }
        items
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let p = join(path, &i.to_string());
                if j.is_null() {
                    default_element(self.registry, &ty.base)
                        .map_err(|e| reg_err(&self.type_name, &p, e))
                } else {
                    self.element(&ty.base, j, &p)
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array)
    }

    fn element(
        &mut self,
        base: &BaseType,
        json: &serde_json::Value,
        path: &str,
    ) -> Result<Value, ConvertError> {
        match base {
            BaseType::Primitive(p) => self.primitive(*p, json, path),
            BaseType::String { bound } | BaseType::WString { bound } => {
                let s = json
                    .as_str()
                    .ok_or_else(|| self.err(path, format!("a string ({base})"), json))?;
                let len = if matches!(base, BaseType::WString { .. }) {
                    s.encode_utf16().count()
                } else {
                    s.len()
                };
                if let Some(b) = bound {
                    if len > *b {
                        return Err(self.err(
                            path,
                            format!("a string of at most {b} bytes ({base})"),
                            json,
                        ));
                    }
                }
                Ok(Value::String(s.to_string()))
            }
            BaseType::Message(t) => {
                let spec = self
                    .registry
                    .spec_by_name(t)
                    .map_err(|e| reg_err(&self.type_name, path, e))?;
                self.message(spec, json, path)
            }
        }
    }

    fn primitive(
        &mut self,
        p: Primitive,
        json: &serde_json::Value,
        path: &str,
    ) -> Result<Value, ConvertError> {
        if p == Primitive::Bool {
            return json
                .as_bool()
                .map(Value::Bool)
                .ok_or_else(|| self.err(path, "a bool (true or false)", json));
        }
        if p.is_float() {
            if let Some(f) = json.as_f64() {
                // Round float32 fields now so that a decoded message compares equal to its input.
                return Ok(Value::Float(if p == Primitive::Float32 {
                    f as f32 as f64
                } else {
                    f
                }));
            }
            if let Some(s) = json.as_str() {
                match s.to_ascii_lowercase().as_str() {
                    "nan" | ".nan" => return Ok(Value::Float(f64::NAN)),
                    "inf" | ".inf" | "+inf" | "+.inf" | "infinity" => {
                        return Ok(Value::Float(f64::INFINITY))
                    }
                    "-inf" | "-.inf" | "-infinity" => return Ok(Value::Float(f64::NEG_INFINITY)),
                    _ => {}
                }
            }
            return Err(self.err(path, format!("a number ({})", p.name()), json));
        }
        let (lo, hi) = p.int_range().expect("integer primitive");
        let i: i128 = if let Some(u) = json.as_u64() {
            u as i128
        } else if let Some(i) = json.as_i64() {
            i as i128
        } else {
            return Err(self.err(path, format!("an integer ({})", p.name()), json));
        };
        if i < lo || i > hi {
            return Err(self.err(
                path,
                format!("an integer in {lo}..={hi} ({})", p.name()),
                json,
            ));
        }
        Ok(if p.is_signed_int() {
            Value::Int(i as i64)
        } else {
            Value::UInt(i as u64)
        })
    }
}

/// Converts a [`Value`] to JSON: messages as objects with fields in `.msg` order, arrays as
/// lists. Non-finite floats become the strings `"nan"`, `"inf"`, `"-inf"`.
pub fn to_json(value: &Value) -> serde_json::Value {
    match value {
        Value::Bool(b) => serde_json::Value::Bool(*b),
        Value::Int(i) => serde_json::Value::from(*i),
        Value::UInt(u) => serde_json::Value::from(*u),
        Value::Float(f) => match serde_json::Number::from_f64(*f) {
            Some(n) => serde_json::Value::Number(n),
            None if f.is_nan() => serde_json::Value::String("nan".into()),
            None if *f > 0.0 => serde_json::Value::String("inf".into()),
            None => serde_json::Value::String("-inf".into()),
        },
        Value::String(s) => serde_json::Value::String(s.clone()),
        Value::Array(a) => serde_json::Value::Array(a.iter().map(to_json).collect()),
        Value::Struct(s) => {
            let mut m = serde_json::Map::new();
            for (k, v) in &s.fields {
                m.insert(k.clone(), to_json(v));
            }
            serde_json::Value::Object(m)
        }
    }
}

/// Converts a [`Value`] to YAML (fields in `.msg` order; NaN and ±∞ as YAML's `.nan`, `.inf`).
pub fn to_yaml(value: &Value) -> serde_yaml::Value {
    match value {
        Value::Bool(b) => serde_yaml::Value::Bool(*b),
        Value::Int(i) => serde_yaml::Value::Number((*i).into()),
        Value::UInt(u) => serde_yaml::Value::Number((*u).into()),
        Value::Float(f) => serde_yaml::Value::Number((*f).into()),
        Value::String(s) => serde_yaml::Value::String(s.clone()),
        Value::Array(a) => serde_yaml::Value::Sequence(a.iter().map(to_yaml).collect()),
        Value::Struct(s) => {
            let mut m = serde_yaml::Mapping::new();
            for (k, v) in &s.fields {
                m.insert(serde_yaml::Value::String(k.clone()), to_yaml(v));
            }
            serde_yaml::Value::Mapping(m)
        }
    }
}

/// YAML text of a value, as `ros2 topic echo` prints a message.
pub fn to_yaml_string(value: &Value) -> String {
    serde_yaml::to_string(&to_yaml(value))
        .unwrap_or_else(|e| format!("# cannot print value: {e}\n"))
}
