//! Dynamic CDR codec: encode/decode a [`Value`] of a registry type as ROS 2 puts it on the
//! wire (plain CDR, XCDR1).
//!
//! Wire layout (checked against RustDDS's serializer and Cyclone DDS in the tests):
//! - a 4-byte encapsulation header: `00 01 00 00` for CDR little-endian (`00 00 00 00` for
//!   big-endian, which [`decode`] also reads);
//! - after it, fields in `.msg` order; each primitive is aligned to its own size (1, 2, 4 or 8),
//!   alignment counted from the first byte after the header; structs add no alignment or padding;
//! - `string`: u32 length including the terminating NUL, the UTF-8 bytes, the NUL;
//! - `wstring`: u32 count of UTF-16 code units, then the units (2 bytes each), no terminator
//!   (Cyclone DDS / rmw_cyclonedds convention);
//! - `T[]` and `T[<=N]`: u32 element count, then the elements; `T[N]`: the N elements, no prefix;
//! - a message with no fields is encoded as one `uint8` (rosidl adds such a dummy member).

use crate::registry::Registry;
use crate::spec::{ArrayKind, BaseType, FieldType, MessageSpec, Primitive};
use crate::value::{StructValue, Value};

/// Encapsulation header of CDR little-endian payloads.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];
/// Encapsulation header of CDR big-endian payloads.
pub const CDR_BE_HEADER: [u8; 4] = [0x00, 0x00, 0x00, 0x00];

/// A value that does not fit its type. `path` is the dotted field path (`header.frame_id`,
/// `detections.2.family`); empty for the top level.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot encode {type_name}{}: {message}", if path.is_empty() { String::new() } else { format!(" field {path}") })]
pub struct EncodeError {
    pub type_name: String,
    pub path: String,
    pub message: String,
}

/// Bytes that are not a valid CDR encoding of the type. `offset` counts from the first byte of
/// the input (the encapsulation header included).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot decode {type_name}{} at byte {offset}: {message}", if path.is_empty() { String::new() } else { format!(" field {path}") })]
pub struct DecodeError {
    pub type_name: String,
    pub path: String,
    pub offset: usize,
    pub message: String,
}

fn join(path: &str, part: &str) -> String {
    if path.is_empty() {
        part.to_string()
    } else {
        format!("{path}.{part}")
    }
}

/// Encodes `value` (a [`Value::Struct`] of type `type_name`) as CDR little-endian with the
/// 4-byte encapsulation header.
pub fn encode(registry: &Registry, type_name: &str, value: &Value) -> Result<Vec<u8>, EncodeError> {
    let spec = registry.spec(type_name).map_err(|e| EncodeError {
        type_name: type_name.to_string(),
        path: String::new(),
        message: e.to_string(),
    })?;
    let mut enc = Encoder {
        registry,
        buf: CDR_LE_HEADER.to_vec(),
        type_name: spec.type_name.to_string(),
    };
    enc.message(spec, value, "")?;
    Ok(enc.buf)
}

struct Encoder<'a> {
    registry: &'a Registry,
    buf: Vec<u8>,
    type_name: String,
}

