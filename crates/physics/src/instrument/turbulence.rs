//! `turbulence` — scatter of tracker range readings, inflated by turbulent air on the beam.
//!
//! σ(ρ) = √( (σ₀ + s·ρ)² + (c·ρ)² )
//!
//! σ₀ + s·ρ is the instrument's own noise (thesis P3: 4 µm + 0.8 µm/m); c·ρ the turbulence
//! contribution, which grows with path length (thesis Ch. 5.3: dispersion rises with distance at
//! constant heated section). Turbulence is *flagged, not fitted as a bias*: the prediction is a
//! standard deviation, and [`turbulence_flag`] compares an observed scatter against it.
//! Effect: range scatter (σ), m.

use nalgebra::{DMatrix, DVector};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// Expected σ at range ρ (see module docs).
pub fn range_scatter(base: f64, proportional: f64, turbulence: f64, rho: f64) -> f64 {
    ((base + proportional * rho).powi(2) + (turbulence * rho).powi(2)).sqrt()
}

/// Ratio of observed to expected scatter (> 1 means inflated).
pub fn scatter_inflation(observed_sigma: f64, expected_sigma: f64) -> f64 {
    observed_sigma / expected_sigma
}

/// True when the observed scatter exceeds `factor` × the expected one (thesis detection rule:
/// RMS above the expected uncertainty signals turbulence or vibration; factor ≈ 2 is the design
/// choice of digest 001 §8.3 item 15).
pub fn turbulence_flag(observed_sigma: f64, expected_sigma: f64, factor: f64) -> bool {
    observed_sigma > factor * expected_sigma
}

#[derive(Debug, Clone, Default)]
pub struct Turbulence {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl Turbulence {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            instrument: super::instance(o)?,
        })
    }
}

impl PhysicsTerm for Turbulence {
    fn id(&self) -> TermId {
        TermId::Turbulence
    }
    fn label(&self) -> String {
        super::instance_label("turbulence", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::RangeScatter
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new(
                "base_sigma",
                "m",
                1e-7,
                1e-4,
                4e-6,
                "σ₀: range noise independent of distance",
            )
            .possible(0.0, f64::INFINITY),
            ParamSpec::new(
                "proportional_sigma",
                "1",
                0.0,
                1e-5,
                0.8e-6,
                "s: range noise per metre of range",
            )
            .possible(0.0, f64::INFINITY),
            ParamSpec::new(
                "turbulence",
                "1",
                0.0,
                1e-3,
                0.0,
                "c: turbulence scatter per metre of beam",
            )
            .possible(0.0, f64::INFINITY),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::TrackerRange]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 3)?;
        let rho = s.range(self)?;
        Ok(Prediction {
            kind: self.effect(),
            value: DVector::from_element(1, range_scatter(p[0], p[1], p[2], rho)),
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 3)?;
        let rho = s.range(self)?;
        let sig = range_scatter(p[0], p[1], p[2], rho);
        if !(sig > 0.0) {
            return Err(PhysicsError::InvalidInput {
                what: self.label(),
                reason: "σ = 0: Jacobian undefined (give base_sigma > 0)".into(),
            });
        }
        let inst = p[0] + p[1] * rho;
        Ok(DMatrix::from_row_slice(
            1,
            3,
            &[inst / sig, inst * rho / sig, p[2] * rho * rho / sig],
        ))
    }
}
