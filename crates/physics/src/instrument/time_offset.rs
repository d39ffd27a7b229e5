//! `time_offset` — latency between two streams: a stream stamped t actually sampled the machine
//! at t − Δt, so it reports x(t − Δt) ≈ x(t) − v·Δt.
//!
//! d = −Δt·v,  v = axis velocities (signal). Positive Δt = the stream lags. Frame: machine.

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone, Default)]
pub struct TimeOffset;

impl TimeOffset {
    pub fn from_options(_o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self)
    }
}

impl PhysicsTerm for TimeOffset {
    fn id(&self) -> TermId {
        TermId::TimeOffset
    }
    fn label(&self) -> String {
        "time_offset".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("latency", "s", -0.05, 0.05, 0.0, "Δt: how late the stream's samples are").unusual_means("a latency of more than 50 ms is not a fieldbus delay: the streams' clocks are not synchronised")]
    }
    fn signals(&self) -> Vec<SignalKind> {
        Axis::ALL
            .iter()
            .map(|a| SignalKind::AxisVelocity(*a))
            .collect()
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(displacement(Frame::Machine, -s.velocity(self)? * p[0]))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(DMatrix::from_column_slice(
            3,
            1,
            (-s.velocity(self)?).as_slice(),
        ))
    }
}