impl Encoder<'_> {
    fn err(&self, path: &str, message: impl Into<String>) -> EncodeError {
        EncodeError {
            type_name: self.type_name.clone(),
            path: path.to_string(),
            message: message.into(),
        }
    }

    fn align(&mut self, n: usize) {
        while (self.buf.len() - 4) % n != 0 {
            self.buf.push(0);
        }
    }

    fn message(
        &mut self,
        spec: &MessageSpec,
        value: &Value,
        path: &str,
    ) -> Result<(), EncodeError> {
        let sv = match value {
            Value::Struct(s) => s,
            other => {
                return Err(self.err(
                    path,
                    format!(
                        "expected a {} message, got a {}",
                        spec.type_name,
                        other.kind()
                    ),
                ))
            }
        };
        for (name, _) in &sv.fields {
            if spec.field(name).is_none() {
                return Err(self.err(
                    &join(path, name),
                    format!("{} has no field {name}", spec.type_name),
                ));
            }
        }
        if spec.fields.is_empty() {
            self.buf.push(0);
            return Ok(());
        }
        for f in &spec.fields {
            let fpath = join(path, &f.name);
            let v = sv
                .get(&f.name)
                .ok_or_else(|| self.err(&fpath, "missing field"))?;
            self.field(&f.ty, v, &fpath)?;
        }
        Ok(())
    }

    fn field(&mut self, ty: &FieldType, v: &Value, path: &str) -> Result<(), EncodeError> {
        if ty.array == ArrayKind::Single {
            return self.element(&ty.base, v, path);
        }
        let items = match v {
            Value::Array(a) => a,
            other => {
                return Err(self.err(
                    path,
                    format!("expected an array ({ty}), got a {}", other.kind()),
                ))
            }
        };
        match ty.array {
            ArrayKind::Fixed(n) if items.len() != n => {
                return Err(self.err(
                    path,
                    format!("{ty} needs exactly {n} elements, got {}", items.len()),
                ))
            }
            ArrayKind::Bounded(n) if items.len() > n => {
                return Err(self.err(
                    path,
                    format!("{ty} allows at most {n} elements, got {}", items.len()),
                ))
            }
            ArrayKind::Fixed(_) => {}
            _ => {
                self.align(4);
                let n = u32::try_from(items.len())
                    .map_err(|_| self.err(path, "sequence longer than 2^32-1"))?;
                self.buf.extend_from_slice(&n.to_le_bytes());
            }
        }
        for (i, item) in items.iter().enumerate() {
            self.element(&ty.base, item, &join(path, &i.to_string()))?;
        }
        Ok(())
    }

    fn element(&mut self, base: &BaseType, v: &Value, path: &str) -> Result<(), EncodeError> {
        match base {
            BaseType::Primitive(p) => self.primitive(*p, v, path),
            BaseType::String { bound } => {
                let s = v.as_str().ok_or_else(|| {
                    self.err(path, format!("expected a string, got a {}", v.kind()))
                })?;
                if let Some(b) = bound {
                    if s.len() > *b {
                        return Err(self.err(
                            path,
                            format!("string of {} bytes exceeds the bound string<={b}", s.len()),
                        ));
                    }
                }
                self.align(4);
                self.buf
                    .extend_from_slice(&((s.len() + 1) as u32).to_le_bytes());
                self.buf.extend_from_slice(s.as_bytes());
                self.buf.push(0);
                Ok(())
            }
            BaseType::WString { bound } => {
                let s = v.as_str().ok_or_else(|| {
                    self.err(path, format!("expected a string, got a {}", v.kind()))
                })?;
                let units: Vec<u16> = s.encode_utf16().collect();
                if let Some(b) = bound {
                    if units.len() > *b {
                        return Err(self.err(
                            path,
                            format!(
                                "wstring of {} code units exceeds the bound wstring<={b}",
                                units.len()
                            ),
                        ));
                    }
                }
                self.align(4);
                self.buf
                    .extend_from_slice(&(units.len() as u32).to_le_bytes());
                for u in units {
                    self.buf.extend_from_slice(&u.to_le_bytes());
                }
                Ok(())
            }
            BaseType::Message(t) => {
                let spec = self
                    .registry
                    .spec_by_name(t)
                    .map_err(|e| self.err(path, e.to_string()))?;
                self.message(spec, v, path)
            }
        }
    }

    fn primitive(&mut self, p: Primitive, v: &Value, path: &str) -> Result<(), EncodeError> {
        use Primitive::*;
        let bad = |s: &Self| {
            s.err(
                path,
                format!("expected {}, got a {} ({v:?})", p.name(), v.kind()),
            )
        };
        self.align(p.size());
        if p == Bool {
            match v {
                Value::Bool(b) => self.buf.push(*b as u8),
                _ => return Err(bad(self)),
            }
            return Ok(());
        }
        if p.is_float() {
            let f = match *v {
                Value::Float(f) => f,
                Value::Int(i) => i as f64,
                Value::UInt(u) => u as f64,
                _ => return Err(bad(self)),
            };
            match p {
                Float32 => self.buf.extend_from_slice(&(f as f32).to_le_bytes()),
                _ => self.buf.extend_from_slice(&f.to_le_bytes()),
            }
            return Ok(());
        }
        let i: i128 = match *v {
            Value::Int(i) => i as i128,
            Value::UInt(u) => u as i128,
            _ => return Err(bad(self)),
        };
        let (lo, hi) = p.int_range().expect("integer primitive");
        if i < lo || i > hi {
            return Err(self.err(
                path,
                format!("{i} is out of range for {} ({lo}..={hi})", p.name()),
            ));
        }
        match p {
            Int8 => self.buf.extend_from_slice(&(i as i8).to_le_bytes()),
            Byte | Char | UInt8 => self.buf.push(i as u8),
            Int16 => self.buf.extend_from_slice(&(i as i16).to_le_bytes()),
            UInt16 => self.buf.extend_from_slice(&(i as u16).to_le_bytes()),
            Int32 => self.buf.extend_from_slice(&(i as i32).to_le_bytes()),
            UInt32 => self.buf.extend_from_slice(&(i as u32).to_le_bytes()),
            Int64 => self.buf.extend_from_slice(&(i as i64).to_le_bytes()),
            UInt64 => self.buf.extend_from_slice(&(i as u64).to_le_bytes()),
            Bool | Float32 | Float64 => unreachable!(),
        }
        Ok(())
    }
}

