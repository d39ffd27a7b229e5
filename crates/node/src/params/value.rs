//! A parameter value and its type, as ROS 2 parameters know them (rcl_interfaces/ParameterType,
//! without byte arrays), plus conversion from YAML the way `rcl_yaml_param_parser` reads it.

use std::fmt;

/// The type of a parameter. Byte arrays are not supported (no metrocell node needs them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamType {
    Bool,
    Integer,
    Double,
    String,
    BoolArray,
    IntegerArray,
    DoubleArray,
    StringArray,
}

impl fmt::Display for ParamType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ParamType::Bool => "bool",
            ParamType::Integer => "integer",
            ParamType::Double => "double",
            ParamType::String => "string",
            ParamType::BoolArray => "bool array",
            ParamType::IntegerArray => "integer array",
            ParamType::DoubleArray => "double array",
            ParamType::StringArray => "string array",
        })
    }
}

/// A typed parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Bool(bool),
    Integer(i64),
    Double(f64),
    String(String),
    BoolArray(Vec<bool>),
    IntegerArray(Vec<i64>),
    DoubleArray(Vec<f64>),
    StringArray(Vec<String>),
}

impl ParamValue {
    pub fn param_type(&self) -> ParamType {
        match self {
            ParamValue::Bool(_) => ParamType::Bool,
            ParamValue::Integer(_) => ParamType::Integer,
            ParamValue::Double(_) => ParamType::Double,
            ParamValue::String(_) => ParamType::String,
            ParamValue::BoolArray(_) => ParamType::BoolArray,
            ParamValue::IntegerArray(_) => ParamType::IntegerArray,
            ParamValue::DoubleArray(_) => ParamType::DoubleArray,
            ParamValue::StringArray(_) => ParamType::StringArray,
        }
    }

    /// Parse a command-line value (`-p name:=VALUE`) with YAML rules, as rcl does:
    /// `1` → integer, `1.5` → double, `true` → bool, `[1, 2]` → integer array,
    /// anything else (including an empty string) → string. Quoting (`'1'`) forces a string.
    pub fn parse_yaml_text(text: &str) -> Result<ParamValue, String> {
        if text.trim().is_empty() {
            return Ok(ParamValue::String(text.to_string()));
        }
        match serde_yaml::from_str::<serde_yaml::Value>(text) {
            Ok(value) => match ParamValue::from_yaml(&value) {
                Ok(v) => Ok(v),
                // A mapping or null typed on the command line is most likely meant as text.
                Err(_) if !text.trim_start().starts_with('[') => {
                    Ok(ParamValue::String(text.to_string()))
                }
                Err(e) => Err(e),
            },
            // Not valid YAML (e.g. `a: b: c`): rcl keeps it as a string.
            Err(_) => Ok(ParamValue::String(text.to_string())),
        }
    }

    /// Convert a YAML node (from a params file or the command line) to a value.
    /// Sequences must be homogeneous; an integer among doubles promotes to double.
    /// An empty sequence is an empty string array until [`ParamValue::coerce_to`] retypes it.
    pub fn from_yaml(value: &serde_yaml::Value) -> Result<ParamValue, String> {
        use serde_yaml::Value as Y;
        match value {
            Y::Bool(b) => Ok(ParamValue::Bool(*b)),
            Y::Number(n) => {
                if let Some(i) = n.as_i64() {
                    Ok(ParamValue::Integer(i))
                } else if n.is_u64() {
                    Err(format!(
                        "integer {n} does not fit in a signed 64-bit parameter"
                    ))
                } else {
                    Ok(ParamValue::Double(n.as_f64().unwrap_or(f64::NAN)))
                }
            }
            Y::String(s) => Ok(ParamValue::String(s.clone())),
            Y::Sequence(items) => sequence_from_yaml(items),
            Y::Null => Err("an empty (null) value is not a parameter value".to_string()),
            Y::Mapping(_) => Err(
                "a mapping is not a parameter value (nested keys must end in a value)".to_string(),
            ),
            Y::Tagged(t) => ParamValue::from_yaml(&t.value),
        }
    }

    /// Retype a value to `target` where that loses nothing a user would care about:
    /// integer → double, integer array → double array, and an empty array → any array type.
    /// Returns `None` if the value cannot be that type.
    pub fn coerce_to(&self, target: ParamType) -> Option<ParamValue> {
        if self.param_type() == target {
            return Some(self.clone());
        }
        match (self, target) {
            (ParamValue::Integer(i), ParamType::Double) => Some(ParamValue::Double(*i as f64)),
            (ParamValue::IntegerArray(v), ParamType::DoubleArray) => Some(ParamValue::DoubleArray(
                v.iter().map(|&i| i as f64).collect(),
            )),
            (ParamValue::StringArray(v), t) if v.is_empty() => match t {
                ParamType::BoolArray => Some(ParamValue::BoolArray(Vec::new())),
                ParamType::IntegerArray => Some(ParamValue::IntegerArray(Vec::new())),
                ParamType::DoubleArray => Some(ParamValue::DoubleArray(Vec::new())),
                _ => None,
            },
            _ => None,
        }
    }

