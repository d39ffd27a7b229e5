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
use crate::linear_target::KeptLayout;
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
        metrocell_physics::instrument::spherical::from_spherical(
            self.measured_range(),
            self.azimuth,
            self.elevation,
        )
    }
}

/// Rows of [`ForwardModel::tracker_jacobian`]: the reported point (x, y, z), then the measured range.
pub const TRACKER_ROWS: usize = 4;

/// The pose term that reads `s`: its setup's (`tracker_pose[<setup>]`) when the instrument has
/// one, else the pose of every reading.
fn pose_of(inst: &Instrument, s: &Signals) -> Result<usize, PhysicsError> {
    if let Some(setup) = s.setup.as_deref() {
        if let Some((_, k)) = inst.setup_poses.iter().find(|(name, _)| name == setup) {
            return Ok(*k);
        }
    }
    inst.pose.ok_or_else(|| {
        let reason = match (s.setup.as_deref(), inst.setup_poses.is_empty()) {
            (Some(setup), false) => format!("a reading of setup `{setup}` needs `tracker_pose[{setup}]`; the {} has poses for setups {}", inst.describe(), inst.setups().collect::<Vec<_>>().join(", ")),
            (None, false) => format!("a reading that names no setup needs a `tracker_pose` without one; the {} has poses for setups {} only", inst.describe(), inst.setups().collect::<Vec<_>>().join(", ")),
            _ => format!("a reading of the {} needs its `tracker_pose` term", inst.describe()),
        };
        PhysicsError::InvalidInput { what: "forward model".into(), reason }
    })
}

