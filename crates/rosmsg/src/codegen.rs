//! Rust code generation for message types (used by the `metrocell-msgs` build script).
//!
//! Layout of the generated code: types of `root_package` go to `crate::msg::Type`, every
//! other package `pkg` to `crate::pkg::msg::Type`. Each struct has its fields in `.msg`
//! order with `.msg` names (Rust keywords as raw identifiers, serde-renamed), derives
//! `Debug, Clone, PartialEq, Serialize, Deserialize`, implements `Default` honouring the
//! `.msg` defaults, carries the `.msg` constants as associated consts and the `.msg` comments
//! as docs, and implements [`crate::RosMessage`].
//!
//! Type mapping: `bool`→`bool`; `byte`, `char`, `uint8`→`u8`; `intN`/`uintN`→`iN`/`uN`;
//! `float32`/`float64`→`f32`/`f64`; `string`/`wstring` (bounded or not)→`String`;
//! `T[]` and `T[<=N]`→`Vec<T>`; `T[N]`→`[T; N]`.

use crate::registry::{Registry, RegistryError};
use crate::spec::{ArrayKind, BaseType, FieldType, MessageSpec, Primitive, TypeName};
use crate::value::Value;
use std::collections::BTreeMap;
use std::fmt::Write;

const KEYWORDS: &[&str] = &[
    "as", "break", "const", "continue", "else", "enum", "extern", "false", "fn", "for", "if",
    "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "static",
    "struct", "trait", "true", "type", "unsafe", "use", "where", "while", "async", "await", "dyn",
    "abstract", "become", "box", "do", "final", "macro", "override", "priv", "typeof", "unsized",
    "virtual", "yield", "try", "gen",
];
/// Keywords that cannot be raw identifiers.
const NON_RAW_KEYWORDS: &[&str] = &["self", "super", "crate", "Self"];

/// The Rust identifier of a `.msg` field name, and whether it differs (needs a serde rename).
pub fn rust_field_ident(name: &str) -> (String, bool) {
    if NON_RAW_KEYWORDS.contains(&name) {
        (format!("{name}_"), true)
    } else if KEYWORDS.contains(&name) {
        (format!("r#{name}"), true)
    } else {
        (name.to_string(), false)
    }
}

fn primitive_rust(p: Primitive) -> &'static str {
    use Primitive::*;
    match p {
        Bool => "bool",
        Byte | Char | UInt8 => "u8",
        Int8 => "i8",
        Int16 => "i16",
        UInt16 => "u16",
        Int32 => "i32",
        UInt32 => "u32",
        Int64 => "i64",
        UInt64 => "u64",
        Float32 => "f32",
        Float64 => "f64",
    }
}

fn type_path(t: &TypeName, root_package: &str) -> String {
    if t.package == root_package {
        format!("crate::msg::{}", t.name)
    } else {
        format!("crate::{}::msg::{}", t.package, t.name)
    }
}

fn base_rust(base: &BaseType, root_package: &str) -> String {
    match base {
        BaseType::Primitive(p) => primitive_rust(*p).to_string(),
        BaseType::String { .. } | BaseType::WString { .. } => "::std::string::String".to_string(),
        BaseType::Message(t) => type_path(t, root_package),
    }
}

fn field_rust(ty: &FieldType, root_package: &str) -> String {
    let b = base_rust(&ty.base, root_package);
    match ty.array {
        ArrayKind::Single => b,
        ArrayKind::Fixed(n) => format!("[{b}; {n}]"),
        ArrayKind::Bounded(_) | ArrayKind::Unbounded => format!("::std::vec::Vec<{b}>"),
    }
}

fn is_byte_like(base: &BaseType) -> bool {
    matches!(
        base,
        BaseType::Primitive(Primitive::Byte | Primitive::Char | Primitive::UInt8)
    )
}

fn literal(base: &BaseType, v: &Value) -> String {
    match (base, v) {
        (_, Value::Bool(b)) => b.to_string(),
        (BaseType::Primitive(p), Value::Int(i)) => format!("{i}{}", primitive_rust(*p)),
        (BaseType::Primitive(p), Value::UInt(u)) => format!("{u}{}", primitive_rust(*p)),
        (BaseType::Primitive(p), Value::Float(f)) => {
            let t = primitive_rust(*p);
            if f.is_nan() {
                format!("{t}::NAN")
            } else if f.is_infinite() {
                format!("{}{t}::INFINITY", if *f < 0.0 { "-" } else { "" })
            } else {
                let s = format!("{f:?}");
                let s = if s.contains(['.', 'e', 'E']) {
                    s
                } else {
                    format!("{s}.0")
                };
                format!("{s}_{t}")
            }
        }
        (_, Value::String(s)) => format!("::std::string::String::from({s:?})"),
        (_, other) => {
            format!("/* unsupported literal {other:?} */ ::core::default::Default::default()")
        }
    }
}

