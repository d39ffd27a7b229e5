//! A parameter declaration: name, type (from the default), description and the rules a value
//! must satisfy (inclusive numeric range, allowed values).

use super::value::{ParamType, ParamValue};

/// Why a candidate value does not satisfy a declaration (the caller adds name and source).
#[derive(Clone, Debug, PartialEq)]
pub enum ValueProblem {
    WrongType { expected: ParamType },
    OutOfRange { min: f64, max: f64 },
    NotAllowed { allowed: Vec<ParamValue> },
}

/// One declared parameter. The type is the type of the default value.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamDecl {
    pub name: String,
    pub default: ParamValue,
    pub description: String,
    /// Inclusive `[min, max]` for numeric parameters (each element of a numeric array).
    pub range: Option<(f64, f64)>,
    /// If set, the value must equal one of these (each element, for arrays of scalars).
    pub allowed: Option<Vec<ParamValue>>,
}

/// Gives the declaration named `name` in `decls` a new default (a command's flag that
/// configures a node run in-process, e.g. `metrocell bag record`). Panics if there is none:
/// the caller names its own node's parameters.
pub fn set_default(decls: &mut [ParamDecl], name: &str, value: impl Into<ParamValue>) {
    let d = decls
        .iter_mut()
        .find(|d| d.name == name)
        .unwrap_or_else(|| panic!("no parameter `{name}` is declared"));
    d.default = value.into();
}

impl ParamDecl {
    pub fn new(name: &str, default: impl Into<ParamValue>, description: &str) -> ParamDecl {
        ParamDecl {
            name: name.to_string(),
            default: default.into(),
            description: description.to_string(),
            range: None,
            allowed: None,
        }
    }

    /// Restrict a numeric parameter to `min..=max`.
    pub fn with_range(mut self, min: f64, max: f64) -> ParamDecl {
        self.range = Some((min, max));
        self
    }

    /// Restrict the parameter to a set of values (e.g. `["LOCALHOST", "SUBNET"]`).
    pub fn with_allowed<V: Into<ParamValue>>(
        mut self,
        values: impl IntoIterator<Item = V>,
    ) -> ParamDecl {
        self.allowed = Some(values.into_iter().map(Into::into).collect());
        self
    }

    pub fn param_type(&self) -> ParamType {
        self.default.param_type()
    }

    /// Check `value` against this declaration; returns the value retyped to the declared type
    /// (e.g. `-p gain:=2` for a double parameter gives `2.0`).
    pub fn check(&self, value: &ParamValue) -> Result<ParamValue, ValueProblem> {
        let value = value
            .coerce_to(self.param_type())
            .ok_or(ValueProblem::WrongType {
                expected: self.param_type(),
            })?;
        if let Some((min, max)) = self.range {
            let numbers: Vec<f64> = match &value {
                ParamValue::Integer(i) => vec![*i as f64],
                ParamValue::Double(d) => vec![*d],
                ParamValue::IntegerArray(v) => v.iter().map(|&i| i as f64).collect(),
                ParamValue::DoubleArray(v) => v.clone(),
                _ => Vec::new(),
            };
            // NaN fails the range check on purpose.
            if numbers.iter().any(|x| !(*x >= min && *x <= max)) {
                return Err(ValueProblem::OutOfRange { min, max });
            }
        }
        if let Some(allowed) = &self.allowed {
            let ok = match &value {
                ParamValue::BoolArray(v) => {
                    v.iter().all(|x| allowed.contains(&ParamValue::Bool(*x)))
                }
                ParamValue::IntegerArray(v) => {
                    v.iter().all(|x| allowed.contains(&ParamValue::Integer(*x)))
                }
                ParamValue::DoubleArray(v) => {
                    v.iter().all(|x| allowed.contains(&ParamValue::Double(*x)))
                }
                ParamValue::StringArray(v) => v
                    .iter()
                    .all(|x| allowed.contains(&ParamValue::String(x.clone()))),
                scalar => allowed
                    .iter()
                    .any(|a| a.coerce_to(scalar.param_type()).as_ref() == Some(scalar)),
            };
            if !ok {
                return Err(ValueProblem::NotAllowed {
                    allowed: allowed.clone(),
                });
            }
        }
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_and_type_are_checked() {
        let d = ParamDecl::new("rate_hz", 10.0, "publish rate").with_range(0.1, 100.0);
        assert_eq!(
            d.check(&ParamValue::Integer(5)),
            Ok(ParamValue::Double(5.0))
        );
        assert_eq!(
            d.check(&ParamValue::Double(100.0)),
            Ok(ParamValue::Double(100.0))
        );
        assert_eq!(
            d.check(&ParamValue::Double(100.5)),
            Err(ValueProblem::OutOfRange {
                min: 0.1,
                max: 100.0
            })
        );
        assert_eq!(
            d.check(&ParamValue::Double(f64::NAN)),
            Err(ValueProblem::OutOfRange {
                min: 0.1,
                max: 100.0
            })
        );
        assert_eq!(
            d.check(&ParamValue::String("x".into())),
            Err(ValueProblem::WrongType {
                expected: ParamType::Double
            })
        );
    }

    #[test]
    fn allowed_values_are_checked() {
        let d = ParamDecl::new("mode", "fast", "").with_allowed(["fast", "slow"]);
        assert!(d.check(&ParamValue::String("slow".into())).is_ok());
        assert!(matches!(
            d.check(&ParamValue::String("medium".into())),
            Err(ValueProblem::NotAllowed { .. })
        ));
        let a = ParamDecl::new("axes", vec!["x"], "").with_allowed(["x", "y", "z"]);
        assert!(a
            .check(&ParamValue::StringArray(vec!["x".into(), "z".into()]))
            .is_ok());
        assert!(a.check(&ParamValue::StringArray(vec!["w".into()])).is_err());
    }
}
