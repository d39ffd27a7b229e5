//! The live dashboard's state model, pure and unit-tested (the node `metrocell-dashboard` feeds
//! it from DDS and serves it): rolling windows of message-stamped samples ([`series`]), drift
//! rates by straight-line fit with uncertainty ([`trend`]), the volumetric error of measured
//! points ([`volumetric`]), temperatures, tracker status, error models with σ, findings from
//! `/diagnostics`, and alert thresholds on the predicted error and its drift ([`alerts`]).
//!
//! Units: SI everywhere in code and JSON (m, m/s, °C, s); the page shows µm and µm/h.

pub mod alerts;
pub mod error_model;
pub mod findings;
pub mod series;
pub mod state;
pub mod temperatures;
pub mod tracker;
pub mod trend;
pub mod volumetric;

pub use alerts::{Alert, AlertThresholds, Level};
pub use state::{DashboardState, Snapshot, StateConfig};

use metrocell_msgs::builtin_interfaces::msg::Time;

/// A field of a message that cannot be used, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field} {reason}")]
pub struct InputError {
    pub field: String,
    pub reason: String,
}

impl InputError {
    pub fn new(field: &str, reason: impl Into<String>) -> InputError {
        InputError {
            field: field.to_string(),
            reason: reason.into(),
        }
    }
}

/// A message stamp in seconds since the epoch.
pub fn stamp_seconds(t: &Time) -> f64 {
    nanos_seconds(t.nanos())
}

/// Nanoseconds since the epoch in seconds: whole seconds first, so only the fraction is rounded.
pub fn nanos_seconds(ns: i64) -> f64 {
    ns.div_euclid(1_000_000_000) as f64 + ns.rem_euclid(1_000_000_000) as f64 * 1e-9
}
