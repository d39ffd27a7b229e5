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
use nalgebra::{DMatrix, Matrix3, RowVector3, Vector3};

use crate::forward::{v3, ForwardModel, KinematicTruth, Slot, ToolState};
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
        self.check_buffer("tracker Jacobian", out, TRACKER_ROWS)?;
        work.check(self)?;
        let inst = self.require(InstrumentKind::Tracker, instrument)?;
        let pose = pose_of(inst)?;
        let target = self.tool_point_jacobian(p, kin, q, s, &mut work.tool)?;
        // x = Rᵀ(P − T) and ∂x/∂pose
        s.target_point = Some(target);
        let mut xv = [0.0; 3];
        let ps = self.slots[pose];
        // the pose term is a `tracker_pose` (see `group_instruments`): its evaluation, with the
        // rotation's trigonometry done once for all readings at this pose
        let pp = self.part(pose, p);
        let rotation = work.pose_rotation([pp[3], pp[4], pp[5]]);
        rotation.evaluate_into(Vector3::new(pp[0], pp[1], pp[2]), target, &mut xv, work.pose.columns_mut(0, ps.len));
        let x = Vector3::new(xv[0], xv[1], xv[2]);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        // ∂x/∂P = Rᵀ = −∂x/∂T
        let rt: Matrix3<f64> = -work.pose.fixed_view::<3, 3>(0, 0).into_owned();
        if rho == 0.0 && inst.warmup.is_none() && inst.refraction.is_none() {
            // points given in the machine frame (pose = identity) can sit at the origin: with no
            // range terms the reported point is x itself, whose Jacobian needs no direction
            let pred = TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup: 0.0, refraction: 0.0 };
            write_chain(out, &work.tool, &work.pose, ps, &Matrix3::identity(), &RowVector3::zeros(), &rt);
            return Ok(pred);
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
        // Δρ_refraction is proportional to ρ: ∂ρ_m/∂x = g·uᵀ with g = 1 + Δρ_refraction/ρ;
        // the reported point y = ρ_m·u: ∂y/∂x = (ρ_m/ρ)(I − u uᵀ) + u·∂ρ_m/∂x
        let g = 1.0 + pred.refraction / rho;
        let f = pred.measured_range() / rho;
        let range_from_x = u.transpose() * g;
        let point_from_x = (Matrix3::identity() - u * u.transpose()) * f + u * range_from_x;
        write_chain(out, &work.tool, &work.pose, ps, &point_from_x, &range_from_x, &rt);
        // the range terms move the reported point along u
        for (row, i) in [inst.warmup, inst.refraction].into_iter().enumerate() {
            if let Some(i) = i {
                let sl = self.slots[i];
                for k in 0..sl.len {
                    let dr = work.range_terms[(row, k)];
                    out.fixed_view_mut::<3, 1>(0, sl.start + k).copy_from(&(u * dr));
                    out[(3, sl.start + k)] = dr;
                }
            }
        }
        Ok(pred)
    }
}

/// Rows of the tracker Jacobian `out` (reported point, then measured range) from the chain
/// x → (y, ρ_m): the machine terms' columns through the sighted point (∂x/∂P = `rt` times
/// `tool`, ∂P/∂p), the pose's columns from ∂x/∂pose (`pose`, its columns at `slot`). One fused
/// pass over the columns, in fixed-size arithmetic: this runs for every reading of a fit. The
/// range terms' columns are left zero (the tool Jacobian is zero there) for the caller.
fn write_chain(out: &mut DMatrix<f64>, tool: &DMatrix<f64>, pose: &DMatrix<f64>, slot: Slot, point_from_x: &Matrix3<f64>, range_from_x: &RowVector3<f64>, rt: &Matrix3<f64>) {
    let rows = |from_x: Matrix3<f64>, range: RowVector3<f64>, dx: Vector3<f64>| {
        let y = from_x * dx;
        [y.x, y.y, y.z, range.dot(&dx.transpose())]
    };
    let point_from_target = point_from_x * rt;
    let range_from_target = range_from_x * rt;
    let out_columns = out.as_mut_slice().chunks_exact_mut(TRACKER_ROWS);
    for (c, (o, t)) in out_columns.zip(tool.as_slice().chunks_exact(3)).enumerate() {
        let in_pose = c >= slot.start && c < slot.start + slot.len;
        let column = if in_pose {
            let k = c - slot.start;
            rows(*point_from_x, *range_from_x, Vector3::new(pose[(0, k)], pose[(1, k)], pose[(2, k)]))
        } else {
            rows(point_from_target, range_from_target, Vector3::new(t[0], t[1], t[2]))
        };
        o.copy_from_slice(&column);
    }
}