    /// Conversion to the ros2-client value served by the node's parameter services.
    pub fn to_ros(&self) -> ros2_client::ParameterValue {
        use ros2_client::ParameterValue as R;
        match self.clone() {
            ParamValue::Bool(b) => R::Boolean(b),
            ParamValue::Integer(i) => R::Integer(i),
            ParamValue::Double(d) => R::Double(d),
            ParamValue::String(s) => R::String(s),
            ParamValue::BoolArray(v) => R::BooleanArray(v),
            ParamValue::IntegerArray(v) => R::IntegerArray(v),
            ParamValue::DoubleArray(v) => R::DoubleArray(v),
            ParamValue::StringArray(v) => R::StringArray(v),
        }
    }

    /// Conversion from a ros2-client value; `None` for `NotSet` and byte arrays.
    pub fn from_ros(value: &ros2_client::ParameterValue) -> Option<ParamValue> {
        use ros2_client::ParameterValue as R;
        Some(match value.clone() {
            R::Boolean(b) => ParamValue::Bool(b),
            R::Integer(i) => ParamValue::Integer(i),
            R::Double(d) => ParamValue::Double(d),
            R::String(s) => ParamValue::String(s),
            R::BooleanArray(v) => ParamValue::BoolArray(v),
            R::IntegerArray(v) => ParamValue::IntegerArray(v),
            R::DoubleArray(v) => ParamValue::DoubleArray(v),
            R::StringArray(v) => ParamValue::StringArray(v),
            _ => return None,
        })
    }
}

fn sequence_from_yaml(items: &[serde_yaml::Value]) -> Result<ParamValue, String> {
    use serde_yaml::Value as Y;
    if items.is_empty() {
        return Ok(ParamValue::StringArray(Vec::new()));
    }
    let scalars: Vec<ParamValue> = items
        .iter()
        .map(|item| match item {
            Y::Sequence(_) | Y::Mapping(_) => {
                Err("nested lists or maps inside a list are not parameter values".to_string())
            }
            other => ParamValue::from_yaml(other),
        })
        .collect::<Result<_, _>>()?;
    let all = |t: ParamType| scalars.iter().all(|s| s.param_type() == t);
    if all(ParamType::Bool) {
        return Ok(ParamValue::BoolArray(
            scalars
                .iter()
                .map(|s| matches!(s, ParamValue::Bool(true)))
                .collect(),
        ));
    }
    if all(ParamType::Integer) {
        return Ok(ParamValue::IntegerArray(
            scalars
                .iter()
                .map(|s| {
                    if let ParamValue::Integer(i) = s {
                        *i
                    } else {
                        0
                    }
                })
                .collect(),
        ));
    }
    if scalars
        .iter()
        .all(|s| matches!(s, ParamValue::Integer(_) | ParamValue::Double(_)))
    {
        return Ok(ParamValue::DoubleArray(
            scalars
                .iter()
                .map(|s| match s {
                    ParamValue::Integer(i) => *i as f64,
                    ParamValue::Double(d) => *d,
                    _ => f64::NAN,
                })
                .collect(),
        ));
    }
    if all(ParamType::String) {
        return Ok(ParamValue::StringArray(
            scalars
                .into_iter()
                .map(|s| {
                    if let ParamValue::String(s) = s {
                        s
                    } else {
                        String::new()
                    }
                })
                .collect(),
        ));
    }
    Err(
        "list mixes types (a parameter array holds one type: bool, integer, double or string)"
            .to_string(),
    )
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn list<T: fmt::Display>(f: &mut fmt::Formatter<'_>, v: &[T]) -> fmt::Result {
            f.write_str("[")?;
            for (i, x) in v.iter().enumerate() {
                if i > 0 {
                    f.write_str(", ")?;
                }
                write!(f, "{x}")?;
            }
            f.write_str("]")
        }
        match self {
            ParamValue::Bool(b) => write!(f, "{b}"),
            ParamValue::Integer(i) => write!(f, "{i}"),
            ParamValue::Double(d) => write!(f, "{d:?}"),
            ParamValue::String(s) => write!(f, "{s:?}"),
            ParamValue::BoolArray(v) => list(f, v),
            ParamValue::IntegerArray(v) => list(f, v),
            ParamValue::DoubleArray(v) => {
                list(f, &v.iter().map(|d| format!("{d:?}")).collect::<Vec<_>>())
            }
            ParamValue::StringArray(v) => {
                list(f, &v.iter().map(|s| format!("{s:?}")).collect::<Vec<_>>())
            }
        }
    }
}

