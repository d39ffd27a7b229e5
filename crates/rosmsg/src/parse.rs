//! Parser for ROS 2 `.msg` files (rosidl message syntax).
//!
//! Supported: primitive types, `string`/`wstring` and their bounded forms `string<=N`,
//! fixed arrays `T[N]`, bounded sequences `T[<=N]`, unbounded sequences `T[]`, nested types
//! (`pkg/Type`, `pkg/msg/Type`, same-package `Type`, and `Header` meaning `std_msgs/Header`
//! as rosidl has it), constants `TYPE NAME=value` (string constants included), default
//! values `TYPE name value` (arrays as `[1, 2]`), and `#` comments (a `#` inside a quoted
//! string literal is not a comment).

use crate::spec::{
    is_package_name, is_type_name, ArrayKind, BaseType, Constant, Field, FieldType, MessageSpec,
    Primitive, TypeName,
};
use crate::value::Value;

/// A `.msg` file that could not be parsed: which file or type, which line, and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}:{line}: {message}")]
pub struct ParseError {
    /// The file path or type name (`metrocell_msgs/TrackerMeasurement`) being parsed.
    pub source_name: String,
    /// 1-based line number (0 when the error concerns the whole file).
    pub line: usize,
    pub message: String,
}

/// Parses the `.msg` text of type `package/name`.
pub fn parse_message(package: &str, name: &str, text: &str) -> Result<MessageSpec, ParseError> {
    parse_message_from(package, name, text, &format!("{package}/{name}"))
}

/// Like [`parse_message`], with `source_name` (e.g. the file path) used in error messages.
pub fn parse_message_from(
    package: &str,
    name: &str,
    text: &str,
    source_name: &str,
) -> Result<MessageSpec, ParseError> {
    let err = |line: usize, message: String| ParseError {
        source_name: source_name.to_string(),
        line,
        message,
    };
    if !is_package_name(package) {
        return Err(err(
            0,
            format!("invalid package name {package:?} (lower case, digits and '_')"),
        ));
    }
    if !is_type_name(name) {
        return Err(err(
            0,
            format!("invalid type name {name:?} (CamelCase letters and digits)"),
        ));
    }

    let mut fields: Vec<Field> = Vec::new();
    let mut constants: Vec<Constant> = Vec::new();
    let mut header_comment: Vec<String> = Vec::new();
    let mut in_header = true;
    let mut pending: Vec<String> = Vec::new();
    // Where an indented comment line just below an item continues that item's trailing comment.
    #[derive(Clone, Copy)]
    enum Last {
        None,
        Field(usize),
        Constant(usize),
    }
    let mut last = Last::None;

    for (idx, raw_line) in text.lines().enumerate() {
        let lineno = idx + 1;
        let (code, comment) = split_comment(raw_line);
        let code = code.trim();
        if code.is_empty() {
            match comment {
                None => {
                    // Blank line: ends the file header block and any pending comment block.
                    if in_header && !header_comment.is_empty() {
                        in_header = false;
                    }
                    pending.clear();
                    last = Last::None;
                }
                Some(c) => {
                    let indented = raw_line.starts_with(|ch: char| ch.is_whitespace());
                    match (last, indented) {
                        (Last::Field(i), true) => push_line(&mut fields[i].comment, &c),
                        (Last::Constant(i), true) => push_line(&mut constants[i].comment, &c),
                        _ => {
                            last = Last::None;
                            if in_header {
                                header_comment.push(c);
                            } else {
                                pending.push(c);
                            }
                        }
                    }
                }
            }
            continue;
        }
        in_header = false;

        let (type_str, rest) = split_first_token(code);
        let rest = rest.trim();
        if rest.is_empty() {
            return Err(err(
                lineno,
                format!("expected a field or constant name after type {type_str:?}"),
            ));
        }
        let ty = parse_field_type(type_str, package).map_err(|m| err(lineno, m))?;

        let mut doc = pending.join("\n");
        pending.clear();
        if let Some(c) = comment {
            push_line(&mut doc, &c);
        }

        if let Some((cname, cvalue)) = constant_parts(rest) {
            let constant =
                constant_of(cname, cvalue, ty, doc, &constants).map_err(|m| err(lineno, m))?;
            constants.push(constant);
            last = Last::Constant(constants.len() - 1);
        } else {
            let field = field_of(rest, ty, doc, &fields).map_err(|m| err(lineno, m))?;
            fields.push(field);
            last = Last::Field(fields.len() - 1);
        }
    }

    Ok(MessageSpec {
        type_name: TypeName::new(package, name),
        fields,
        constants,
        comment: header_comment.join("\n"),
        text: text.to_string(),
    })
}

