//! The dynamic value model: a message value whose type is only known at run time.

/// A dynamically typed message value. Which variant a field holds follows its `.msg` type:
/// `bool` → [`Value::Bool`]; `int8..int64` → [`Value::Int`]; `byte`, `char`, `uint8..uint64`
/// → [`Value::UInt`]; `float32`/`float64` → [`Value::Float`]; `string`/`wstring` →
/// [`Value::String`]; any array or sequence → [`Value::Array`]; a nested message →
/// [`Value::Struct`].
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Bool(bool),
    Int(i64),
    UInt(u64),
    Float(f64),
    String(String),
    Array(Vec<Value>),
    Struct(StructValue),
}

/// A message value: its type (`pkg/Type`) and its fields in `.msg` order.
#[derive(Debug, Clone, PartialEq)]
pub struct StructValue {
    pub type_name: String,
    pub fields: Vec<(String, Value)>,
}

impl StructValue {
    /// The value of the field called `name`.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    pub fn get_mut(&mut self, name: &str) -> Option<&mut Value> {
        self.fields
            .iter_mut()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }
}

impl Value {
    /// Short description of the variant, used in error messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Bool(_) => "bool",
            Value::Int(_) => "signed integer",
            Value::UInt(_) => "unsigned integer",
            Value::Float(_) => "float",
            Value::String(_) => "string",
            Value::Array(_) => "array",
            Value::Struct(_) => "message",
        }
    }

    /// Looks a field up by a dotted path (`header.stamp.sec`); array indices as numbers (`corners.3`).
    pub fn at_path(&self, path: &str) -> Option<&Value> {
        let mut v = self;
        for part in path.split('.').filter(|p| !p.is_empty()) {
            v = match v {
                Value::Struct(s) => s.get(part)?,
                Value::Array(a) => a.get(part.parse::<usize>().ok()?)?,
                _ => return None,
            };
        }
        Some(v)
    }

    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Value::Float(f) => Some(f),
            Value::Int(i) => Some(i as f64),
            Value::UInt(u) => Some(u as f64),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::String(s) => Some(s),
            _ => None,
        }
    }

    pub fn as_struct(&self) -> Option<&StructValue> {
        match self {
            Value::Struct(s) => Some(s),
            _ => None,
        }
    }
}
