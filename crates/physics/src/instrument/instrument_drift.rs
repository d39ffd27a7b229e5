//! `instrument_drift` — the instrument's pose moving slowly in time: a tracker's stand sinking or
//! settling, the floor under it creeping, its head turning as its base warms.
//!
//! δpose(t) = Σ_{j=1..order} P_j(u)·c_j,  u = 2·(t − t_start)/(t_end − t_start) − 1 ∈ [−1, 1],
//!
//! P_j the Legendre polynomials (P₁ = u: a drift linear in time, P₂ = (3u² − 1)/2 its curvature),
//! c_j = (dx_j, dy_j, dz_j, rx_j, ry_j, rz_j): a translation of the instrument's origin (m, in the
//! frame its pose is given in: the workpiece frame, an arm's cell frame) and small increments of
//! its pose angles (rad, the `tracker_pose` angles α, β, δ of Rx(α)·Ry(β)·Rz(δ)). The instrument's
//! pose at t is its fitted pose + δpose(t). The series starts at j = 1: the drift's mean over the
//! span is the pose itself. With `rotation: false` only the translations are parameters.
//!
//! What it reads: the instant's time on the recording's clock (`t`) and the span the series is
//! defined over (option `span: [t_start, t_end]`, s, the same clock). Effect: a pose change,
//! [`EffectKind::PoseChange`] (dx, dy, dz, rx, ry, rz); the shared forward model adds it to the
//! instrument's pose for each reading.
//!
//! Convention (stated once): `dx1` is the translation at the span's end relative to its middle
//! for a linear drift (P₁(1) = 1): a stand that sinks 18 µm over the recording has dz1 = −9 µm.
//!
//! Why a term: an instrument that moves during a shift moves every reading the same way a
//! structure growing in time would; only points that the machine does not move (fixed reference
//! nests re-measured through the shift) tell them apart — and the term is what those points fit.

use nalgebra::{DMatrix, DMatrixViewMut, DVector};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::geometry::error_series::{ErrorSeries, SeriesBasis, MAX_ORDER};
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// Components of one order's pose change.
const COMPONENTS: [&str; 6] = ["dx", "dy", "dz", "rx", "ry", "rz"];

/// Highest order of the drift series.
pub const MAX_DRIFT_ORDER: usize = 3;

#[derive(Debug, Clone)]
pub struct InstrumentDrift {
    pub instrument: Option<String>,
    /// The series over time: `travel` holds the span (s, the recording's clock).
    pub series: ErrorSeries,
    /// Rotations as parameters too (else translations only).
    pub rotation: bool,
}

impl InstrumentDrift {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let instrument = super::instance(o)?;
        let order = o.count("order", 1, MAX_DRIFT_ORDER)?;
        if order == 0 {
            return Err(o.bad(
                "order",
                "must be at least 1 (order 0 would be the pose itself)",
            ));
        }
        let span = match o.get_list("span")? {
            Some(items) if items.len() == 2 => (crate::config::quantity("instrument_drift", "span", &items[0], "s")?, crate::config::quantity("instrument_drift", "span", &items[1], "s")?),
            Some(_) => return Err(o.bad("span", "expected [t_start, t_end] in s (the recording's clock)")),
            None => return Err(o.bad("span", "is required: [t_start, t_end] in s, the recording's clock (the time the series is defined over)")),
        };
        let series = ErrorSeries::new(SeriesBasis::Legendre, order, span)
            .map_err(|e| o.bad("span", e.to_string()))?;
        let rotation = o.flag("rotation", true)?;
        Ok(Self {
            instrument,
            series,
            rotation,
        })
    }

    fn components(&self) -> usize {
        if self.rotation {
            6
        } else {
            3
        }
    }

    /// Number of parameters: components × order.
    fn len(&self) -> usize {
        self.components() * self.series.order
    }

    fn time(&self, s: &Signals) -> Result<f64, PhysicsError> {
        s.time.ok_or_else(|| PhysicsError::MissingSignal {
            term: self.label(),
            signal: SignalKind::Time.to_string(),
        })
    }

    /// P₁..P_order at time t.
    fn basis(&self, t: f64) -> [f64; MAX_ORDER + 1] {
        self.series.basis_array(t)
    }
}