/// The constant `cname` = `cvalue` of type `ty` with its comment `doc`; Err with what is wrong
/// (an array or message type, a bad name, a second definition, a value of another type).
fn constant_of(
    cname: &str,
    cvalue: &str,
    ty: FieldType,
    doc: String,
    constants: &[Constant],
) -> Result<Constant, String> {
    if ty.array != ArrayKind::Single {
        return Err(format!("constant {cname} cannot have an array type ({ty})"));
    }
    if matches!(ty.base, BaseType::Message(_)) {
        return Err(format!(
            "constant {cname} must have a primitive or string type, not {ty}"
        ));
    }
    if !is_constant_name(cname) {
        return Err(format!(
            "invalid constant name {cname:?} (upper case letters, digits and '_')"
        ));
    }
    if constants.iter().any(|c| c.name == cname) {
        return Err(format!("constant {cname} defined twice"));
    }
    let value = parse_scalar_literal(&ty.base, cvalue.trim(), true)
        .map_err(|m| format!("constant {cname}: {m}"))?;
    Ok(Constant {
        name: cname.to_string(),
        ty: ty.base,
        value,
        comment: doc,
    })
}

/// The field `rest` (its name and any default value) of type `ty` with its comment `doc`; Err
/// with what is wrong (a bad name, a second definition, a default of a nested message or of
/// another type).
fn field_of(rest: &str, ty: FieldType, doc: String, fields: &[Field]) -> Result<Field, String> {
    let (fname, default_str) = split_first_token(rest);
    if !is_field_name(fname) {
        return Err(format!(
            "invalid field name {fname:?} (lower case letter first, then lower case, digits and single '_', not ending in '_')"
        ));
    }
    if fields.iter().any(|f| f.name == fname) {
        return Err(format!("field {fname} defined twice"));
    }
    let default_str = default_str.trim();
    let default = if default_str.is_empty() {
        None
    } else {
        if matches!(ty.base, BaseType::Message(_)) {
            return Err(format!(
                "field {fname}: a nested message field ({ty}) cannot have a default value"
            ));
        }
        Some(
            parse_literal(&ty, default_str)
                .map_err(|m| format!("default of field {fname}: {m}"))?,
        )
    };
    Ok(Field {
        name: fname.to_string(),
        ty,
        default,
        comment: doc,
    })
}

fn push_line(doc: &mut String, line: &str) {
    if !doc.is_empty() {
        doc.push('\n');
    }
    doc.push_str(line);
}

/// Splits a line at the first `#` that is not inside a quoted string.
/// Returns the code part and the comment text (without the leading `#`s, trimmed).
fn split_comment(line: &str) -> (&str, Option<String>) {
    let mut quote: Option<char> = None;
    let mut escaped = false;
    for (i, ch) in line.char_indices() {
        if escaped {
            escaped = false;
            continue;
        }
        match quote {
            Some(q) => {
                if ch == '\\' {
                    escaped = true;
                } else if ch == q {
                    quote = None;
                }
            }
            None => {
                if ch == '"' || ch == '\'' {
                    quote = Some(ch);
                } else if ch == '#' {
                    let c = line[i..].trim_start_matches('#').trim().to_string();
                    return (&line[..i], Some(c));
                }
            }
        }
    }
    (line, None)
}

fn split_first_token(s: &str) -> (&str, &str) {
    let s = s.trim_start();
    match s.find(char::is_whitespace) {
        Some(i) => (&s[..i], &s[i..]),
        None => (s, ""),
    }
}

