//! Term configuration as read from YAML/JSON (serde), and the typed reader of its options.
//!
//! ```yaml
//! id: thermal_scale
//! options: { axis: x, sensors: [ {name: x_left, position: 0 m}, {name: x_right, position: "1.2 m"} ] }
//! params: { alpha: "11.5e-6 1/K" }
//! ```
//! Parameter values are numbers (canonical unit) or strings with a unit suffix.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};

use crate::error::PhysicsError;
use crate::signals::Axis;
use crate::units::{parse_quantity, parse_unit, QuantityError};

/// A value in a config: number, text (possibly with a unit), bool, list or map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ConfigValue {
    Bool(bool),
    Number(f64),
    Text(String),
    List(Vec<ConfigValue>),
    Map(BTreeMap<String, ConfigValue>),
}

impl ConfigValue {
    fn describe(&self) -> String {
        match self {
            ConfigValue::Bool(b) => b.to_string(),
            ConfigValue::Number(n) => n.to_string(),
            ConfigValue::Text(t) => t.clone(),
            ConfigValue::List(_) => "<list>".into(),
            ConfigValue::Map(_) => "<map>".into(),
        }
    }
}

/// Configuration of one term instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TermConfig {
    /// Catalog id (e.g. `positioning`).
    pub id: String,
    /// Structural options (axis, order, sensors, ...); see each term's docs.
    #[serde(default)]
    pub options: BTreeMap<String, ConfigValue>,
    /// Parameter values by name.
    #[serde(default)]
    pub params: BTreeMap<String, ConfigValue>,
    /// When true, parameters absent from `params` take their catalog default instead of being an error.
    #[serde(default)]
    pub use_defaults: bool,
}

/// How an estimator treats one term's parameters (a cell file's `estimation: {<term label>: …}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct EstimationConfig {
    /// Parameters to fit; absent = all of the term's. The others stay at their configured values.
    #[serde(default)]
    pub free: Option<Vec<String>>,
    /// Prior knowledge per parameter name: value and standard uncertainty.
    #[serde(default)]
    pub priors: BTreeMap<String, PriorConfig>,
}

/// A prior of one parameter: value and σ, numbers in the canonical unit or quantities.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorConfig {
    pub value: ConfigValue,
    pub sigma: ConfigValue,
}

/// Convert a config value to a quantity in `unit`, naming term and key on failure.
pub fn quantity(term: &str, key: &str, v: &ConfigValue, unit: &str) -> Result<f64, PhysicsError> {
    let text = match v {
        ConfigValue::Number(n) => return Ok(*n),
        ConfigValue::Text(t) => t.clone(),
        other => {
            return Err(PhysicsError::BadValue {
                term: term.into(),
                key: key.into(),
                text: other.describe(),
                reason: format!("expected a number or a quantity in {unit}"),
            })
        }
    };
    parse_quantity(&text, unit).map_err(|e| match e {
        QuantityError::Parse(reason) => PhysicsError::BadValue {
            term: term.into(),
            key: key.into(),
            text: text.clone(),
            reason,
        },
        QuantityError::Dimension { given, expected: _ } => PhysicsError::WrongUnit {
            term: term.into(),
            key: key.into(),
            given,
            dimension: parse_unit(unit)
                .map(|u| u.dimension.describe())
                .unwrap_or_default(),
            allowed: unit.into(),
        },
    })
}

/// Typed, consumption-tracking reader of a term's options; `finish` rejects unknown keys.
pub struct Options<'a> {
    term: &'a str,
    map: &'a BTreeMap<String, ConfigValue>,
    used: RefCell<BTreeSet<String>>,
}

