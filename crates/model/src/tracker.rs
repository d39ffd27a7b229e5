//! The laser tracker's reading and its analytic Jacobian.
//!
//! What a tracker reads for the sighted tool point P ([`ToolState::target`]: the tool relative
//! to the true part, in the frame the tracker pose is given in):
//! * x = `tracker_pose`(P) = Rᵀ(P − T), ρ = |x|, azimuth and elevation of x
//!   ([`metrocell_physics::instrument::spherical`]);
//! * measured range ρ_m = ρ + Δρ_refraction(ρ) + Δρ_warmup (in that order of summation);
//! * the reported point is ρ_m along the direction of x.

use metrocell_physics::instrument::spherical::to_spherical;
use metrocell_physics::{PhysicsError, Signals};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::forward::{v3, ForwardModel, KinematicTruth, ToolState};
use crate::instruments::{Instrument, InstrumentKind};
use crate::workspace::Workspace;

/// The predicted reading of a laser tracker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerPrediction {
    /// The true tool point in the tracker frame, m.
    pub point: Vector3<f64>,
    /// Its geometric range ρ = |point|, azimuth and elevation (rad).
    pub range: f64,
    pub azimuth: f64,
    pub elevation: f64,
    /// Range change of the `tracker_warmup` term (0 without one), m.
    pub warmup: f64,
    /// Range change of the `refraction` term (0 without one), m.
    pub refraction: f64,
}

impl TrackerPrediction {
    /// What the interferometer reports: ρ + Δρ_refraction + Δρ_warmup.
    pub fn measured_range(&self) -> f64 {
        self.range + self.refraction + self.warmup
    }
    /// The reported point: the measured range along the true direction.
    pub fn measured_point(&self) -> Vector3<f64> {
        metrocell_physics::instrument::spherical::from_spherical(self.measured_range(), self.azimuth, self.elevation)
    }
}

/// Rows of [`ForwardModel::tracker_jacobian`]: the reported point (x, y, z), then the measured range.
pub const TRACKER_ROWS: usize = 4;

fn pose_of(inst: &Instrument) -> Result<usize, PhysicsError> {
    inst.pose.ok_or_else(|| PhysicsError::InvalidInput { what: "forward model".into(), reason: format!("a reading of the {} needs its `tracker_pose` term", inst.describe()) })
}

