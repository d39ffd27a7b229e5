//! `positioning` — linear positioning error of an axis (ISO 230-1 E_XX; VDI 2617-3 xTx).
//!
//! d = δ_k(q_k)·e_k, with δ_k(q) = Σ_i c_i·φ_i(u(q)) an [`ErrorSeries`] over the axis travel.
//! Frame: machine; displacement of the tool relative to the workpiece (realised − commanded),
//! i.e. δ is defined as seen by a laser interferometer between tool and table.
//! Options: `axis`, `basis`, `order` (default 1), `travel`.

use nalgebra::{DMatrix, DMatrixViewMut};

use super::error_series::ErrorSeries;
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Positioning {
    pub axis: Axis,
    pub series: ErrorSeries,
}

impl Positioning {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            axis: o.axis("axis", None)?,
            series: ErrorSeries::from_options(o, 1)?,
        })
    }
}

/// Coefficient descriptors c0..cn shared by the series-based geometric terms.
pub(crate) fn series_params(
    series: &ErrorSeries,
    unit: &'static str,
    bound: f64,
    what: &str,
) -> Vec<ParamSpec> {
    (0..series.len())
        .map(|i| {
            ParamSpec::new(
                format!("c{i}"),
                unit,
                -bound,
                bound,
                0.0,
                format!(
                    "{what}: coefficient of basis function {i} ({:?})",
                    series.basis
                ),
            )
        })
        .collect()
}

/// Value and Jacobian of a series error along `direction` (d = e_dir·δ(q)), into buffers; the
/// value's arithmetic is `predict`'s.
pub(crate) fn series_along_into(
    series: &ErrorSeries,
    direction: Axis,
    p: &[f64],
    q: f64,
    value: &mut [f64],
    mut jac: DMatrixViewMut<'_, f64>,
) {
    let basis = series.basis_array(q);
    let v = direction.unit() * series.combine(&basis, p);
    value[..3].copy_from_slice(v.as_slice());
    jac.fill(0.0);
    for (i, b) in basis[..p.len()].iter().enumerate() {
        jac[(direction.index(), i)] = *b;
    }
}

impl PhysicsTerm for Positioning {
    fn id(&self) -> TermId {
        TermId::Positioning
    }
    fn label(&self) -> String {
        format!("positioning[{}]", self.axis)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        series_params(&self.series, "m", 1e-3, "positioning error")
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::AxisPosition(self.axis)]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let q = s.position(self, self.axis)?;
        Ok(displacement(
            Frame::Machine,
            self.axis.unit() * self.series.eval(p, q),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let q = s.position(self, self.axis)?;
        let mut j = DMatrix::zeros(3, p.len());
        for (i, b) in self.series.basis_values(q).into_iter().enumerate() {
            j[(self.axis.index(), i)] = b;
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
        series_along_into(&self.series, self.axis, p, q, value, jac);
        Ok(())
    }
}
