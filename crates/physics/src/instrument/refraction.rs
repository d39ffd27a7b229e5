//! `refraction` — range error of a tracker whose weather station misreads the air on the beam.
//!
//! Δρ = ρ·( n(t + ΔT, p + Δp, h + Δh) / n(t, p, h) − 1 )      (thesis eq. 5.7 with one uniform section)
//!
//! n is the shop-floor Edlén index ([`super::edlen::shop_floor_index`]); (t, p, h) are the
//! station readings (signals), ΔT and Δp the mean offsets of the beam's air from them
//! (parameters). Δh (%RH), option `path_humidity_offset` (default 0), is a known, fixed offset:
//! at 8·10⁻⁹ per %RH it is never worth fitting. Hotter air → lower n → the tracker reads short
//! (Δρ < 0). Effect: range change, m.

use nalgebra::{DMatrix, DMatrixViewMut, DVector};

use super::edlen::{
    shop_floor_index, shop_floor_index_dp, shop_floor_index_dt, shop_floor_refractivity,
};
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// Range change and its derivatives w.r.t. (ΔT, Δp) at range ρ and station air (t, p, h).
fn range_change(rho: f64, t: f64, pa: f64, h: f64, dh: f64, p: &[f64]) -> (f64, [f64; 2]) {
    // n_path/n_lt − 1 = (N_path − N_lt)/(1 + N_lt) with N = n − 1: no cancellation.
    let n_lt = shop_floor_refractivity(pa, t, h);
    let n_path = shop_floor_refractivity(pa + p[1], t + p[0], h + dh);
    let n_lt_index = shop_floor_index(pa, t, h);
    let (tp, pp, hp) = (t + p[0], pa + p[1], h + dh);
    (
        rho * (n_path - n_lt) / (1.0 + n_lt),
        [
            rho * shop_floor_index_dt(pp, tp, hp) / n_lt_index,
            rho * shop_floor_index_dp(pp, tp, hp) / n_lt_index,
        ],
    )
}

#[derive(Debug, Clone, Default)]
pub struct Refraction {
    /// Δh, %RH: relative humidity on the beam minus the station reading.
    pub path_humidity_offset: f64,
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl Refraction {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let path_humidity_offset = o.quantity("path_humidity_offset", "1", Some(0.0))?;
        if !(path_humidity_offset.abs() <= 100.0) {
            return Err(o.bad(
                "path_humidity_offset",
                format!("must be within ±100 %RH, got {path_humidity_offset}"),
            ));
        }
        Ok(Self {
            path_humidity_offset,
            instrument: super::instance(o)?,
        })
    }
}

impl PhysicsTerm for Refraction {
    fn id(&self) -> TermId {
        TermId::Refraction
    }
    fn label(&self) -> String {
        super::instance_label("refraction", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::RangeChange
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new("path_temperature_offset", "K", -3.0, 3.0, 0.0, "mean air temperature on the beam minus the station reading")
                .possible(-150.0, 150.0)
                .unusual_means("a beam-air offset of more than 3 K (about 3 ppm of range per kelvin) is not a station misplaced in a shop: the instrument did not use the station's air data, or its altitude/pressure settings are wrong"),
            ParamSpec::new("path_pressure_offset", "Pa", -500.0, 500.0, 0.0, "mean air pressure on the beam minus the station reading")
                .possible(-60_000.0, 60_000.0)
                .unusual_means("a pressure offset above 5 hPa is not a shop's pressure gradient: the instrument did not use the station's pressure, or its altitude setting is wrong (about 12 hPa per 100 m)"),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![
            SignalKind::TrackerRange,
            SignalKind::AirTemperature,
            SignalKind::AirPressure,
            SignalKind::AirHumidity,
        ]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 2)?;
        let rho = s.range(self)?;
        let (t, pa, h) = s.air(self)?;
        Ok(Prediction {
            kind: self.effect(),
            value: DVector::from_element(
                1,
                range_change(rho, t, pa, h, self.path_humidity_offset, p).0,
            ),
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 2)?;
        let rho = s.range(self)?;
        let (t, pa, h) = s.air(self)?;
        Ok(DMatrix::from_row_slice(
            1,
            2,
            &range_change(rho, t, pa, h, self.path_humidity_offset, p).1,
        ))
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, 2)?;
        let (rho, t, pa, h) = match (
            s.tracker_range,
            s.air_temperature,
            s.air_pressure,
            s.air_humidity,
        ) {
            (Some(rho), Some(t), Some(pa), Some(h)) => (rho, t, pa, h),
            _ => {
                let (t, pa, h) = s.air(self)?;
                (s.range(self)?, t, pa, h)
            }
        };
        let (v, j) = range_change(rho, t, pa, h, self.path_humidity_offset, p);
        value[0] = v;
        jac[(0, 0)] = j[0];
        jac[(0, 1)] = j[1];
        Ok(())
    }
}
