//! `thermal_growth` — growth of a structural element (column, ram, spindle head) with its
//! temperature, optionally lagging behind the sensor by a first-order time constant
//! (thesis Ch. 5.5.3, eq. 5.9: Δz = L_col·α_L·ΔT).
//!
//! d = n̂ · g·(T_f − T_ref),   g = L·α (m/K; L and α are not separable from growth alone)
//!
//! Without lag, T_f is the sensor's latest reading (signal `temperature[sensor]`). With
//! `lag: true`, T_f is the sensor history (signal `temperature_history[sensor]`: the samples of
//! the signals' timeline up to their time) passed through the exact discrete first-order filter
//! `T_f[0] = T[0],  T_f[k] = T_f[k−1] + (1 − e^(−Δt_k/τ))·(T[k] − T_f[k−1])`
//! ([`crate::thermal::first_order_lag`]) and the prediction is at the last sample; τ is then the
//! second parameter. The Jacobian with respect to τ is propagated through the recursion
//! analytically. The timeline filters incrementally ([`crate::TemperatureTimeline`]).
//! Frame: machine, tool relative to workpiece. Options: `sensor`, `direction` (default `[0, 0, 1]`),
//! `lag` (default false), `reference_temperature` (°C, default 20).

use nalgebra::{DMatrix, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

pub use crate::thermal::first_order_lag::first_order_lag;

#[derive(Debug, Clone)]
pub struct ThermalGrowth {
    pub sensor: String,
    pub direction: Vector3<f64>,
    pub lag: bool,
    pub reference_temperature: f64,
}

impl ThermalGrowth {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let direction = o.vector3("direction", "1", Some(Vector3::z()))?;
        let n = direction.norm();
        if !(n > 0.0) {
            return Err(o.bad("direction", "must be a non-zero vector"));
        }
        Ok(Self {
            sensor: o.text("sensor", None)?,
            direction: direction / n,
            lag: o.flag("lag", false)?,
            reference_temperature: o.quantity("reference_temperature", "degC", Some(20.0))?,
        })
    }
    fn n_params(&self) -> usize {
        if self.lag {
            2
        } else {
            1
        }
    }
    /// (T_f − T_ref, ∂T_f/∂τ)
    fn state(&self, p: &[f64], s: &Signals) -> Result<(f64, f64), PhysicsError> {
        if self.lag {
            let (tf, d) = s.lagged_temperature(self, &self.sensor, p[1])?;
            Ok((tf - self.reference_temperature, d))
        } else {
            Ok((
                s.temperature(self, &self.sensor)? - self.reference_temperature,
                0.0,
            ))
        }
    }
}

impl PhysicsTerm for ThermalGrowth {
    fn id(&self) -> TermId {
        TermId::ThermalGrowth
    }
    fn label(&self) -> String {
        format!("thermal_growth[{}]", self.sensor)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut v = vec![ParamSpec::new("coefficient", "m/K", -50e-6, 50e-6, 11.5e-6, "g = L·α: growth per kelvin")
            .possible(-1e-3, 1e-3)
            .unusual_means("more than 50 µm/K is more than a 4 m steel structure grows: the sensor sees only part of the structure's temperature change")];
        if self.lag {
            v.push(ParamSpec::new("time_constant", "s", 60.0, 4e4, 1800.0, "τ: lag of the structure behind the sensor").possible(1.0, f64::INFINITY).unusual_means("a lag of more than 11 h is longer than a structure's thermal time constant: the sensor is far from the growing part"));
        }
        v
    }
    fn signals(&self) -> Vec<SignalKind> {
        if self.lag {
            vec![SignalKind::TemperatureHistory(self.sensor.clone())]
        } else {
            vec![SignalKind::Temperature(self.sensor.clone())]
        }
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, self.n_params())?;
        let (dt, _) = self.state(p, s)?;
        Ok(displacement(Frame::Machine, self.direction * (p[0] * dt)))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, self.n_params())?;
        let (dt, dtau) = self.state(p, s)?;
        let mut j = DMatrix::zeros(3, self.n_params());
        j.set_column(0, &(self.direction * dt));
        if self.lag {
            j.set_column(1, &(self.direction * (p[0] * dtau)));
        }
        Ok(j)
    }
}