fn default_expr(ty: &FieldType, default: Option<&Value>) -> String {
    match (ty.array, default) {
        (ArrayKind::Single, Some(v)) => literal(&ty.base, v),
        (ArrayKind::Fixed(_), Some(Value::Array(items))) => {
            format!(
                "[{}]",
                items
                    .iter()
                    .map(|v| literal(&ty.base, v))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        (_, Some(Value::Array(items))) => {
            format!(
                "::std::vec![{}]",
                items
                    .iter()
                    .map(|v| literal(&ty.base, v))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        (ArrayKind::Fixed(_), _) => {
            "::core::array::from_fn(|_| ::core::default::Default::default())".to_string()
        }
        _ => "::core::default::Default::default()".to_string(),
    }
}

fn doc_lines(out: &mut String, indent: &str, text: &str) {
    for line in text.lines() {
        let _ = writeln!(out, "{indent}#[doc = {:?}]", format!(" {line}"));
    }
}

/// Generates Rust source for every type in `registry` (see the module docs for the layout),
/// plus `pub(crate) const MSG_SOURCES: &[(&str, &str, &str)]` = (package, type, `.msg` text) of
/// every type, and a `for_each_message!(callback)` macro that calls `callback!(path::Type)`
/// for every generated type.
pub fn generate_rust(registry: &Registry, root_package: &str) -> Result<String, RegistryError> {
    registry.check()?;
    let mut by_pkg: BTreeMap<&str, Vec<&MessageSpec>> = BTreeMap::new();
    for spec in registry.specs() {
        by_pkg
            .entry(spec.type_name.package.as_str())
            .or_default()
            .push(spec);
    }
    let mut out = String::new();
    out.push_str("// @generated by rosmsg::codegen from the .msg files. Do not edit.\n\n");
    for (pkg, specs) in &by_pkg {
        let is_root = *pkg == root_package;
        if !is_root {
            let _ = writeln!(
                out,
                "/// Types of the ROS 2 package `{pkg}`.\npub mod {pkg} {{"
            );
        }
        let _ = writeln!(out, "/// Message types of `{pkg}`.\npub mod msg {{");
        for spec in specs {
            generate_struct(&mut out, registry, spec, root_package)?;
        }
        out.push_str("}\n");
        if !is_root {
            out.push_str("}\n");
        }
    }
    out.push_str("\n/// (package, type, `.msg` text) of every generated type.\npub(crate) const MSG_SOURCES: &[(&str, &str, &str)] = &[\n");
    for spec in registry.specs() {
        let _ = writeln!(
            out,
            "    ({:?}, {:?}, {:?}),",
            spec.type_name.package, spec.type_name.name, spec.text
        );
    }
    out.push_str("];\n\n");
    out.push_str("/// Calls `$callback!(path::to::Type);` once for every generated message type.\n#[macro_export]\nmacro_rules! for_each_message {\n    ($callback:ident) => {\n");
    for spec in registry.specs() {
        let path = type_path(&spec.type_name, root_package).replacen("crate::", "$crate::", 1);
        let _ = writeln!(out, "        $callback!({path});");
    }
    out.push_str("    };\n}\n");
    Ok(out)
}

fn generate_struct(
    out: &mut String,
    registry: &Registry,
    spec: &MessageSpec,
    root_package: &str,
) -> Result<(), RegistryError> {
    let t = &spec.type_name;
    let name = &t.name;
    if !spec.comment.is_empty() {
        doc_lines(out, "", &spec.comment);
        out.push_str("#[doc = \"\"]\n");
    }
    let _ = writeln!(
        out,
        "#[doc = {:?}]",
        format!(" ROS 2 type `{}`.", t.ros_type())
    );
    out.push_str("#[derive(Debug, Clone, PartialEq, ::serde::Serialize, ::serde::Deserialize)]\n");
    let _ = writeln!(out, "pub struct {name} {{");
    let mut defaults = Vec::new();
    for f in &spec.fields {
        if !f.comment.is_empty() {
            doc_lines(out, "    ", &f.comment);
            out.push_str("    #[doc = \"\"]\n");
        }
        let _ = writeln!(
            out,
            "    #[doc = {:?}]",
            format!(" `.msg`: `{} {}`", f.ty, f.name)
        );
        let (ident, renamed) = rust_field_ident(&f.name);
        if renamed {
            let _ = writeln!(out, "    #[serde(rename = {:?})]", f.name);
        }
        match f.ty.array {
            ArrayKind::Fixed(_) => {
                out.push_str("    #[serde(with = \"::rosmsg::serde_helpers::fixed_array\")]\n")
            }
            ArrayKind::Bounded(_) | ArrayKind::Unbounded if is_byte_like(&f.ty.base) => {
                out.push_str("    #[serde(with = \"::rosmsg::serde_helpers::byte_seq\")]\n")
            }
            _ => {}
        }
        let _ = writeln!(out, "    pub {ident}: {},", field_rust(&f.ty, root_package));
        defaults.push((ident, default_expr(&f.ty, f.default.as_ref())));
    }
    if spec.fields.is_empty() {
        // rosidl gives empty messages one uint8 member so that they have a wire representation.
        out.push_str("    #[doc = \" Placeholder member rosidl adds to empty messages.\"]\n    pub structure_needs_at_least_one_member: u8,\n");
        defaults.push((
            "structure_needs_at_least_one_member".to_string(),
            "0u8".to_string(),
        ));
    }
    out.push_str("}\n\n");

    if !spec.constants.is_empty() {
        let _ = writeln!(out, "impl {name} {{");
        for c in &spec.constants {
            if !c.comment.is_empty() {
                doc_lines(out, "    ", &c.comment);
            }
            match (&c.ty, &c.value) {
                (BaseType::String { .. } | BaseType::WString { .. }, Value::String(s)) => {
                    let _ = writeln!(out, "    pub const {}: &'static str = {s:?};", c.name);
                }
                (BaseType::Primitive(p), v) => {
                    let _ = writeln!(
                        out,
                        "    pub const {}: {} = {};",
                        c.name,
                        primitive_rust(*p),
                        literal(&c.ty, v)
                    );
                }
                _ => {}
            }
        }
        out.push_str("}\n\n");
    }

    let _ = writeln!(out, "#[allow(clippy::derivable_impls)]\nimpl ::core::default::Default for {name} {{\n    fn default() -> Self {{\n        Self {{");
    for (ident, expr) in defaults {
        let _ = writeln!(out, "            {ident}: {expr},");
    }
    out.push_str("        }\n    }\n}\n\n");

    let definition = registry.full_definition(&t.short())?;
    let _ = writeln!(
        out,
        "impl ::rosmsg::RosMessage for {name} {{\n    const ROS_TYPE: &'static str = {:?};\n    const PACKAGE: &'static str = {:?};\n    const NAME: &'static str = {:?};\n    const DDS_TYPE: &'static str = {:?};\n    const DEFINITION: &'static str = {:?};\n}}\n",
        t.ros_type(),
        t.package,
        t.name,
        t.dds_type(),
        definition
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generates_paths_defaults_and_renames() {
        let mut r = Registry::new();
        r.add_msg(
            "geometry_msgs",
            "Point",
            "float64 x\nfloat64 y\nfloat64 z\n",
        )
        .unwrap();
        r.add_msg("my_pkg", "Thing", "uint8 A=3\nstring S=hi\nfloat64 type 1.5\nint32[3] v [1, -2, 3]\nuint8[] data\ngeometry_msgs/Point p\nfloat64[36] cov\n").unwrap();
        let code = generate_rust(&r, "my_pkg").unwrap();
        assert!(code.contains("pub mod geometry_msgs {"), "{code}");
        assert!(code.contains("pub r#type: f64,"), "{code}");
        assert!(code.contains("#[serde(rename = \"type\")]"), "{code}");
        assert!(code.contains("r#type: 1.5_f64,"), "{code}");
        assert!(code.contains("v: [1i32, -2i32, 3i32],"), "{code}");
        assert!(
            code.contains("pub p: crate::geometry_msgs::msg::Point,"),
            "{code}"
        );
        assert!(code.contains("pub cov: [f64; 36],"), "{code}");
        assert!(code.contains("byte_seq"), "{code}");
        assert!(code.contains("pub const A: u8 = 3u8;"), "{code}");
        assert!(
            code.contains("pub const S: &'static str = \"hi\";"),
            "{code}"
        );
        assert!(
            code.contains("const DDS_TYPE: &'static str = \"my_pkg::msg::dds_::Thing_\";"),
            "{code}"
        );
        assert!(code.contains("$callback!($crate::msg::Thing);"), "{code}");
    }
}