/// Decodes a CDR payload (4-byte encapsulation header included, little- or big-endian) of type
/// `type_name`. Trailing bytes after the message (RTPS pads payloads to 4 bytes) are ignored.
pub fn decode(registry: &Registry, type_name: &str, bytes: &[u8]) -> Result<Value, DecodeError> {
    let spec = registry.spec(type_name).map_err(|e| DecodeError {
        type_name: type_name.to_string(),
        path: String::new(),
        offset: 0,
        message: e.to_string(),
    })?;
    let tn = spec.type_name.to_string();
    if bytes.len() < 4 {
        return Err(DecodeError {
            type_name: tn,
            path: String::new(),
            offset: 0,
            message: format!(
                "{} bytes is too short for the 4-byte encapsulation header",
                bytes.len()
            ),
        });
    }
    let big_endian = match [bytes[0], bytes[1]] {
        [0x00, 0x01] => false,
        [0x00, 0x00] => true,
        other => {
            return Err(DecodeError {
                type_name: tn,
                path: String::new(),
                offset: 0,
                message: format!(
                "unsupported encapsulation {:02x} {:02x} (expected 00 01 CDR_LE or 00 00 CDR_BE)",
                other[0], other[1]
            ),
            })
        }
    };
    let mut dec = Decoder {
        registry,
        data: &bytes[4..],
        pos: 0,
        big_endian,
        type_name: tn,
    };
    dec.message(spec, "")
}

struct Decoder<'a> {
    registry: &'a Registry,
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
    type_name: String,
}

impl<'a> Decoder<'a> {
    fn err(&self, path: &str, message: impl Into<String>) -> DecodeError {
        DecodeError {
            type_name: self.type_name.clone(),
            path: path.to_string(),
            offset: self.pos + 4,
            message: message.into(),
        }
    }

    fn take(&mut self, n: usize, path: &str) -> Result<&'a [u8], DecodeError> {
        let left = self.data.len().saturating_sub(self.pos);
        if n > left {
            return Err(self.err(path, format!("truncated: need {n} bytes, {left} left")));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn align(&mut self, n: usize, path: &str) -> Result<(), DecodeError> {
        let pad = (n - self.pos % n) % n;
        self.take(pad, path).map(|_| ())
    }

    fn fixed<const N: usize>(&mut self, path: &str) -> Result<[u8; N], DecodeError> {
        self.align(N, path)?;
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, path)?);
        if self.big_endian {
            a.reverse();
        }
        Ok(a)
    }

    fn u32(&mut self, path: &str) -> Result<u32, DecodeError> {
        Ok(u32::from_le_bytes(self.fixed::<4>(path)?))
    }

    fn message(&mut self, spec: &MessageSpec, path: &str) -> Result<Value, DecodeError> {
        let mut fields = Vec::with_capacity(spec.fields.len());
        if spec.fields.is_empty() {
            self.take(1, path)?;
        }
        for f in &spec.fields {
            let fpath = join(path, &f.name);
            let v = self.field(&f.ty, &fpath)?;
            fields.push((f.name.clone(), v));
        }
        Ok(Value::Struct(StructValue {
            type_name: spec.type_name.to_string(),
            fields,
        }))
    }

    fn field(&mut self, ty: &FieldType, path: &str) -> Result<Value, DecodeError> {
        let n = match ty.array {
            ArrayKind::Single => return self.element(&ty.base, path),
            ArrayKind::Fixed(n) => n,
            ArrayKind::Bounded(_) | ArrayKind::Unbounded => {
                let start = self.pos;
                let n = self.u32(path)? as usize;
                if let ArrayKind::Bounded(b) = ty.array {
                    if n > b {
                        self.pos = start;
                        return Err(
                            self.err(path, format!("sequence length {n} exceeds the bound {ty}"))
                        );
                    }
                }
                // Every element takes at least one byte: reject impossible lengths before allocating.
                let left = self.data.len().saturating_sub(self.pos);
                if n > left {
                    self.pos = start;
                    return Err(self.err(
                        path,
                        format!("truncated: sequence length {n} but only {left} bytes left"),
                    ));
                }
                n
            }
        };
        let mut items = Vec::with_capacity(n);
        for i in 0..n {
            items.push(self.element(&ty.base, &join(path, &i.to_string()))?);
        }
        Ok(Value::Array(items))
    }

    fn element(&mut self, base: &BaseType, path: &str) -> Result<Value, DecodeError> {
        match base {
            BaseType::Primitive(p) => self.primitive(*p, path),
            BaseType::String { bound } => {
                let start = self.pos;
                let len = self.u32(path)? as usize;
                let bytes = self.take(len, path)?;
                let body = match bytes.split_last() {
                    None => &[][..], // tolerate length 0 for the empty string
                    Some((0, body)) => body,
                    Some(_) => {
                        self.pos = start;
                        return Err(self.err(path, "string is not NUL-terminated"));
                    }
                };
                if let Some(b) = bound {
                    if body.len() > *b {
                        self.pos = start;
                        return Err(self.err(
                            path,
                            format!(
                                "string of {} bytes exceeds the bound string<={b}",
                                body.len()
                            ),
                        ));
                    }
                }
                match std::str::from_utf8(body) {
                    Ok(s) => Ok(Value::String(s.to_string())),
                    Err(e) => {
                        self.pos = start;
                        Err(self.err(path, format!("string is not UTF-8: {e}")))
                    }
                }
            }
            BaseType::WString { .. } => {
                let start = self.pos;
                let n = self.u32(path)? as usize;
                let raw = self.take(n.saturating_mul(2), path)?;
                let units: Vec<u16> = raw
                    .chunks_exact(2)
                    .map(|c| {
                        if self.big_endian {
                            u16::from_be_bytes([c[0], c[1]])
                        } else {
                            u16::from_le_bytes([c[0], c[1]])
                        }
                    })
                    .collect();
                String::from_utf16(&units).map(Value::String).map_err(|_| {
                    self.pos = start;
                    self.err(path, "wstring is not valid UTF-16")
                })
            }
            BaseType::Message(t) => {
                let spec = self
                    .registry
                    .spec_by_name(t)
                    .map_err(|e| self.err(path, e.to_string()))?;
                self.message(spec, path)
            }
        }
    }

    fn primitive(&mut self, p: Primitive, path: &str) -> Result<Value, DecodeError> {
        use Primitive::*;
        Ok(match p {
            Bool => {
                let b = self.take(1, path)?[0];
                Value::Bool(b != 0)
            }
            Byte | Char | UInt8 => Value::UInt(self.take(1, path)?[0] as u64),
            Int8 => Value::Int(self.take(1, path)?[0] as i8 as i64),
            Int16 => Value::Int(i16::from_le_bytes(self.fixed::<2>(path)?) as i64),
            UInt16 => Value::UInt(u16::from_le_bytes(self.fixed::<2>(path)?) as u64),
            Int32 => Value::Int(i32::from_le_bytes(self.fixed::<4>(path)?) as i64),
            UInt32 => Value::UInt(u32::from_le_bytes(self.fixed::<4>(path)?) as u64),
            Int64 => Value::Int(i64::from_le_bytes(self.fixed::<8>(path)?)),
            UInt64 => Value::UInt(u64::from_le_bytes(self.fixed::<8>(path)?)),
            Float32 => Value::Float(f32::from_le_bytes(self.fixed::<4>(path)?) as f64),
            Float64 => Value::Float(f64::from_le_bytes(self.fixed::<8>(path)?)),
        })
    }
}