impl ForwardModel<'_> {
    /// The reading of the model's only tracker for the tool state `tool` (see
    /// [`Self::tracker_of`]).
    pub fn tracker(
        &self,
        p: &[f64],
        tool: &ToolState,
        s: &mut Signals,
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.tracker_of(None, p, tool, s)
    }

    /// The reading of tracker `instrument` (None: the only one) of the tool point it sights,
    /// [`ToolState::target`]. `s` carries `time_since_power_on` (warm-up) and the station's air
    /// (refraction); its `target_point` and `tracker_range` are set here.
    pub fn tracker_of(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        tool: &ToolState,
        s: &mut Signals,
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        let inst = self.require(InstrumentKind::Tracker, instrument)?;
        let pose = pose_of(inst, s)?;
        // a levelled instrument reads the point in the levelled frame: the base's tilt first
        s.target_point = Some(match inst.tilt {
            Some(t) => v3(&self
                .term(t)
                .term
                .predict(
                    self.part(t, p),
                    &Signals {
                        target_point: Some(tool.target()),
                        ..Signals::default()
                    },
                )?
                .value),
            None => tool.target(),
        });
        let x = match inst.drift {
            None => v3(&self.term(pose).term.predict(self.part(pose, p), s)?.value),
            Some(d) => {
                // the pose at this instant: the fitted pose plus the drift's change
                let change = self.term(d).term.predict(self.part(d, p), s)?.value;
                let at: Vec<f64> = self
                    .part(pose, p)
                    .iter()
                    .zip(change.iter())
                    .map(|(a, b)| a + b)
                    .collect();
                v3(&self.term(pose).term.predict(&at, s)?.value)
            }
        };
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
        Ok(TrackerPrediction {
            point: x,
            range: rho,
            azimuth: az,
            elevation: el,
            warmup,
            refraction,
        })
    }

    /// [`Self::tracker_jacobian_of`] the model's only tracker.
    pub fn tracker_jacobian(
        &self,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
        out: &mut DMatrix<f64>,
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.tracker_jacobian_of(None, p, kin, q, s, work, out)
    }

    /// The reading of tracker `instrument` at joint vector `q` and its Jacobian w.r.t. the
    /// stacked parameters, written into `out` ([`TRACKER_ROWS`] × [`Self::param_count`]: the
    /// reported point x, y, z in the tracker frame, then the measured range). The prediction is
    /// [`Self::tracker_of`]'s bit for bit. No allocation on cartesian and five-axis machines
    /// with the catalog's hot terms (see `PhysicsTerm::evaluate_into`); `work` holds the
    /// intermediate Jacobians.
    #[allow(clippy::too_many_arguments)]
    pub fn tracker_jacobian_of(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
        out: &mut DMatrix<f64>,
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.check_buffer("tracker Jacobian", out, TRACKER_ROWS)?;
        let (pred, chain) = self.tracker_chain(instrument, p, kin, q, s, work)?;
        for (c, o) in out
            .as_mut_slice()
            .chunks_exact_mut(TRACKER_ROWS)
            .enumerate()
        {
            let (y, range) = chain.column(work, work.tool.as_slice(), c);
            o.copy_from_slice(&[y.x, y.y, y.z, range]);
        }
        Ok(pred)
    }

    /// The reported point's rows of [`Self::tracker_jacobian_of`] in the given `columns`, each
    /// multiplied by `map` (3 × 3, e.g. a whitening) and handed to `write(column, map·∂y/∂p)`:
    /// for a caller that stores them elsewhere (an estimator's m × n Jacobian) without a buffer
    /// in between. The prediction is `tracker_jacobian_of`'s bit for bit, the columns to
    /// round-off (`map` is applied to the chain once, not to every column).
    #[allow(clippy::too_many_arguments)]
    pub fn tracker_point_jacobian_mapped(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
        map: &Matrix3<f64>,
        columns: &[usize],
        mut write: impl FnMut(usize, Vector3<f64>),
    ) -> Result<TrackerPrediction, PhysicsError> {
        let (pred, chain) = self.tracker_chain(instrument, p, kin, q, s, work)?;
        let chain = chain.mapped(map);
        for &c in columns {
            assert!(
                c < self.n_params,
                "column {c} of {} parameters",
                self.n_params
            );
            write(c, chain.column(work, work.tool.as_slice(), c).0);
        }
        Ok(pred)
    }

    /// [`Self::tracker_point_jacobian_mapped`] of a reading whose sighted point was kept
    /// (`kept`: [`Self::linear_target`]'s values packed by `layout`; the model's target must be
    /// linear, see [`crate::linear_target`]): the machine terms are not evaluated, the point is
    /// P₀ + A·p and its Jacobian A. Equal to the unkept evaluation to round-off.
    #[allow(clippy::too_many_arguments)]
    pub fn tracker_point_jacobian_mapped_linear(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        layout: &KeptLayout,
        kept: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
        map: &Matrix3<f64>,
        columns: &[usize],
        mut write: impl FnMut(usize, Vector3<f64>),
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        work.check(self)?;
        let machine = layout.columns();
        let (pred, chain) =
            self.tracker_chain_at(instrument, p, layout.target_at(p, kept), s, work)?;
        let chain = chain.mapped(map);
        for &c in columns {
            assert!(
                c < self.n_params,
                "column {c} of {} parameters",
                self.n_params
            );
            // a machine column moves only the sighted point; the instrument's through the chain
            let column = if c < machine {
                chain.point_from_target * layout.column(kept, c)
            } else {
                chain.column(work, &[], c).0
            };
            write(c, column);
        }
        Ok(pred)
    }

    /// The tracker's reading of a kept reading (as [`Self::tracker_point_jacobian_mapped_linear`]
    /// predicts it, bit for bit), without its Jacobian.
    pub fn tracker_linear(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        layout: &KeptLayout,
        kept: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        work.check(self)?;
        Ok(self
            .tracker_chain_at(instrument, p, layout.target_at(p, kept), s, work)?
            .0)
    }

    /// The reading of tracker `instrument` of a point fixed in the frame its pose is given in
    /// (a reference nest: the machine does not move it, only the instrument's own terms act).
    pub fn tracker_of_fixed_point(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        point: Vector3<f64>,
        s: &mut Signals,
    ) -> Result<TrackerPrediction, PhysicsError> {
        let tool = ToolState {
            nominal: nalgebra::Isometry3::identity(),
            truth: nalgebra::Isometry3::translation(point.x, point.y, point.z),
            d: Vector3::zeros(),
            workpiece: Vector3::zeros(),
        };
        self.tracker_of(instrument, p, &tool, s)
    }

    /// [`Self::tracker_point_jacobian_mapped`] of a fixed point ([`Self::tracker_of_fixed_point`]):
    /// the machine's columns are zero, the instrument's through the chain.
    #[allow(clippy::too_many_arguments)]
    pub fn tracker_point_jacobian_of_fixed_point_mapped(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        point: Vector3<f64>,
        s: &mut Signals,
        work: &mut Workspace,
        map: &Matrix3<f64>,
        columns: &[usize],
        mut write: impl FnMut(usize, Vector3<f64>),
    ) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        work.check(self)?;
        let (pred, chain) = self.tracker_chain_at(instrument, p, point, s, work)?;
        let chain = chain.mapped(map);
        for &c in columns {
            assert!(
                c < self.n_params,
                "column {c} of {} parameters",
                self.n_params
            );
            write(c, chain.column(work, &[], c).0);
        }
        Ok(pred)
    }

    /// The reading and its Jacobian as a [`TrackerChain`] over the intermediate Jacobians it
    /// leaves in `work`.
    fn tracker_chain(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
    ) -> Result<(TrackerPrediction, TrackerChain), PhysicsError> {
        work.check(self)?;
        let target = self.tool_point_jacobian(p, kin, q, s, &mut work.tool)?;
        self.tracker_chain_at(instrument, p, target, s, work)
    }

    /// [`Self::tracker_chain`] from the sighted point `target`, whose Jacobian the caller holds
    /// (`work.tool`, or a kept reading's A).
    fn tracker_chain_at(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        target: Vector3<f64>,
        s: &mut Signals,
        work: &mut Workspace,
    ) -> Result<(TrackerPrediction, TrackerChain), PhysicsError> {
        let inst = self.require(InstrumentKind::Tracker, instrument)?;
        let pose = pose_of(inst, s)?;
        // a levelled instrument: P_level = R_tilt·P (base_tilt), its Jacobian kept for the chain
        let tilt = inst.tilt.map(|t| {
            let q = self.part(t, p);
            let (r, d) = metrocell_physics::instrument::base_tilt::levelling(q[0], q[1]);
            (self.slots[t], r, [d[0] * target, d[1] * target])
        });
        let target = match &tilt {
            Some((_, r, _)) => r * target,
            None => target,
        };
        // x = Rᵀ(P − T) and ∂x/∂pose
        s.target_point = Some(target);
        let mut xv = [0.0; 3];
        let ps = self.slots[pose];
        // the pose term is a `tracker_pose` (see `group_instruments`): its evaluation, with the
        // rotation's trigonometry done once for all readings at this pose
        let mut pp = [0.0; 6];
        pp.copy_from_slice(self.part(pose, p));
        let drift = inst.drift.map(|d| (d, self.slots[d]));
        if let Some((d, ds)) = drift {
            // the pose at this instant: the fitted pose plus the drift's change (its Jacobian
            // w.r.t. the drift's parameters kept for the chain)
            let mut change = [0.0; 6];
            self.term(d).term.evaluate_into(
                self.part(d, p),
                s,
                &mut change,
                work.drift_pose.columns_mut(0, ds.len),
            )?;
            for (a, b) in pp.iter_mut().zip(change) {
                *a += b;
            }
        }
        let rotation = work.pose_rotation([pp[3], pp[4], pp[5]]);
        rotation.evaluate_into(
            Vector3::new(pp[0], pp[1], pp[2]),
            target,
            &mut xv,
            work.pose.columns_mut(0, ps.len),
        );
        if let Some((_, ds)) = drift {
            let dx = &work.pose * work.drift_pose.columns(0, ds.len);
            work.drift.columns_mut(0, ds.len).copy_from(&dx);
        }
        let drift_slot = drift.map(|(_, ds)| ds);
        let x = Vector3::new(xv[0], xv[1], xv[2]);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        // ∂x/∂P_level = Rᵀ = −∂x/∂T; ∂x/∂P = Rᵀ·R_tilt; ∂x/∂tilt = Rᵀ·∂R_tilt·P
        let r_t: Matrix3<f64> = -work.pose.fixed_view::<3, 3>(0, 0).into_owned();
        let (rt, tilt) = match tilt {
            Some((slot, r, d)) => (r_t * r, Some((slot, [r_t * d[0], r_t * d[1]]))),
            None => (r_t, None),
        };
        let range_slots = [inst.warmup, inst.refraction].map(|i| i.map(|i| self.slots[i]));
        if rho == 0.0 && inst.warmup.is_none() && inst.refraction.is_none() {
            // points given in the machine frame (pose = identity) can sit at the origin: with no
            // range terms the reported point is x itself, whose Jacobian needs no direction
            let pred = TrackerPrediction {
                point: x,
                range: rho,
                azimuth: az,
                elevation: el,
                warmup: 0.0,
                refraction: 0.0,
            };
            return Ok((
                pred,
                TrackerChain::new(
                    ps,
                    drift_slot,
                    tilt,
                    range_slots,
                    Vector3::zeros(),
                    Matrix3::identity(),
                    RowVector3::zeros(),
                    &rt,
                ),
            ));
        }
        if !(rho > 0.0) {
            return Err(PhysicsError::InvalidInput { what: "forward model, tracker reading".into(), reason: "the target is at the tracker origin (range 0): no direction for the range terms".into() });
        }
        let mut range_changes = [0.0; 2];
        for (k, i) in [inst.warmup, inst.refraction].into_iter().enumerate() {
            if let Some(i) = i {
                let sl = self.slots[i];
                let mut v = [0.0; 1];
                self.term(i).term.evaluate_into(
                    self.part(i, p),
                    s,
                    &mut v,
                    work.range_terms.view_mut((k, 0), (1, sl.len)),
                )?;
                range_changes[k] = v[0];
            }
        }
        let pred = TrackerPrediction {
            point: x,
            range: rho,
            azimuth: az,
            elevation: el,
            warmup: range_changes[0],
            refraction: range_changes[1],
        };
        let u = x / rho;
        // Δρ_refraction is proportional to ρ: ∂ρ_m/∂x = g·uᵀ with g = 1 + Δρ_refraction/ρ;
        // the reported point y = ρ_m·u: ∂y/∂x = (ρ_m/ρ)(I − u uᵀ) + u·∂ρ_m/∂x
        let g = 1.0 + pred.refraction / rho;
        let f = pred.measured_range() / rho;
        let range_from_x = u.transpose() * g;
        let point_from_x = (Matrix3::identity() - u * u.transpose()) * f + u * range_from_x;
        Ok((
            pred,
            TrackerChain::new(
                ps,
                drift_slot,
                tilt,
                range_slots,
                u,
                point_from_x,
                range_from_x,
                &rt,
            ),
        ))
    }
}