/// `NAME=value` → (NAME, value) when the part before `=` is a single token.
fn constant_parts(rest: &str) -> Option<(&str, &str)> {
    let eq = rest.find('=')?;
    let name = rest[..eq].trim();
    if name.is_empty() || name.contains(char::is_whitespace) {
        return None;
    }
    Some((name, &rest[eq + 1..]))
}

fn is_field_name(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_lowercase())
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !s.contains("__")
        && !s.ends_with('_')
}

fn is_constant_name(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_uppercase())
        && s.chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        && !s.contains("__")
        && !s.ends_with('_')
}

/// Parses a field type such as `float64[9]`, `string<=32`, `geometry_msgs/Point[<=4]`.
/// `package` resolves same-package type names.
pub fn parse_field_type(s: &str, package: &str) -> Result<FieldType, String> {
    let (base_str, array) = match s.find('[') {
        None => (s, ArrayKind::Single),
        Some(i) => {
            if !s.ends_with(']') {
                return Err(format!("malformed array type {s:?}: missing closing ']'"));
            }
            let inner = &s[i + 1..s.len() - 1];
            let array = if inner.is_empty() {
                ArrayKind::Unbounded
            } else if let Some(b) = inner.strip_prefix("<=") {
                let n = parse_bound(b).map_err(|m| format!("array bound in {s:?}: {m}"))?;
                ArrayKind::Bounded(n)
            } else {
                let n = parse_bound(inner).map_err(|m| format!("array size in {s:?}: {m}"))?;
                ArrayKind::Fixed(n)
            };
            (&s[..i], array)
        }
    };
    let base = parse_base_type(base_str, package)?;
    Ok(FieldType { base, array })
}

fn parse_bound(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a positive integer"))?;
    if n == 0 {
        return Err("must be at least 1".to_string());
    }
    Ok(n)
}

fn parse_base_type(s: &str, package: &str) -> Result<BaseType, String> {
    if let Some(p) = Primitive::from_name(s) {
        return Ok(BaseType::Primitive(p));
    }
    if s == "string" {
        return Ok(BaseType::String { bound: None });
    }
    if s == "wstring" {
        return Ok(BaseType::WString { bound: None });
    }
    if let Some(b) = s.strip_prefix("string<=") {
        return Ok(BaseType::String {
            bound: Some(parse_bound(b).map_err(|m| format!("string bound in {s:?}: {m}"))?),
        });
    }
    if let Some(b) = s.strip_prefix("wstring<=") {
        return Ok(BaseType::WString {
            bound: Some(parse_bound(b).map_err(|m| format!("wstring bound in {s:?}: {m}"))?),
        });
    }
    if s == "Header" {
        return Ok(BaseType::Message(TypeName::new("std_msgs", "Header")));
    }
    if s.contains('/') {
        return TypeName::parse(s).map(BaseType::Message).ok_or_else(|| {
            format!("unknown type {s:?} (expected a primitive, string, or pkg/Type)")
        });
    }
    if is_type_name(s) {
        return Ok(BaseType::Message(TypeName::new(package, s)));
    }
    Err(format!(
        "unknown type {s:?} (expected bool, byte, char, int8..int64, uint8..uint64, float32, float64, string, wstring, or a message type)"
    ))
}

/// Parses a default value for a field of type `ty`: a scalar, or `[a, b, ...]` for arrays.
pub fn parse_literal(ty: &FieldType, s: &str) -> Result<Value, String> {
    match ty.array {
        ArrayKind::Single => parse_scalar_literal(&ty.base, s, false),
        array => {
            let inner = s
                .strip_prefix('[')
                .and_then(|r| r.strip_suffix(']'))
                .ok_or_else(|| format!("array value {s:?} must be written as [a, b, ...]"))?;
            let items = split_array_items(inner)?;
            let values = items
                .iter()
                .enumerate()
                .map(|(i, item)| {
                    parse_scalar_literal(&ty.base, item, false)
                        .map_err(|m| format!("element {i}: {m}"))
                })
                .collect::<Result<Vec<_>, _>>()?;
            match array {
                ArrayKind::Fixed(n) if values.len() != n => Err(format!(
                    "{ty} needs exactly {n} values, {} given",
                    values.len()
                )),
                ArrayKind::Bounded(n) if values.len() > n => Err(format!(
                    "{ty} allows at most {n} values, {} given",
                    values.len()
                )),
                _ => Ok(Value::Array(values)),
            }
        }
    }
}

