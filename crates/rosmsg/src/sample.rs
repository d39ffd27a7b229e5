//! Deterministic sample values for tests: every field gets a non-default value derived from a
//! seed, within the field's bounds, so that a codec that drops, reorders or mis-aligns a field
//! produces different bytes.
//!
//! Rules: integers `(seed + k) mod range` shifted away from 0 (signed ones negative on odd k),
//! floats `±(seed + k) + 0.25` (exactly representable in f32), bools alternate starting with
//! `true`, strings `"s<seed>_<k>"` cut to their bound, sequences get
//! `min(2, bound)` elements, fixed arrays are filled, where k counts the values generated so far.

use crate::registry::{Registry, RegistryError};
use crate::spec::{ArrayKind, BaseType, FieldType, MessageSpec, Primitive};
use crate::value::{StructValue, Value};

/// A sample value of `type_name` with every field set to a non-default value.
pub fn sample_value(
    registry: &Registry,
    type_name: &str,
    seed: u64,
) -> Result<Value, RegistryError> {
    let spec = registry.spec(type_name)?;
    let mut g = Gen {
        registry,
        seed,
        k: 0,
    };
    g.message(spec)
}

struct Gen<'a> {
    registry: &'a Registry,
    seed: u64,
    k: u64,
}

impl Gen<'_> {
    fn next(&mut self) -> u64 {
        self.k += 1;
        self.seed + self.k
    }

    fn message(&mut self, spec: &MessageSpec) -> Result<Value, RegistryError> {
        let mut fields = Vec::new();
        for f in &spec.fields {
            fields.push((f.name.clone(), self.field(&f.ty)?));
        }
        Ok(Value::Struct(StructValue {
            type_name: spec.type_name.to_string(),
            fields,
        }))
    }

    fn field(&mut self, ty: &FieldType) -> Result<Value, RegistryError> {
        let n = match ty.array {
            ArrayKind::Single => return self.element(&ty.base),
            ArrayKind::Fixed(n) => n,
            ArrayKind::Bounded(b) => b.min(2),
            ArrayKind::Unbounded => 2,
        };
        (0..n)
            .map(|_| self.element(&ty.base))
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array)
    }

    fn element(&mut self, base: &BaseType) -> Result<Value, RegistryError> {
        let x = self.next();
        Ok(match base {
            BaseType::Primitive(Primitive::Bool) => Value::Bool(x % 2 == 1),
            BaseType::Primitive(p) if p.is_float() => {
                let v = (x % 100_000) as f64 + 0.25;
                Value::Float(if x % 2 == 0 { -v } else { v })
            }
            BaseType::Primitive(p) => {
                let (_, hi) = p.int_range().expect("integer primitive");
                let m = (x as i128 % hi) + 1; // 1..=hi, never 0
                if p.is_signed_int() {
                    Value::Int(if x % 2 == 1 { -(m as i64) } else { m as i64 })
                } else {
                    Value::UInt(m as u64)
                }
            }
            BaseType::String { bound } | BaseType::WString { bound } => {
                let mut s = format!("s{}_{}", self.seed, self.k);
                if let Some(b) = bound {
                    s.truncate(*b);
                }
                Value::String(s)
            }
            BaseType::Message(t) => {
                let spec = self.registry.spec_by_name(t)?;
                self.message(spec)?
            }
        })
    }
}