/// The tracker Jacobian as the chain it is, x → (y, ρ_m), column by column from the
/// intermediate Jacobians in a [`Workspace`]: the machine terms' columns through the sighted
/// point (∂x/∂P = Rᵀ times ∂P/∂p), the pose's from ∂x/∂pose, the range terms' along u. Fixed-size
/// arithmetic per column, no pass over a buffer in between: this runs for every reading of a fit.
#[derive(Clone, Copy)]
struct TrackerChain {
    pose: Slot,
    /// The `instrument_drift`'s columns, through the pose (`work.drift`: ∂x/∂drift).
    drift: Option<Slot>,
    /// The `base_tilt`'s columns: ∂x/∂roll, ∂x/∂pitch.
    tilt: Option<(Slot, [Vector3<f64>; 2])>,
    /// The warm-up's and the refraction's columns (rows 0 and 1 of the range-term Jacobian).
    range_terms: [Option<Slot>; 2],
    /// The direction of x.
    u: Vector3<f64>,
    point_from_x: Matrix3<f64>,
    range_from_x: RowVector3<f64>,
    point_from_target: Matrix3<f64>,
    range_from_target: RowVector3<f64>,
}

impl TrackerChain {
    #[allow(clippy::too_many_arguments)]
    fn new(
        pose: Slot,
        drift: Option<Slot>,
        tilt: Option<(Slot, [Vector3<f64>; 2])>,
        range_terms: [Option<Slot>; 2],
        u: Vector3<f64>,
        point_from_x: Matrix3<f64>,
        range_from_x: RowVector3<f64>,
        rt: &Matrix3<f64>,
    ) -> Self {
        Self {
            pose,
            drift,
            tilt,
            range_terms,
            u,
            point_from_x,
            range_from_x,
            point_from_target: point_from_x * rt,
            range_from_target: range_from_x * rt,
        }
    }