impl ForwardModel<'_> {
    /// The reading of the model's only tracker for the tool state `tool` (see
    /// [`Self::tracker_of`]).
    pub fn tracker(&self, p: &[f64], tool: &ToolState, s: &mut Signals) -> Result<TrackerPrediction, PhysicsError> {
        self.tracker_of(None, p, tool, s)
    }

    /// The reading of tracker `instrument` (None: the only one) of the tool point it sights,
    /// [`ToolState::target`]. `s` carries `time_since_power_on` (warm-up) and the station's air
    /// (refraction); its `target_point` and `tracker_range` are set here.
    pub fn tracker_of(&self, instrument: Option<&str>, p: &[f64], tool: &ToolState, s: &mut Signals) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        let inst = self.require(InstrumentKind::Tracker, instrument)?;
        let pose = pose_of(inst)?;
        s.target_point = Some(tool.target());
        let x = v3(&self.term(pose).term.predict(self.part(pose, p), s)?.value);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        let range_change = |i: Option<usize>, s: &Signals| -> Result<f64, PhysicsError> {
            match i {
                Some(i) => Ok(self.term(i).term.predict(self.part(i, p), s)?.value[0]),
                None => Ok(0.0),
            }
        };
        let warmup = range_change(inst.warmup, s)?;
        let refraction = range_change(inst.refraction, s)?;
        Ok(TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup, refraction })
    }

    /// [`Self::tracker_jacobian_of`] the model's only tracker.
    pub fn tracker_jacobian(&self, p: &[f64], kin: &KinematicTruth, q: &[f64], s: &mut Signals, work: &mut Workspace, out: &mut DMatrix<f64>) -> Result<TrackerPrediction, PhysicsError> {
        self.tracker_jacobian_of(None, p, kin, q, s, work, out)
    }

    /// The reading of tracker `instrument` at joint vector `q` and its Jacobian w.r.t. the
    /// stacked parameters, written into `out` ([`TRACKER_ROWS`] × [`Self::param_count`]: the
    /// reported point x, y, z in the tracker frame, then the measured range). The prediction is
    /// [`Self::tracker_of`]'s bit for bit. No allocation on cartesian and five-axis machines
    /// with the catalog's hot terms (see `PhysicsTerm::evaluate_into`); `work` holds the
    /// intermediate Jacobians.
    #[allow(clippy::too_many_arguments)]
    pub fn tracker_jacobian_of(&self, instrument: Option<&str>, p: &[f64], kin: &KinematicTruth, q: &[f64], s: &mut Signals, work: &mut Workspace, out: &mut DMatrix<f64>) -> Result<TrackerPrediction, PhysicsError> {
        let n = self.n_params;
        self.check_buffer("tracker Jacobian", out, TRACKER_ROWS)?;
        work.check(self)?;
        let inst = self.require(InstrumentKind::Tracker, instrument)?;
        let pose = pose_of(inst)?;
        let target = self.tool_point_jacobian(p, kin, q, s, &mut work.tool)?;
        // x = Rᵀ(P − T) and ∂x/∂pose
        s.target_point = Some(target);
        let mut xv = [0.0; 3];
        let ps = self.slots[pose];
        self.term(pose).term.evaluate_into(self.part(pose, p), s, &mut xv, work.pose.columns_mut(0, ps.len))?;
        let x = Vector3::new(xv[0], xv[1], xv[2]);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        // ∂x/∂P = Rᵀ = −∂x/∂T
        let rt: Matrix3<f64> = -work.pose.fixed_view::<3, 3>(0, 0).into_owned();
        work.point.gemm(1.0, &rt, &work.tool, 0.0);
        work.point.columns_mut(ps.start, ps.len).copy_from(&work.pose.columns(0, ps.len));
        if rho == 0.0 && inst.warmup.is_none() && inst.refraction.is_none() {
            // points given in the machine frame (pose = identity) can sit at the origin: with no
            // range terms the reported point is x itself, whose Jacobian needs no direction
            out.rows_mut(0, 3).copy_from(&work.point);
            out.row_mut(3).fill(0.0);
            return Ok(TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup: 0.0, refraction: 0.0 });
        }
        if !(rho > 0.0) {
            return Err(PhysicsError::InvalidInput { what: "forward model, tracker reading".into(), reason: "the target is at the tracker origin (range 0): no direction for the range terms".into() });
        }
        let mut range_changes = [0.0; 2];
        for (k, i) in [inst.warmup, inst.refraction].into_iter().enumerate() {
            if let Some(i) = i {
                let sl = self.slots[i];
                let mut v = [0.0; 1];
                self.term(i).term.evaluate_into(self.part(i, p), s, &mut v, work.range_terms.view_mut((k, 0), (1, sl.len)))?;
                range_changes[k] = v[0];
            }
        }
        let pred = TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup: range_changes[0], refraction: range_changes[1] };
        let u = x / rho;
        // Δρ_refraction is proportional to ρ: ∂ρ_m/∂x = (1 + Δρ_refraction/ρ)·uᵀ
        let g = 1.0 + pred.refraction / rho;
        let measured = pred.measured_range();
        let f = measured / rho;
        for c in 0..n {
            let dx = work.point.fixed_view::<3, 1>(0, c).into_owned();
            out[(3, c)] = g * u.dot(&dx);
        }
        for (row, i) in [inst.warmup, inst.refraction].into_iter().enumerate() {
            if let Some(i) = i {
                let sl = self.slots[i];
                for k in 0..sl.len {
                    out[(3, sl.start + k)] += work.range_terms[(row, k)];
                }
            }
        }
        // reported point y = ρ_m·u: ∂y = (ρ_m/ρ)(I − u uᵀ)∂x + u ∂ρ_m
        for c in 0..n {
            let dx = work.point.fixed_view::<3, 1>(0, c).into_owned();
            let dy = (dx - u * u.dot(&dx)) * f + u * out[(3, c)];
            out.fixed_view_mut::<3, 1>(0, c).copy_from(&dy);
        }
        Ok(pred)
    }
}