/// The default value of a type: `.msg` defaults where given, otherwise zero, `false`, empty
/// strings and sequences, fixed arrays filled with element defaults, nested defaults.
pub fn default_value(
    registry: &Registry,
    type_name: &str,
) -> Result<Value, crate::registry::RegistryError> {
    let spec = registry.spec(type_name)?;
    default_message(registry, spec)
}

pub(crate) fn default_message(
    registry: &Registry,
    spec: &MessageSpec,
) -> Result<Value, crate::registry::RegistryError> {
    let mut fields = Vec::with_capacity(spec.fields.len());
    for f in &spec.fields {
        let v = match &f.default {
            Some(d) => d.clone(),
            None => default_field(registry, &f.ty)?,
        };
        fields.push((f.name.clone(), v));
    }
    Ok(Value::Struct(StructValue {
        type_name: spec.type_name.to_string(),
        fields,
    }))
}

pub(crate) fn default_field(
    registry: &Registry,
    ty: &FieldType,
) -> Result<Value, crate::registry::RegistryError> {
    Ok(match ty.array {
        ArrayKind::Single => default_element(registry, &ty.base)?,
        ArrayKind::Fixed(n) => {
            let e = default_element(registry, &ty.base)?;
            Value::Array(vec![e; n])
        }
        _ => Value::Array(Vec::new()),
    })
}

pub(crate) fn default_element(
    registry: &Registry,
    base: &BaseType,
) -> Result<Value, crate::registry::RegistryError> {
    Ok(match base {
        BaseType::Primitive(p) if *p == Primitive::Bool => Value::Bool(false),
        BaseType::Primitive(p) if p.is_float() => Value::Float(0.0),
        BaseType::Primitive(p) if p.is_signed_int() => Value::Int(0),
        BaseType::Primitive(_) => Value::UInt(0),
        BaseType::String { .. } | BaseType::WString { .. } => Value::String(String::new()),
        BaseType::Message(t) => default_message(registry, registry.spec_by_name(t)?)?,
    })
}
