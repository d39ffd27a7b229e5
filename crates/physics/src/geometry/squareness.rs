//! `squareness` — out-of-squareness between two axes (ISO 230-1 E_C0X etc.; VDI xWy, xWz, yWz;
//! thesis P5 s_xy, s_xz, s_yz).
//!
//! Sign convention of thesis P5 eqs (8)–(9) (the axis vectors Y and Z):
//!   pair xy: d = (−y·s, 0, 0)     pair xz: d = (−z·s, 0, 0)     pair yz: d = (0, −z·s, 0)
//! i.e. a positive s tilts the second axis of the pair towards the negative first axis.
//! Frame: machine, tool relative to workpiece. Options: `pair` (xy | xz | yz). One parameter `s`.

use nalgebra::{DMatrix, DMatrixViewMut, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Squareness {
    /// Axis whose component is affected (first letter of the pair).
    pub affected: Axis,
    /// Axis whose position drives the error (second letter).
    pub driver: Axis,
}

impl Squareness {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let pair = o.text("pair", None)?;
        let (affected, driver) = match pair.as_str() {
            "xy" => (Axis::X, Axis::Y),
            "xz" => (Axis::X, Axis::Z),
            "yz" => (Axis::Y, Axis::Z),
            other => {
                return Err(o.bad(
                    "pair",
                    format!("`{other}` is not a pair; allowed: xy, xz, yz"),
                ))
            }
        };
        Ok(Self { affected, driver })
    }
    fn arm(&self, s: &Signals) -> Result<Vector3<f64>, PhysicsError> {
        Ok(-self.affected.unit() * s.position(self, self.driver)?)
    }
}

impl PhysicsTerm for Squareness {
    fn id(&self) -> TermId {
        TermId::Squareness
    }
    fn label(&self) -> String {
        format!("squareness[{}{}]", self.affected, self.driver)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new(
            "s",
            "rad",
            -2e-3,
            2e-3,
            0.0,
            "out-of-squareness angle",
        )]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::AxisPosition(self.driver)]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(displacement(Frame::Machine, self.arm(s)? * p[0]))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(DMatrix::from_column_slice(3, 1, self.arm(s)?.as_slice()))
    }
    /// Linear: s·arm, the arm from the driver's position.
    fn linear_in_params(&self) -> bool {
        true
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, 1)?;
        let arm = self.arm(s)?;
        value[..3].copy_from_slice((arm * p[0]).as_slice());
        jac.column_mut(0).copy_from(&arm);
        Ok(())
    }
}