impl<'a> Options<'a> {
    pub fn new(term: &'a str, map: &'a BTreeMap<String, ConfigValue>) -> Self {
        Self {
            term,
            map,
            used: RefCell::new(BTreeSet::new()),
        }
    }
    fn get(&self, key: &str) -> Option<&'a ConfigValue> {
        self.used.borrow_mut().insert(key.to_string());
        self.map.get(key)
    }
    pub fn bad(&self, key: &str, reason: impl Into<String>) -> PhysicsError {
        PhysicsError::BadOption {
            term: self.term.into(),
            key: key.into(),
            reason: reason.into(),
        }
    }
    /// Whether the config gives `key` (does not count as reading it).
    pub fn has(&self, key: &str) -> bool {
        self.map.contains_key(key)
    }
    pub fn required(&self, key: &str) -> Result<&'a ConfigValue, PhysicsError> {
        self.get(key).ok_or_else(|| self.bad(key, "is required"))
    }
    pub fn text(&self, key: &str, default: Option<&str>) -> Result<String, PhysicsError> {
        match (self.get(key), default) {
            (Some(ConfigValue::Text(t)), _) => Ok(t.clone()),
            (Some(other), _) => {
                Err(self.bad(key, format!("expected text, got {}", other.describe())))
            }
            (None, Some(d)) => Ok(d.to_string()),
            (None, None) => Err(self.bad(key, "is required")),
        }
    }
    pub fn axis(&self, key: &str, default: Option<Axis>) -> Result<Axis, PhysicsError> {
        match (self.get(key), default) {
            (Some(ConfigValue::Text(t)), _) => Axis::parse(t)
                .ok_or_else(|| self.bad(key, format!("`{t}` is not an axis; allowed: x, y, z"))),
            (Some(other), _) => {
                Err(self.bad(key, format!("expected x, y or z, got {}", other.describe())))
            }
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.bad(key, "is required (x, y or z)")),
        }
    }
    pub fn axes(&self, key: &str, default: &[Axis]) -> Result<Vec<Axis>, PhysicsError> {
        match self.get(key) {
            None => Ok(default.to_vec()),
            Some(ConfigValue::List(items)) => items
                .iter()
                .map(|i| match i {
                    ConfigValue::Text(t) => {
                        Axis::parse(t).ok_or_else(|| self.bad(key, format!("`{t}` is not an axis")))
                    }
                    o => Err(self.bad(key, format!("expected axis names, got {}", o.describe()))),
                })
                .collect(),
            Some(o) => Err(self.bad(
                key,
                format!("expected a list of axes, got {}", o.describe()),
            )),
        }
    }
    pub fn count(&self, key: &str, default: usize, max: usize) -> Result<usize, PhysicsError> {
        match self.get(key) {
            None => Ok(default),
            Some(ConfigValue::Number(n))
                if n.fract() == 0.0 && *n >= 0.0 && (*n as usize) <= max =>
            {
                Ok(*n as usize)
            }
            Some(o) => Err(self.bad(
                key,
                format!("expected an integer in 0..={max}, got {}", o.describe()),
            )),
        }
    }
    pub fn flag(&self, key: &str, default: bool) -> Result<bool, PhysicsError> {
        match self.get(key) {
            None => Ok(default),
            Some(ConfigValue::Bool(b)) => Ok(*b),
            Some(o) => Err(self.bad(key, format!("expected true/false, got {}", o.describe()))),
        }
    }
    pub fn quantity(
        &self,
        key: &str,
        unit: &str,
        default: Option<f64>,
    ) -> Result<f64, PhysicsError> {
        match (self.get(key), default) {
            (Some(v), _) => quantity(self.term, key, v, unit),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.bad(key, format!("is required ({unit})"))),
        }
    }
    pub fn vector3(
        &self,
        key: &str,
        unit: &str,
        default: Option<Vector3<f64>>,
    ) -> Result<Vector3<f64>, PhysicsError> {
        match (self.get(key), default) {
            (Some(ConfigValue::List(items)), _) if items.len() == 3 => {
                let mut v = Vector3::zeros();
                for (i, it) in items.iter().enumerate() {
                    v[i] = quantity(self.term, key, it, unit)?;
                }
                Ok(v)
            }
            (Some(o), _) => Err(self.bad(
                key,
                format!(
                    "expected a list of 3 quantities in {unit}, got {}",
                    o.describe()
                ),
            )),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.bad(key, format!("is required (3 values in {unit})"))),
        }
    }
    /// An optional list (its items unread).
    pub fn get_list(&self, key: &str) -> Result<Option<&'a Vec<ConfigValue>>, PhysicsError> {
        match self.get(key) {
            None => Ok(None),
            Some(ConfigValue::List(items)) => Ok(Some(items)),
            Some(o) => Err(self.bad(key, format!("expected a list, got {}", o.describe()))),
        }
    }
    /// Optional `[min, max]` pair of lengths in m.
    pub fn length_range(&self, key: &str) -> Result<Option<(f64, f64)>, PhysicsError> {
        match self.get(key) {
            None => Ok(None),
            Some(ConfigValue::List(items)) if items.len() == 2 => Ok(Some((
                quantity(self.term, key, &items[0], "m")?,
                quantity(self.term, key, &items[1], "m")?,
            ))),
            Some(o) => Err(self.bad(
                key,
                format!("expected [min, max] in m, got {}", o.describe()),
            )),
        }
    }
    /// Reject keys that no reader asked for (the readers' keys are the allowed ones).
    pub fn finish(self) -> Result<(), PhysicsError> {
        let used = self.used.borrow();
        for k in self.map.keys() {
            if !used.contains(k) {
                let allowed: Vec<&str> = used.iter().map(|s| s.as_str()).collect();
                return Err(PhysicsError::UnknownOption {
                    term: self.term.into(),
                    key: k.clone(),
                    allowed: allowed.join(", "),
                });
            }
        }
        Ok(())
    }
}
