//! One component of one measurement's residual and what was true when it was taken.

use nalgebra::Vector3;

/// A residual component: measured − predicted along machine axis `axis` of channel `channel`.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualSample {
    /// The instrument or stream, e.g. `tracker`, `probe`, `camera`.
    pub channel: String,
    /// Component: 0, 1, 2 for the machine's x, y, z.
    pub axis: usize,
    /// Time of the measurement (s).
    pub time: f64,
    /// Commanded position of the tool in the machine frame (m).
    pub position: Vector3<f64>,
    /// measured − predicted (m).
    pub residual: f64,
    /// Stated standard uncertainty of this component (m), > 0.
    pub sigma: f64,
    /// Direction each axis approached the point from (+1 / −1), where known.
    pub approach: [Option<f64>; 3],
    /// Other recorded conditions by name, e.g. `velocity.x` (m/s), `temperature.x_left` (°C),
    /// `load` (N).
    pub conditions: Vec<(String, f64)>,
}

impl ResidualSample {
    /// Normalised residual r/σ.
    pub fn z(&self) -> f64 {
        self.residual / self.sigma
    }

    pub fn condition(&self, name: &str) -> Option<f64> {
        self.conditions
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }
}

/// Machine axis name.
pub fn axis_name(axis: usize) -> &'static str {
    ["x", "y", "z"].get(axis).copied().unwrap_or("?")
}
