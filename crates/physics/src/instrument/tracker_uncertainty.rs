//! Expanded uncertainty of a laser-tracker range (GUM combination of thesis P1 eqs 12–14).
//!
//! The budget items are relative (m/m) and stated at 2σ, as the manufacturer gives them
//! (absolute accuracy u_AA, repeatability u_R, weather station u_WS, environmental deviation
//! along the beam u_ED). Each is halved to 1σ, combined in quadrature and multiplied by the
//! coverage factor k and by the range:  U = k·√Σ(u_i/2)²·ρ.
//! Thesis LT1 at 2 m: u_AA 5, u_R 2.5, u_WS 0.385, u_ED 0 ppm → U(k = 2) = 5.60 ppm = 11.2 µm.

/// Relative 2σ uncertainty items of a tracker range, m/m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerRangeBudget {
    pub absolute_accuracy: f64,
    pub repeatability: f64,
    pub weather_station: f64,
    pub environment_deviation: f64,
}

impl TrackerRangeBudget {
    /// Combined standard uncertainty per metre (1σ), m/m.
    pub fn standard_per_metre(&self) -> f64 {
        let items = [
            self.absolute_accuracy,
            self.repeatability,
            self.weather_station,
            self.environment_deviation,
        ];
        items.iter().map(|u| (0.5 * u).powi(2)).sum::<f64>().sqrt()
    }
    /// Expanded uncertainty at range `rho` (m) with coverage factor `k`, m.
    pub fn expanded(&self, rho: f64, k: f64) -> f64 {
        k * self.standard_per_metre() * rho
    }
}
