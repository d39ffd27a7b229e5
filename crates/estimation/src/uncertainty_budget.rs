//! Uncertainty budgets: standard uncertainties combined by root sum of squares (GUM, uncorrelated
//! inputs with unit sensitivity) and expanded by a coverage factor k.
//!
//! The ISO/TS 15530-3 form used in seed 001 (eq. 3.4) for a machine measuring a calibrated
//! artefact: U = k·√(u_cal² + u_p² + u_b² + u_w²), where u_cal is the artefact's calibration,
//! u_p the measurement procedure (from Monte Carlo), u_b the systematic error's uncertainty and
//! u_w the material and manufacturing variation (thermal expansion among it).

/// One named standard uncertainty (m, or the quantity's unit).
#[derive(Debug, Clone, PartialEq)]
pub struct Contribution {
    pub name: String,
    pub standard_uncertainty: f64,
}

/// Standard uncertainties combined and expanded.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    pub contributions: Vec<Contribution>,
    /// Coverage factor k (2 ≈ 95 % for a normal distribution).
    pub coverage_factor: f64,
}

impl Budget {
    pub fn new(coverage_factor: f64) -> Self {
        Self {
            contributions: Vec::new(),
            coverage_factor,
        }
    }

    pub fn with(mut self, name: &str, standard_uncertainty: f64) -> Self {
        self.contributions.push(Contribution {
            name: name.into(),
            standard_uncertainty,
        });
        self
    }

    /// u_c = √(Σ u_i²).
    pub fn combined(&self) -> f64 {
        self.contributions
            .iter()
            .map(|c| c.standard_uncertainty * c.standard_uncertainty)
            .sum::<f64>()
            .sqrt()
    }

    /// U = k·u_c.
    pub fn expanded(&self) -> f64 {
        self.coverage_factor * self.combined()
    }

    /// Each contribution's share of u_c² (0..1), in order.
    pub fn shares(&self) -> Vec<(String, f64)> {
        let total: f64 = self
            .contributions
            .iter()
            .map(|c| c.standard_uncertainty.powi(2))
            .sum();
        self.contributions
            .iter()
            .map(|c| {
                (
                    c.name.clone(),
                    if total > 0.0 {
                        c.standard_uncertainty.powi(2) / total
                    } else {
                        0.0
                    },
                )
            })
            .collect()
    }

    /// The ISO/TS 15530-3 budget of seed 001 eq. 3.4.
    pub fn iso_15530_3(u_cal: f64, u_p: f64, u_b: f64, u_w: f64, coverage_factor: f64) -> Self {
        Budget::new(coverage_factor)
            .with("u_cal (artefact calibration)", u_cal)
            .with("u_p (measurement procedure)", u_p)
            .with("u_b (systematic error)", u_b)
            .with("u_w (material and manufacturing)", u_w)
    }
}

/// Standard uncertainty of a quantity known only to lie within ±`half_width` (rectangular
/// distribution): a/√3.
pub fn rectangular(half_width: f64) -> f64 {
    half_width / 3f64.sqrt()
}

/// Standard uncertainty of reading a scale of resolution `resolution`: r/√12.
pub fn resolution(resolution: f64) -> f64 {
    resolution / 12f64.sqrt()
}

/// u_w of an artefact of length `length` (m) and expansion coefficient `alpha` (1/K) whose
/// temperature is known within ±`temperature_half_width` (K), rectangular: α·ΔT·L/√3
/// (seed 001, P4 eq. 5).
pub fn thermal_expansion_uncertainty(alpha: f64, temperature_half_width: f64, length: f64) -> f64 {
    rectangular(alpha * temperature_half_width * length)
}

/// Calibration uncertainty of an artefact measured on a CMM with MPE 1.45 µm + L/500 (L in mm),
/// seed 001 P4 eq. 3; `length` in m, result in m.
pub fn cmm_calibration_uncertainty(length: f64) -> f64 {
    (1.45 + length * 1e3 / 500.0) * 1e-6
}

/// Type A standard uncertainty of the mean of `n` values whose standard deviation is `sd`:
/// σ/√n (seed 001's u_b over a Monte Carlo of n trials).
pub fn standard_uncertainty_of_mean(sd: f64, n: usize) -> f64 {
    sd / (n.max(1) as f64).sqrt()
}

/// The bound mean + k·sd a normally distributed quantity stays below (k = 2: about 97.7 % one
/// sided, what seed 001 P5 calls its 95 % bound).
pub fn normal_upper_bound(mean: f64, sd: f64, k: f64) -> f64 {
    mean + k * sd
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 001 part 1 fixture 6 (u_b = σ/√n: σ = 1 µm, n = 1000 → 0.0316 µm), part 2
    /// fixture 8 (P5's verification uncertainty N(13.77, 5.02) µm: bound 23.81 µm) and
    /// fixture 18 (an EVE of 10 µm as a rectangular width: u = 10/(2√3) = 2.89 µm).
    #[test]
    fn seed001_type_a_bound_and_eve() {
        assert!((standard_uncertainty_of_mean(1.0, 1000) - 0.0316).abs() < 0.00005);
        assert!((normal_upper_bound(13.77, 5.02, 2.0) - 23.81).abs() < 1e-9);
        assert!((rectangular(10.0 / 2.0) - 2.89).abs() < 0.005);
    }

    /// Seed 000 Table 4 (camera measurement, µm) and its Type B helpers (digest T2).
    #[test]
    fn seed000_gum_table() {
        let x = Budget::new(2.0)
            .with("experimental", 15.9)
            .with("reference", 0.8)
            .with("resolution", 2.9)
            .with("accuracy", 17.3);
        assert!((x.combined() - 23.69).abs() < 0.005, "{}", x.combined());
        assert!((x.expanded() - 47.38).abs() < 0.01);
        let y = Budget::new(2.0)
            .with("experimental", 8.5)
            .with("reference", 0.8)
            .with("resolution", 2.9)
            .with("accuracy", 17.3);
        assert!((y.combined() - 19.51).abs() < 0.005 && (y.expanded() - 39.02).abs() < 0.01);
        assert!((resolution(10.0) - 2.887).abs() < 0.0005);
        assert!((rectangular(30.0) - 17.32).abs() < 0.005);
        let shares: f64 = x.shares().iter().map(|s| s.1).sum();
        assert!((shares - 1.0).abs() < 1e-12);
    }

    /// Seed 001: the aluminium plate's u_w (L = 300 mm, α = 24e-6 /K) is 0.83 µm with the
    /// temperature monitored to ±0.2 °C and 8.3 µm at ±2 °C; u_cal,MMC = 1.45 + L/500 µm.
    #[test]
    fn seed001_plate_terms() {
        assert!((thermal_expansion_uncertainty(24e-6, 0.2, 0.3) - 0.83e-6).abs() < 0.005e-6);
        assert!((thermal_expansion_uncertainty(24e-6, 2.0, 0.3) - 8.3e-6).abs() < 0.05e-6);
        assert!((cmm_calibration_uncertainty(0.46) - 2.37e-6).abs() < 1e-12);
        let b = Budget::iso_15530_3(2.0e-6, 8.0e-6, 0.1e-6, 0.83e-6, 2.0);
        assert!((b.expanded() - 2.0 * (4.0f64 + 64.0 + 0.01 + 0.6889).sqrt() * 1e-6).abs() < 1e-12);
    }
}
