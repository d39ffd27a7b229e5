//! Quantities in the cell file: a bare number (already in the SI unit the key documents) or a
//! string with a unit suffix (`"800 mm"`, `"0.8 um/m"`, `"90 min"`, `"10 Hz"`), parsed by the
//! physics crate's unit parser so the cell file and the term parameters accept the same units.

use metrocell_physics::units::{parse_quantity, parse_unit, QuantityError};
use serde::{Deserialize, Serialize};

use crate::error::CellError;

/// A number (canonical unit) or a text with a unit suffix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Quantity {
    Number(f64),
    Text(String),
}

impl From<f64> for Quantity {
    fn from(v: f64) -> Self {
        Quantity::Number(v)
    }
}

impl Quantity {
    /// The value in `unit` (a unit string of the physics parser, e.g. `m`, `s`, `1/K`, `degC`);
    /// `path` names the key for the error message.
    pub fn to_si(&self, path: &str, unit: &str) -> Result<f64, CellError> {
        let text = match self {
            Quantity::Number(n) => return finite(path, *n),
            Quantity::Text(t) => t.trim().to_string(),
        };
        finite(path, parse(path, &text, unit)?)
    }

    /// Like [`Quantity::to_si`] and also requires the value to be > 0.
    pub fn positive(&self, path: &str, unit: &str) -> Result<f64, CellError> {
        let v = self.to_si(path, unit)?;
        if !(v > 0.0) {
            return Err(CellError::OutOfRange {
                path: path.into(),
                value: v,
                reason: format!("must be > 0 {unit}"),
            });
        }
        Ok(v)
    }

    /// Like [`Quantity::to_si`] and also requires the value to be ≥ 0.
    pub fn non_negative(&self, path: &str, unit: &str) -> Result<f64, CellError> {
        let v = self.to_si(path, unit)?;
        if !(v >= 0.0) {
            return Err(CellError::OutOfRange {
                path: path.into(),
                value: v,
                reason: format!("must be ≥ 0 {unit}"),
            });
        }
        Ok(v)
    }
}

fn finite(path: &str, v: f64) -> Result<f64, CellError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(CellError::OutOfRange {
            path: path.into(),
            value: v,
            reason: "must be finite".into(),
        })
    }
}

fn parse(path: &str, text: &str, unit: &str) -> Result<f64, CellError> {
    parse_quantity(text, unit).map_err(|e| match e {
        QuantityError::Parse(reason) => CellError::BadQuantity {
            path: path.into(),
            text: text.into(),
            reason,
        },
        QuantityError::Dimension { given, .. } => CellError::WrongUnit {
            path: path.into(),
            given,
            dimension: parse_unit(unit)
                .map(|u| u.dimension.describe())
                .unwrap_or_default(),
            allowed: if unit == "1/s" {
                "Hz".into()
            } else {
                unit.into()
            },
        },
    })
}

/// Three quantities in `unit`.
pub fn vector3(
    q: &[Quantity; 3],
    path: &str,
    unit: &str,
) -> Result<nalgebra::Vector3<f64>, CellError> {
    Ok(nalgebra::Vector3::new(
        q[0].to_si(&format!("{path}[0]"), unit)?,
        q[1].to_si(&format!("{path}[1]"), unit)?,
        q[2].to_si(&format!("{path}[2]"), unit)?,
    ))
}

/// An optional quantity in `unit`, 0 when absent.
pub fn si_or_zero(q: &Option<Quantity>, path: &str, unit: &str) -> Result<f64, CellError> {
    q.as_ref()
        .map(|q| q.to_si(path, unit))
        .transpose()
        .map(|v| v.unwrap_or(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_numbers_units_and_hertz() {
        assert_eq!(Quantity::Number(0.5).to_si("a", "m").unwrap(), 0.5);
        assert!((Quantity::Text("800 mm".into()).to_si("a", "m").unwrap() - 0.8).abs() < 1e-15);
        assert!((Quantity::Text("10 Hz".into()).to_si("a", "1/s").unwrap() - 10.0).abs() < 1e-12);
        assert!((Quantity::Text("2 kHz".into()).to_si("a", "1/s").unwrap() - 2000.0).abs() < 1e-9);
        assert!((Quantity::Text("90 min".into()).to_si("a", "s").unwrap() - 5400.0).abs() < 1e-9);
    }

    #[test]
    fn wrong_unit_names_the_key_and_the_allowed_unit() {
        let e = Quantity::Text("3 urad".into())
            .to_si("sensors.tracker.range_noise.constant", "m")
            .unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("sensors.tracker.range_noise.constant")
                && msg.contains("`m`")
                && msg.contains("urad"),
            "{msg}"
        );
    }
}
