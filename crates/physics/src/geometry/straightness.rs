//! `straightness` — straightness error of an axis in a perpendicular direction
//! (ISO 230-1 E_YX, E_ZX, ...; VDI 2617-3 xTy = straightness of the X motion along Y).
//!
//! d = δ_j(q_k)·e_j, j ≠ k, δ_j an [`ErrorSeries`] over the travel of axis k.
//! Frame: machine, tool relative to workpiece. Options: `axis`, `direction`, `basis`,
//! `order` (default 2), `travel`. A linear coefficient is indistinguishable from squareness —
//! declare one or the other, not both.

use nalgebra::{DMatrix, DMatrixViewMut};

use super::error_series::ErrorSeries;
use super::positioning::{series_along_into, series_params};
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Straightness {
    pub axis: Axis,
    pub direction: Axis,
    pub series: ErrorSeries,
}

impl Straightness {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let axis = o.axis("axis", None)?;
        let direction = o.axis("direction", None)?;
        if direction == axis {
            return Err(o.bad(
                "direction",
                format!("must differ from axis `{axis}` (that would be positioning)"),
            ));
        }
        Ok(Self {
            axis,
            direction,
            series: ErrorSeries::from_options(o, 2)?,
        })
    }
}

impl PhysicsTerm for Straightness {
    fn id(&self) -> TermId {
        TermId::Straightness
    }
    fn label(&self) -> String {
        format!("straightness[{}:{}]", self.axis, self.direction)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        series_params(&self.series, "m", 1e-3, "straightness error")
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::AxisPosition(self.axis)]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let q = s.position(self, self.axis)?;
        Ok(displacement(
            Frame::Machine,
            self.direction.unit() * self.series.eval(p, q),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let q = s.position(self, self.axis)?;
        let mut j = DMatrix::zeros(3, p.len());
        for (i, b) in self.series.basis_values(q).into_iter().enumerate() {
            j[(self.direction.index(), i)] = b;
        }
        Ok(j)
    }
    /// Linear: the series' value Σ cₖ·bₖ(q) along a fixed direction.
    fn linear_in_params(&self) -> bool {
        true
    }
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        check_len(self, p, self.series.len())?;
        let q = s.position(self, self.axis)?;
        series_along_into(&self.series, self.direction, p, q, value, jac);
        Ok(())
    }
}