impl PhysicsTerm for InstrumentDrift {
    fn id(&self) -> TermId {
        TermId::InstrumentDrift
    }
    fn label(&self) -> String {
        super::instance_label("instrument_drift", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::PoseChange
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut v = Vec::with_capacity(self.len());
        for j in 1..=self.series.order {
            for (k, c) in COMPONENTS.iter().enumerate().take(self.components()) {
                let (unit, usual, what) = if k < 3 {
                    ("m", 50e-6, "translation of the instrument's origin")
                } else {
                    ("rad", 50e-6, "turn of the instrument's pose angle")
                };
                v.push(
                    ParamSpec::new(format!("{c}{j}"), unit, -usual, usual, 0.0, format!("{what} along/about {}: coefficient of P{j} over the span", &c[1..]))
                        .unusual_means("an instrument moving more than 50 µm (or 50 µrad) in a recording stands on a loose or soft support, or was knocked"),
                );
            }
        }
        v
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::Time]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, self.len())?;
        let b = self.basis(self.time(s)?);
        let n = self.components();
        let mut v = DVector::zeros(6);
        for j in 1..=self.series.order {
            for k in 0..n {
                v[k] += b[j] * p[(j - 1) * n + k];
            }
        }
        Ok(Prediction {
            kind: self.effect(),
            value: v,
        })
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, self.len())?;
        let b = self.basis(self.time(s)?);
        let n = self.components();
        let mut j = DMatrix::zeros(6, self.len());
        for o in 1..=self.series.order {
            for k in 0..n {
                j[(k, (o - 1) * n + k)] = b[o];
            }
        }
        Ok(j)
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, self.len())?;
        let b = self.basis(self.time(s)?);
        let n = self.components();
        value[..6].fill(0.0);
        jac.fill(0.0);
        for o in 1..=self.series.order {
            for k in 0..n {
                value[k] += b[o] * p[(o - 1) * n + k];
                jac[(k, (o - 1) * n + k)] = b[o];
            }
        }
        Ok(())
    }
    fn linear_in_params(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ConfigValue;
    use std::collections::BTreeMap;

    fn drift(order: usize, rotation: bool) -> InstrumentDrift {
        let map: BTreeMap<String, ConfigValue> = [
            ("order".to_string(), ConfigValue::Number(order as f64)),
            (
                "span".to_string(),
                ConfigValue::List(vec![
                    ConfigValue::Number(1000.0),
                    ConfigValue::Number(19000.0),
                ]),
            ),
            ("rotation".to_string(), ConfigValue::Bool(rotation)),
        ]
        .into_iter()
        .collect();
        let o = Options::new("instrument_drift", &map);
        let d = InstrumentDrift::from_options(&o).unwrap();
        o.finish().unwrap();
        d
    }

    #[test]
    fn a_linear_drift_is_zero_mid_span_and_its_coefficient_at_the_end() {
        let d = drift(1, false);
        assert_eq!(
            d.params()
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>(),
            ["dx1", "dy1", "dz1"]
        );
        let p = [0.0, 0.0, -9e-6];
        let at = |t: f64| {
            d.predict(
                &p,
                &Signals {
                    time: Some(t),
                    ..Default::default()
                },
            )
            .unwrap()
            .value
        };
        assert!(at(10_000.0).norm() < 1e-18);
        assert!((at(19_000.0)[2] + 9e-6).abs() < 1e-18);
        assert!((at(1_000.0)[2] - 9e-6).abs() < 1e-18);
        // rotations untouched without `rotation`
        assert_eq!(at(19_000.0).rows(3, 3).norm(), 0.0);
    }

    #[test]
    fn the_jacobian_is_the_basis_and_the_term_is_linear() {
        let d = drift(2, true);
        assert_eq!(d.params().len(), 12);
        let s = Signals {
            time: Some(4_000.0),
            ..Default::default()
        };
        let p: Vec<f64> = (0..12).map(|i| (i as f64 - 5.0) * 1e-6).collect();
        let j = d.jacobian(&p, &s).unwrap();
        let v = d.predict(&p, &s).unwrap().value;
        assert!((j * DVector::from_vec(p) - v).norm() < 1e-18);
        assert!(d.linear_in_params());
    }

    #[test]
    fn without_a_span_or_a_time_it_says_what_is_missing() {
        let map: BTreeMap<String, ConfigValue> = BTreeMap::new();
        let e = InstrumentDrift::from_options(&Options::new("instrument_drift", &map))
            .unwrap_err()
            .to_string();
        assert!(e.contains("span") && e.contains("recording's clock"), "{e}");
        let d = drift(1, true);
        let e = d
            .predict(&[0.0; 6], &Signals::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("time"), "{e}");
    }
}