fn split_array_items(inner: &str) -> Result<Vec<String>, String> {
    let mut items = Vec::new();
    let mut cur = String::new();
    let mut quote: Option<char> = None;
    let mut escaped = false;
    for ch in inner.chars() {
        if escaped {
            cur.push(ch);
            escaped = false;
            continue;
        }
        match quote {
            Some(q) => {
                if ch == '\\' {
                    escaped = true;
                }
                if ch == q {
                    quote = None;
                }
                cur.push(ch);
            }
            None => match ch {
                '"' | '\'' => {
                    quote = Some(ch);
                    cur.push(ch);
                }
                ',' => items.push(std::mem::take(&mut cur).trim().to_string()),
                _ => cur.push(ch),
            },
        }
    }
    if quote.is_some() {
        return Err("unterminated quoted string in array value".to_string());
    }
    let last = cur.trim().to_string();
    if !last.is_empty() || !items.is_empty() {
        items.push(last);
    }
    if items.iter().any(|i| i.is_empty()) {
        return Err("empty element in array value".to_string());
    }
    Ok(items)
}

/// Parses one scalar literal. `is_constant`: string constants take the rest of the line
/// verbatim unless quoted.
fn parse_scalar_literal(base: &BaseType, s: &str, is_constant: bool) -> Result<Value, String> {
    let _ = is_constant;
    match base {
        BaseType::Primitive(p) => parse_primitive_literal(*p, s),
        BaseType::String { bound } | BaseType::WString { bound } => {
            let text = unquote(s)?;
            let len = if matches!(base, BaseType::WString { .. }) {
                text.encode_utf16().count()
            } else {
                text.len()
            };
            if let Some(b) = bound {
                if len > *b {
                    return Err(format!("string {text:?} is longer than the bound {b}"));
                }
            }
            Ok(Value::String(text))
        }
        BaseType::Message(t) => Err(format!(
            "a value of message type {t} cannot be written literally"
        )),
    }
}

fn unquote(s: &str) -> Result<String, String> {
    let s = s.trim();
    let q = match s.chars().next() {
        Some(c @ ('"' | '\'')) => c,
        _ => return Ok(s.to_string()),
    };
    if s.len() < 2 || !s.ends_with(q) {
        return Err(format!("unterminated quoted string {s}"));
    }
    let inner = &s[1..s.len() - 1];
    let mut out = String::new();
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => out.push('\\'),
            }
        } else {
            out.push(c);
        }
    }
    Ok(out)
}

