//! The parsed form of a `.msg` file: field types, fields, constants.

use crate::value::Value;
use std::fmt;

/// A primitive (fixed-size) ROS 2 type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Primitive {
    Bool,
    /// `byte`: an opaque octet (uint8 on the wire).
    Byte,
    /// `char`: an 8-bit character (uint8 on the wire in ROS 2).
    Char,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float32,
    Float64,
}

impl Primitive {
    /// Parses a primitive type name as written in a `.msg` file.
    pub fn from_name(name: &str) -> Option<Primitive> {
        use Primitive::*;
        Some(match name {
            "bool" => Bool,
            "byte" => Byte,
            "char" => Char,
            "int8" => Int8,
            "uint8" => UInt8,
            "int16" => Int16,
            "uint16" => UInt16,
            "int32" => Int32,
            "uint32" => UInt32,
            "int64" => Int64,
            "uint64" => UInt64,
            "float32" => Float32,
            "float64" => Float64,
            _ => return None,
        })
    }

    /// The `.msg` spelling.
    pub fn name(self) -> &'static str {
        use Primitive::*;
        match self {
            Bool => "bool",
            Byte => "byte",
            Char => "char",
            Int8 => "int8",
            UInt8 => "uint8",
            Int16 => "int16",
            UInt16 => "uint16",
            Int32 => "int32",
            UInt32 => "uint32",
            Int64 => "int64",
            UInt64 => "uint64",
            Float32 => "float32",
            Float64 => "float64",
        }
    }

    /// Size on the wire in bytes; CDR (XCDR1) aligns each primitive to its own size.
    pub fn size(self) -> usize {
        use Primitive::*;
        match self {
            Bool | Byte | Char | Int8 | UInt8 => 1,
            Int16 | UInt16 => 2,
            Int32 | UInt32 | Float32 => 4,
            Int64 | UInt64 | Float64 => 8,
        }
    }

    pub fn is_float(self) -> bool {
        matches!(self, Primitive::Float32 | Primitive::Float64)
    }

    pub fn is_signed_int(self) -> bool {
        use Primitive::*;
        matches!(self, Int8 | Int16 | Int32 | Int64)
    }

    pub fn is_unsigned_int(self) -> bool {
        use Primitive::*;
        matches!(self, Byte | Char | UInt8 | UInt16 | UInt32 | UInt64)
    }

    /// Inclusive integer range of an integer primitive (as i128 so u64 fits).
    pub fn int_range(self) -> Option<(i128, i128)> {
        use Primitive::*;
        Some(match self {
            Int8 => (i8::MIN as i128, i8::MAX as i128),
            Int16 => (i16::MIN as i128, i16::MAX as i128),
            Int32 => (i32::MIN as i128, i32::MAX as i128),
            Int64 => (i64::MIN as i128, i64::MAX as i128),
            Byte | Char | UInt8 => (0, u8::MAX as i128),
            UInt16 => (0, u16::MAX as i128),
            UInt32 => (0, u32::MAX as i128),
            UInt64 => (0, u64::MAX as i128),
            _ => return None,
        })
    }
}

/// Fully qualified message type name: package and bare type name (`std_msgs`, `Header`).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TypeName {
    pub package: String,
    pub name: String,
}

impl TypeName {
    pub fn new(package: impl Into<String>, name: impl Into<String>) -> Self {
        TypeName {
            package: package.into(),
            name: name.into(),
        }
    }

    /// Parses `pkg/Type` or `pkg/msg/Type`.
    pub fn parse(s: &str) -> Option<TypeName> {
        let parts: Vec<&str> = s.split('/').collect();
        let (pkg, name) = match parts.as_slice() {
            [p, n] => (*p, *n),
            [p, "msg", n] => (*p, *n),
            _ => return None,
        };
        if !is_package_name(pkg) || !is_type_name(name) {
            return None;
        }
        Some(TypeName::new(pkg, name))
    }

    /// `pkg/Type`, the key used by the registry and in `MSG:` lines.
    pub fn short(&self) -> String {
        format!("{}/{}", self.package, self.name)
    }

    /// `pkg/msg/Type`, the ROS 2 type name (MCAP schema name, `ros2 topic` type).
    pub fn ros_type(&self) -> String {
        format!("{}/msg/{}", self.package, self.name)
    }

    /// `pkg::msg::dds_::Type_`, the DDS type name.
    pub fn dds_type(&self) -> String {
        format!("{}::msg::dds_::{}_", self.package, self.name)
    }
}

impl fmt::Display for TypeName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.package, self.name)
    }
}

pub(crate) fn is_package_name(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_lowercase())
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

pub(crate) fn is_type_name(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_uppercase())
        && s.chars().all(|c| c.is_ascii_alphanumeric())
}

/// The element type of a field, without array-ness.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum BaseType {
    Primitive(Primitive),
    /// `string` or `string<=N` (bound in bytes, excluding the terminating NUL).
    String {
        bound: Option<usize>,
    },
    /// `wstring` or `wstring<=N` (bound in UTF-16 code units).
    WString {
        bound: Option<usize>,
    },
    /// A nested message type.
    Message(TypeName),
}

impl fmt::Display for BaseType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BaseType::Primitive(p) => f.write_str(p.name()),
            BaseType::String { bound: None } => f.write_str("string"),
            BaseType::String { bound: Some(n) } => write!(f, "string<={n}"),
            BaseType::WString { bound: None } => f.write_str("wstring"),
            BaseType::WString { bound: Some(n) } => write!(f, "wstring<={n}"),
            BaseType::Message(t) => write!(f, "{t}"),
        }
    }
}

/// Array-ness of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArrayKind {
    /// A single value.
    Single,
    /// `T[N]`: exactly N elements, no length prefix on the wire.
    Fixed(usize),
    /// `T[<=N]`: at most N elements, u32 length prefix.
    Bounded(usize),
    /// `T[]`: any number of elements, u32 length prefix.
    Unbounded,
}

/// Full field type: element type and array-ness.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct FieldType {
    pub base: BaseType,
    pub array: ArrayKind,
}

impl fmt::Display for FieldType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.base)?;
        match self.array {
            ArrayKind::Single => Ok(()),
            ArrayKind::Fixed(n) => write!(f, "[{n}]"),
            ArrayKind::Bounded(n) => write!(f, "[<={n}]"),
            ArrayKind::Unbounded => f.write_str("[]"),
        }
    }
}

/// One field of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: String,
    pub ty: FieldType,
    /// Default value written in the `.msg` (`float64 x 1.5`), already checked against `ty`.
    pub default: Option<Value>,
    /// Comment lines attached to the field (the block just above it and the trailing comment).
    pub comment: String,
}

/// One constant of a message (`uint8 STATUS_OK=0`, `string NAME=value`).
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    pub name: String,
    pub ty: BaseType,
    pub value: Value,
    pub comment: String,
}

/// A parsed `.msg` file.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageSpec {
    pub type_name: TypeName,
    pub fields: Vec<Field>,
    pub constants: Vec<Constant>,
    /// The comment block at the top of the file (message documentation).
    pub comment: String,
    /// The `.msg` text exactly as given (used verbatim in the full definition).
    pub text: String,
}

impl MessageSpec {
    /// Nested message types referenced by fields, in field order, without repeats.
    pub fn nested_types(&self) -> Vec<TypeName> {
        let mut out: Vec<TypeName> = Vec::new();
        for f in &self.fields {
            if let BaseType::Message(t) = &f.ty.base {
                if !out.contains(t) {
                    out.push(t.clone());
                }
            }
        }
        out
    }

    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }
}