    /// The chain of `map`·y (e.g. the whitened point): the point's factors premultiplied once.
    fn mapped(&self, map: &Matrix3<f64>) -> Self {
        Self {
            u: map * self.u,
            point_from_x: map * self.point_from_x,
            point_from_target: map * self.point_from_target,
            ..*self
        }
    }

    /// Column `c` of ∂(reported point)/∂p and of ∂(measured range)/∂p, with `tool` the sighted
    /// point's Jacobian (3 values per column, column-major; columns past its end are zero:
    /// a kept reading holds the machine's only). (Inline: the callers are generic over their
    /// writer, so they are compiled in the caller's crate.)
    #[inline]
    fn column(&self, work: &Workspace, tool: &[f64], c: usize) -> (Vector3<f64>, f64) {
        let within = |s: Slot| c >= s.start && c < s.start + s.len;
        let through = |from_x: &Matrix3<f64>, range: &RowVector3<f64>, d: &[f64]| {
            let dx = Vector3::new(d[0], d[1], d[2]);
            (from_x * dx, range.dot(&dx.transpose()))
        };
        if within(self.pose) {
            let k = c - self.pose.start;
            return through(
                &self.point_from_x,
                &self.range_from_x,
                &work.pose.as_slice()[3 * k..3 * k + 3],
            );
        }
        if let Some(slot) = self.drift.filter(|s| within(*s)) {
            let k = c - slot.start;
            return through(
                &self.point_from_x,
                &self.range_from_x,
                &work.drift.as_slice()[3 * k..3 * k + 3],
            );
        }
        if let Some((slot, d)) = self.tilt.filter(|(s, _)| within(*s)) {
            let dx = d[c - slot.start];
            return (
                self.point_from_x * dx,
                self.range_from_x.dot(&dx.transpose()),
            );
        }
        for (row, slot) in self.range_terms.iter().enumerate() {
            if let Some(slot) = slot.filter(|s| within(*s)) {
                // the range terms move the reported point along u
                let dr = work.range_terms[(row, c - slot.start)];
                return (self.u * dr, dr);
            }
        }
        match tool.get(3 * c..3 * c + 3) {
            Some(d) => through(&self.point_from_target, &self.range_from_target, d),
            None => (Vector3::zeros(), 0.0),
        }
    }
}
