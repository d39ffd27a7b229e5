//! `tracker_warmup` — range drift of a laser tracker while it warms up (thesis P1, eq. 3.1).
//!
//! Δρ(t) = A + B·(1 − e^(−t/τ)),  t = time since power-on.
//!
//! A is a constant range offset, B the total drift, τ the time constant. The thesis fits, in mm
//! and minutes: API Tracker3 ρ = 159.798 + 0.019(1 − e^(−t/30)); Leica LTD600
//! ρ = 154.999 + 0.075(1 − e^(−t/90)) (the nest distances are the A of ρ, the drift is B).
//! Effect: range change (measured − true), m.

use nalgebra::{DMatrix, DMatrixViewMut, DVector};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// A + B·(1 − e^(−t/τ)).
pub fn warmup_drift(a: f64, b: f64, tau: f64, t: f64) -> f64 {
    a + b * (1.0 - (-t / tau).exp())
}

/// Time for the exponential to reach `fraction` of B: t = −τ·ln(1 − fraction).
/// 95 % gives 2.996·τ, the "3τ" rule of the thesis.
pub fn settling_time(tau: f64, fraction: f64) -> f64 {
    -tau * (1.0 - fraction).ln()
}

#[derive(Debug, Clone, Default)]
pub struct TrackerWarmup {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl TrackerWarmup {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            instrument: super::instance(o)?,
        })
    }
}

impl PhysicsTerm for TrackerWarmup {
    fn id(&self) -> TermId {
        TermId::TrackerWarmup
    }
    fn label(&self) -> String {
        super::instance_label("tracker_warmup", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::RangeChange
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new("offset", "m", -1e-3, 1e-3, 0.0, "A: constant range offset"),
            ParamSpec::new("amplitude", "m", -100e-6, 100e-6, 0.0, "B: total warm-up drift").unusual_means("a warm-up drift above 100 µm is more than trackers show: the range drifts for another reason (refraction, the stand)"),
            ParamSpec::new("time_constant", "s", 300.0, 10_800.0, 5400.0, "τ: warm-up time constant").possible(1.0, f64::INFINITY).unusual_means("a warm-up longer than 3 h or shorter than 5 min is not a tracker's warm-up: a slow drift of another cause"),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::TimeSincePowerOn]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 3)?;
        let t = s.time_on(self)?;
        Ok(Prediction {
            kind: self.effect(),
            value: DVector::from_element(1, warmup_drift(p[0], p[1], p[2], t)),
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 3)?;
        let t = s.time_on(self)?;
        let e = (-t / p[2]).exp();
        Ok(DMatrix::from_row_slice(
            1,
            3,
            &[1.0, 1.0 - e, -p[1] * t / (p[2] * p[2]) * e],
        ))
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, 3)?;
        let t = match s.time_since_power_on {
            Some(t) => t,
            None => s.time_on(self)?,
        };
        value[0] = warmup_drift(p[0], p[1], p[2], t);
        let e = (-t / p[2]).exp();
        jac[(0, 0)] = 1.0;
        jac[(0, 1)] = 1.0 - e;
        jac[(0, 2)] = -p[1] * t / (p[2] * p[2]) * e;
        Ok(())
    }
}
