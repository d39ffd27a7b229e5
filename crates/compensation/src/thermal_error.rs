//! What can go wrong when configuring or applying a thermal correction. Every variant names the
//! sensor, term or parameter at fault.

use metrocell_physics::PhysicsError;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ThermalError {
    #[error("sensor '{sensor}': axis index {axis} is not 0 (x), 1 (y) or 2 (z)")]
    BadAxis { sensor: String, axis: usize },
    #[error("sensor '{0}' is listed twice")]
    DuplicateSensor(String),
    /// (sensor, what needs it: an axis name or a term id)
    #[error("no reading yet from sensor '{0}' (needed for {1}); compensation waits for it")]
    NoReading(String, &'static str),
    #[error(
        "sensor '{sensor}' is stale: its last reading is {age_s:.1} s old (limit {limit_s} s)"
    )]
    StaleReading {
        sensor: String,
        age_s: f64,
        limit_s: f64,
    },
    #[error("alpha {0} 1/K is outside the catalog's plausible range of thermal_scale.alpha [-2e-6, 3e-5] 1/K")]
    BadAlpha(f64),
    #[error("parameter {name}: {reason}")]
    BadParameter { name: String, reason: String },
    #[error("{what} is not finite")]
    NotFinite { what: String },
    #[error(transparent)]
    Physics(#[from] PhysicsError),
}

impl ThermalError {
    /// Short key of why a point was not compensated (diagnostics counter suffix).
    pub fn reason(&self) -> &'static str {
        match self {
            ThermalError::NoReading(..) => "no_reading",
            ThermalError::StaleReading { .. } => "stale_sensor",
            ThermalError::NotFinite { .. } => "not_finite",
            _ => "model_error",
        }
    }
}

/// A temperature reading: value (°C) and variance (K²), as sensor_msgs/Temperature carries.
pub type Reading = (f64, f64);
