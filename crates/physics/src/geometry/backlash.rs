//! `backlash` — reversal error of an axis, by sign of approach (ISO 230-2 reversal value B).
//!
//! d = −(β/2)·s_k·e_k,   s_k = +1 when axis k approaches moving positive, −1 moving negative.
//!
//! The carriage lags the drive by half the lost motion, so moving positive it falls short
//! (−β/2) and moving negative it overshoots the commanded coordinate (+β/2); the difference
//! between the two approach directions is the reversal value β. Frame: machine, tool relative
//! to workpiece. Options: `axis`. Parameter `reversal` (m).

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Backlash {
    pub axis: Axis,
}

impl Backlash {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            axis: o.axis("axis", None)?,
        })
    }
}

impl PhysicsTerm for Backlash {
    fn id(&self) -> TermId {
        TermId::Backlash
    }
    fn label(&self) -> String {
        format!("backlash[{}]", self.axis)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("reversal", "m", 0.0, 100e-6, 0.0, "reversal value β (lost motion between the two approach directions; negative: the axis overshoots in the direction of travel)")
            .unusual_means("a negative reversal is an overshoot: the controller's backlash compensation set higher than the axis's lost motion (over-compensated); a reversal above 100 µm is worn or loose drive parts")]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::ApproachDirection(self.axis)]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        let dir = s.approach(self, self.axis)?;
        Ok(displacement(
            Frame::Machine,
            self.axis.unit() * (-0.5 * p[0] * dir),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        let dir = s.approach(self, self.axis)?;
        let mut j = DMatrix::zeros(3, 1);
        j[(self.axis.index(), 0)] = -0.5 * dir;
        Ok(j)
    }
}
