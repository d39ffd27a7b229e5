//! `angular` — roll, pitch or yaw of an axis, with its Abbe lever
//! (ISO 230-1 E_AX, E_BX, E_CX ...; VDI 2617-3 xRx, xRy, xRz).
//!
//! d = ε(q_k)·e_a × L,   L = r_abbe + δ_tool + Σ_{j ∈ lever_axes} q_j·e_j
//!
//! ε is the small rotation of the tool relative to the workpiece about machine axis a, caused by
//! the motion of axis k (an [`ErrorSeries`] in rad). L is the Abbe lever: the vector from the
//! rotation's reference point to the tool point — the tool/probe offset `abbe_offset` (m) plus the
//! positions of the axes carried between the reference and the tool (`lever_axes`). For an XFYZ
//! machine with the P5 chain (see `volumetric`): X → `[x, y, z]`, Y → `[z]`, Z → `[]` — and the
//! relative rotation of the workpiece-side X is minus the table's rotation. δ_tool is the
//! reading's target offset from the model's tool (`Signals::tool_offset_shift`, zero unless a
//! recording names another tool offset): the same ε seen through arms of several lengths is what
//! separates an angular error from a straightness (ISO 230-1 Annex A, multi-offset verification).
//! Frame: machine, tool relative to workpiece. Options: `axis`, `about`, `lever_axes`,
//! `abbe_offset`, `basis`, `order` (default 1), `travel`.

use nalgebra::{DMatrix, DMatrixViewMut, Vector3};

use super::error_series::ErrorSeries;
use super::positioning::series_params;
use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct Angular {
    pub axis: Axis,
    pub about: Axis,
    pub lever_axes: Vec<Axis>,
    pub abbe_offset: Vector3<f64>,
    pub series: ErrorSeries,
}

impl Angular {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            axis: o.axis("axis", None)?,
            about: o.axis("about", None)?,
            lever_axes: o.axes("lever_axes", &[])?,
            abbe_offset: o.vector3("abbe_offset", "m", Some(Vector3::zeros()))?,
            series: ErrorSeries::from_options(o, 1)?,
        })
    }

    fn lever(&self, s: &Signals) -> Result<(f64, Vector3<f64>), PhysicsError> {
        let q = s.position(self, self.axis)?;
        // a target moved on the spindle (a reflector at another offset) lengthens every arm by
        // its move: the term's `abbe_offset` is the arm at the model's tool
        let mut l = self.abbe_offset + s.tool_offset_shift.unwrap_or_default();
        for a in &self.lever_axes {
            l += a.unit() * s.position(self, *a)?;
        }
        Ok((q, self.about.unit().cross(&l)))
    }
}

impl PhysicsTerm for Angular {
    fn id(&self) -> TermId {
        TermId::Angular
    }
    fn label(&self) -> String {
        format!("angular[{}:{}]", self.axis, self.about)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        series_params(&self.series, "rad", 5e-3, "angular error")
    }
    fn signals(&self) -> Vec<SignalKind> {
        let mut v = vec![SignalKind::AxisPosition(self.axis)];
        for a in &self.lever_axes {
            if !v.contains(&SignalKind::AxisPosition(*a)) {
                v.push(SignalKind::AxisPosition(*a));
            }
        }
        v
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let (q, arm) = self.lever(s)?;
        Ok(displacement(Frame::Machine, arm * self.series.eval(p, q)))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, self.series.len())?;
        let (q, arm) = self.lever(s)?;
        let mut j = DMatrix::zeros(3, p.len());
        for (i, b) in self.series.basis_values(q).into_iter().enumerate() {
            j.set_column(i, &(arm * b));
        }
        Ok(j)
    }
    /// Linear: ε(q)·(e_a × L), L from the axis positions.
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
        check_len(self, p, self.series.len())?;
        let (q, arm) = self.lever(s)?;
        let basis = self.series.basis_array(q);
        let v = arm * self.series.combine(&basis, p);
        value[..3].copy_from_slice(v.as_slice());
        for (i, b) in basis[..p.len()].iter().enumerate() {
            jac.set_column(i, &(arm * *b));
        }
        Ok(())
    }
}