fn parse_primitive_literal(p: Primitive, s: &str) -> Result<Value, String> {
    let s = s.trim();
    if p == Primitive::Bool {
        return match s.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(Value::Bool(true)),
            "false" | "0" => Ok(Value::Bool(false)),
            _ => Err(format!("{s:?} is not a bool (true, false, 1 or 0)")),
        };
    }
    if p.is_float() {
        let v: f64 = s
            .parse()
            .map_err(|_| format!("{s:?} is not a number ({})", p.name()))?;
        return Ok(Value::Float(v));
    }
    let v: i128 = s
        .parse()
        .map_err(|_| format!("{s:?} is not an integer ({})", p.name()))?;
    let (lo, hi) = p.int_range().expect("integer primitive");
    if v < lo || v > hi {
        return Err(format!(
            "{v} is out of range for {} ({lo}..={hi})",
            p.name()
        ));
    }
    Ok(if p.is_signed_int() {
        Value::Int(v as i64)
    } else {
        Value::UInt(v as u64)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_types_arrays_bounds_and_defaults() {
        let text = "# A test message.\n# Second line.\n\n\
            uint8 A=1 # a constant\n\
            string GREETING=hello world\n\
            string QUOTED=\"a # b\"\n\
            # doc of x\n\
            float64 x 1.5 # metres\n\
            int32[3] v [1, -2, 3]\n\
            string<=8 s \"hi\"\n\
            float64[<=4] b\n\
            Header header\n\
            geometry_msgs/msg/Point p\n\
            Other[] others\n\
            wstring w\n\
            bool flag true\n";
        let m = parse_message("pkg", "Test", text).unwrap();
        assert_eq!(m.comment, "A test message.\nSecond line.");
        assert_eq!(m.constants.len(), 3);
        assert_eq!(m.constants[0].value, Value::UInt(1));
        assert_eq!(m.constants[0].comment, "a constant");
        assert_eq!(m.constants[1].value, Value::String("hello world".into()));
        assert_eq!(m.constants[2].value, Value::String("a # b".into()));
        let x = m.field("x").unwrap();
        assert_eq!(x.default, Some(Value::Float(1.5)));
        assert_eq!(x.comment, "doc of x\nmetres");
        let v = m.field("v").unwrap();
        assert_eq!(v.ty.array, ArrayKind::Fixed(3));
        assert_eq!(
            v.default,
            Some(Value::Array(vec![
                Value::Int(1),
                Value::Int(-2),
                Value::Int(3)
            ]))
        );
        assert_eq!(
            m.field("s").unwrap().ty.base,
            BaseType::String { bound: Some(8) }
        );
        assert_eq!(m.field("b").unwrap().ty.array, ArrayKind::Bounded(4));
        assert_eq!(
            m.field("header").unwrap().ty.base,
            BaseType::Message(TypeName::new("std_msgs", "Header"))
        );
        assert_eq!(
            m.field("p").unwrap().ty.base,
            BaseType::Message(TypeName::new("geometry_msgs", "Point"))
        );
        let others = m.field("others").unwrap();
        assert_eq!(
            others.ty.base,
            BaseType::Message(TypeName::new("pkg", "Other"))
        );
        assert_eq!(others.ty.array, ArrayKind::Unbounded);
        assert_eq!(
            m.field("w").unwrap().ty.base,
            BaseType::WString { bound: None }
        );
        assert_eq!(m.field("flag").unwrap().default, Some(Value::Bool(true)));
        assert_eq!(m.nested_types().len(), 3);
    }

    #[test]
    fn errors_name_file_line_and_problem() {
        let e = parse_message("pkg", "Bad", "float64 x\nfloat65 y\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert_eq!(e.source_name, "pkg/Bad");
        assert!(e.message.contains("float65"), "{e}");
        assert!(e.to_string().starts_with("pkg/Bad:2: "), "{e}");

        let e = parse_message("pkg", "Bad", "uint8 X=300\n").unwrap_err();
        assert!(e.message.contains("out of range"), "{e}");
        let e = parse_message("pkg", "Bad", "float64[3] v [1, 2]\n").unwrap_err();
        assert!(e.message.contains("exactly 3"), "{e}");
        let e = parse_message("pkg", "Bad", "float64 Xy\n").unwrap_err();
        assert!(e.message.contains("invalid field name"), "{e}");
        let e = parse_message("pkg", "Bad", "float64 x\nfloat64 x\n").unwrap_err();
        assert!(e.message.contains("twice"), "{e}");
        let e = parse_message("pkg", "Bad", "float64[x] v\n").unwrap_err();
        assert!(e.message.contains("array size"), "{e}");
        let e = parse_message("pkg", "Bad", "string<=2 s \"abc\"\n").unwrap_err();
        assert!(e.message.contains("bound"), "{e}");
        let e = parse_message("pkg", "Bad", "float64\n").unwrap_err();
        assert!(e.message.contains("expected a field"), "{e}");
    }

    #[test]
    fn trailing_comment_continuation_attaches_to_field() {
        let text = "uint32 height  # rows\n               # more about rows\nuint32 width\n";
        let m = parse_message("pkg", "T", text).unwrap();
        assert_eq!(m.fields[0].comment, "rows\nmore about rows");
        assert_eq!(m.fields[1].comment, "");
    }
}