/// Rust types a parameter can be read as (`node.param::<f64>("rate_hz")`) or declared from.
pub trait ParamKind: Sized {
    const TYPE: ParamType;
    fn from_value(value: &ParamValue) -> Option<Self>;
    fn into_value(self) -> ParamValue;
}

macro_rules! param_kind {
    ($t:ty, $variant:ident, $ptype:ident) => {
        impl ParamKind for $t {
            const TYPE: ParamType = ParamType::$ptype;
            fn from_value(value: &ParamValue) -> Option<Self> {
                match value.coerce_to(ParamType::$ptype)? {
                    ParamValue::$variant(x) => Some(x),
                    _ => None,
                }
            }
            fn into_value(self) -> ParamValue {
                ParamValue::$variant(self)
            }
        }
        impl From<$t> for ParamValue {
            fn from(x: $t) -> ParamValue {
                ParamValue::$variant(x)
            }
        }
    };
}
param_kind!(bool, Bool, Bool);
param_kind!(i64, Integer, Integer);
param_kind!(f64, Double, Double);
param_kind!(String, String, String);
param_kind!(Vec<bool>, BoolArray, BoolArray);
param_kind!(Vec<i64>, IntegerArray, IntegerArray);
param_kind!(Vec<f64>, DoubleArray, DoubleArray);
param_kind!(Vec<String>, StringArray, StringArray);

impl From<&str> for ParamValue {
    fn from(s: &str) -> ParamValue {
        ParamValue::String(s.to_string())
    }
}
impl From<i32> for ParamValue {
    fn from(i: i32) -> ParamValue {
        ParamValue::Integer(i as i64)
    }
}
impl From<Vec<&str>> for ParamValue {
    fn from(v: Vec<&str>) -> ParamValue {
        ParamValue::StringArray(v.into_iter().map(str::to_string).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_values_follow_yaml_rules() {
        assert_eq!(
            ParamValue::parse_yaml_text("1").unwrap(),
            ParamValue::Integer(1)
        );
        assert_eq!(
            ParamValue::parse_yaml_text("-7").unwrap(),
            ParamValue::Integer(-7)
        );
        assert_eq!(
            ParamValue::parse_yaml_text("1.5").unwrap(),
            ParamValue::Double(1.5)
        );
        assert_eq!(
            ParamValue::parse_yaml_text("1e-6").unwrap(),
            ParamValue::Double(1e-6)
        );
        assert_eq!(
            ParamValue::parse_yaml_text("true").unwrap(),
            ParamValue::Bool(true)
        );
        assert_eq!(
            ParamValue::parse_yaml_text("[1,2]").unwrap(),
            ParamValue::IntegerArray(vec![1, 2])
        );
        assert_eq!(
            ParamValue::parse_yaml_text("[1, 2.5]").unwrap(),
            ParamValue::DoubleArray(vec![1.0, 2.5])
        );
        assert_eq!(
            ParamValue::parse_yaml_text("[a, 'b c']").unwrap(),
            ParamValue::StringArray(vec!["a".into(), "b c".into()])
        );
        assert_eq!(
            ParamValue::parse_yaml_text("hello").unwrap(),
            ParamValue::String("hello".into())
        );
        assert_eq!(
            ParamValue::parse_yaml_text("'1'").unwrap(),
            ParamValue::String("1".into())
        );
        assert_eq!(
            ParamValue::parse_yaml_text("").unwrap(),
            ParamValue::String("".into())
        );
        assert_eq!(
            ParamValue::parse_yaml_text("/tmp/x.yaml").unwrap(),
            ParamValue::String("/tmp/x.yaml".into())
        );
        assert!(ParamValue::parse_yaml_text("[1, a]").is_err());
    }

    #[test]
    fn coercion_promotes_integers_only() {
        assert_eq!(
            ParamValue::Integer(3).coerce_to(ParamType::Double),
            Some(ParamValue::Double(3.0))
        );
        assert_eq!(ParamValue::Double(3.0).coerce_to(ParamType::Integer), None);
        assert_eq!(
            ParamValue::StringArray(vec![]).coerce_to(ParamType::DoubleArray),
            Some(ParamValue::DoubleArray(vec![]))
        );
        assert_eq!(f64::from_value(&ParamValue::Integer(2)), Some(2.0));
        assert_eq!(bool::from_value(&ParamValue::Integer(1)), None);
    }
}
