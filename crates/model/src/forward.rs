//! The forward model: machine geometry + configured catalog terms + instrument terms + a stacked
//! parameter vector + [`Signals`] → the tool state and the predicted tracker reading, with the
//! analytic Jacobian of the reading w.r.t. the whole stacked parameter vector.
//!
//! Parameter vector (stated once): the machine terms' parameters in term order, then the
//! instrument terms' parameters in term order; names are `label.param`
//! ([`ForwardModel::param_names`]). The machine terms are the cell's `terms` (machine- and
//! tool-frame displacements, and the kinematic terms of a delta or an arm); the instrument terms
//! are the tracker's `tracker_pose` (required for a tracker reading), `tracker_warmup`,
//! `refraction` and `turbulence` (a scatter: it never enters a prediction).
//!
//! What the tracker reads for the true tool point P (tool-point frame of the family, see
//! [`crate::machine`]):
//! * x = `tracker_pose`(P) = Rᵀ(P − T), ρ = |x|, azimuth and elevation of x
//!   ([`metrocell_physics::instrument::spherical`]);
//! * measured range ρ_m = ρ + Δρ_refraction(ρ) + Δρ_warmup (in that order of summation);
//! * the reported point is ρ_m along the direction of x.
//!
//! Kinematic terms enter the Jacobian through crates/kinematics' analytic parameter Jacobians:
//! a delta's `forward_parameter_jacobian` at the firmware carriage heights, an arm's geometric
//! Jacobian (joint offsets), DH `parameter_jacobian` (DH `a`) or `origin_translation_jacobian`
//! (URDF origin lengths).

use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::dh::DhTable;
use metrocell_kinematics::serial::SerialChain;
use metrocell_kinematics::KinematicsError;
use metrocell_physics::instrument::spherical::to_spherical;
use metrocell_physics::model::TermModel;
use metrocell_physics::{ConfiguredTerm, EffectKind, Frame, PhysicsError, SignalKind, Signals, TermId};
use nalgebra::{DMatrix, Isometry3, Matrix3, Vector3};

use crate::machine::{MachineGeometry, MachineKinematics};

/// The tool at one instant. Poses are of the tool frame in the frame tool points are reported
/// in (workpiece: cartesian, delta, five_axis; cell: serial_arm), `p = pose·p_tool`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolState {
    pub nominal: Isometry3<f64>,
    pub truth: Isometry3<f64>,
    /// Displacement d (m): true − nominal tool point (cartesian, delta, arm); for a five-axis
    /// machine the linear axes' displacement in the machine frame.
    pub d: Vector3<f64>,
}

/// The kinematic part of the machine at one parameter vector (built once per parameter vector:
/// an arm's chain is cloned).
#[derive(Debug, Clone)]
pub enum KinematicTruth {
    /// Cartesian and five-axis machines: no kinematic terms.
    None,
    /// Delta: the nominal geometry the firmware inverts, and the true geometry (nominal + trims).
    Delta { nominal: DeltaGeometry, truth: DeltaGeometry },
    /// Arm: the true chain (joint offsets and link lengths applied), the joint offsets, and the
    /// true DH table if the arm came from one.
    Arm { chain: SerialChain, joint_offsets: Vec<f64>, dh: Option<DhTable> },
}

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

/// Cached displacements of terms that read nothing but temperature histories (valid while the
/// parameters and the histories are unchanged; the caller invalidates it when a history grows).
#[derive(Debug, Clone)]
pub struct DisplacementCache {
    history_only: Vec<bool>,
    values: Vec<Option<Vector3<f64>>>,
}

impl DisplacementCache {
    pub fn new(model: &ForwardModel) -> Self {
        let history_only: Vec<bool> = model
            .machine_terms
            .terms
            .iter()
            .map(|t| {
                let sig = t.term.signals();
                !sig.is_empty() && sig.iter().all(|s| matches!(s, SignalKind::TemperatureHistory(_)))
            })
            .collect();
        Self { values: vec![None; history_only.len()], history_only }
    }
    pub fn invalidate(&mut self) {
        self.values.iter_mut().for_each(|c| *c = None);
    }
}

#[derive(Debug, Clone, Copy)]
struct Slot {
    start: usize,
    len: usize,
}

/// The forward model over a machine, its terms and its instruments (borrowed; cheap to build).
#[derive(Debug)]
pub struct ForwardModel<'a> {
    pub machine: &'a MachineGeometry,
    pub machine_terms: &'a TermModel,
    pub instrument_terms: &'a TermModel,
    /// Column range of every term: machine terms, then instrument terms.
    slots: Vec<Slot>,
    n_params: usize,
    tracker_pose: Option<usize>,
    warmup: Option<usize>,
    refraction: Option<usize>,
}

fn kin_error(what: &str, q: &[f64], e: KinematicsError) -> PhysicsError {
    PhysicsError::InvalidInput { what: format!("{what} at q = {q:?}"), reason: e.to_string() }
}

fn v3(v: &nalgebra::DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

impl<'a> ForwardModel<'a> {
    /// Check that every term is one the model evaluates: machine terms are displacements in the
    /// machine or tool frame or kinematic terms of the machine's family; instrument terms are
    /// `tracker_pose`, `tracker_warmup`, `refraction`, `turbulence`, each at most once.
    pub fn new(machine: &'a MachineGeometry, machine_terms: &'a TermModel, instrument_terms: &'a TermModel) -> Result<Self, PhysicsError> {
        let bad = |label: String, reason: &str| PhysicsError::InvalidInput { what: format!("forward model, term `{label}`"), reason: reason.into() };
        let mut slots = Vec::new();
        let mut at = 0;
        for t in &machine_terms.terms {
            let id = t.term.id();
            let ok = match t.term.effect() {
                EffectKind::Displacement(Frame::Machine | Frame::Tool) => true,
                EffectKind::Kinematic => match &machine.kinematics {
                    MachineKinematics::Delta(_) => matches!(id, TermId::DeltaRodLength | TermId::DeltaRadius | TermId::DeltaTowerAngle | TermId::DeltaEndstop),
                    MachineKinematics::SerialArm(_) => matches!(id, TermId::JointOffset | TermId::LinkLength),
                    _ => false,
                },
                _ => false,
            };
            if !ok {
                return Err(bad(t.term.label(), "is not a machine term of this family (machine- or tool-frame displacement, or a kinematic term of the family)"));
            }
            let len = t.params.len();
            slots.push(Slot { start: at, len });
            at += len;
        }
        let (mut tracker_pose, mut warmup, mut refraction, mut turbulence) = (None, None, None, None);
        for (k, t) in instrument_terms.terms.iter().enumerate() {
            let i = machine_terms.terms.len() + k;
            let which = match t.term.id() {
                TermId::TrackerPose => &mut tracker_pose,
                TermId::TrackerWarmup => &mut warmup,
                TermId::Refraction => &mut refraction,
                TermId::Turbulence => &mut turbulence,
                _ => return Err(bad(t.term.label(), "is not an instrument term of the tracker model (tracker_pose, tracker_warmup, refraction, turbulence)")),
            };
            if which.replace(i).is_some() {
                return Err(bad(t.term.label(), "is given twice"));
            }
            let len = t.params.len();
            slots.push(Slot { start: at, len });
            at += len;
        }
        Ok(Self { machine, machine_terms, instrument_terms, slots, n_params: at, tracker_pose, warmup, refraction })
    }

    /// Length of the stacked parameter vector.
    pub fn param_count(&self) -> usize {
        self.n_params
    }

    /// `label.param` of every parameter, in stacked order.
    pub fn param_names(&self) -> Vec<String> {
        self.machine_terms.param_specs().into_iter().chain(self.instrument_terms.param_specs()).map(|s| s.name).collect()
    }

    /// The configured (true, for the twin) stacked parameter vector.
    pub fn params(&self) -> Vec<f64> {
        let mut p = self.machine_terms.params();
        p.extend(self.instrument_terms.params());
        p
    }

    /// Index in the stacked vector of the first parameter of the instrument term `id`.
    pub fn instrument_param_start(&self, id: TermId) -> Option<usize> {
        let i = match id {
            TermId::TrackerPose => self.tracker_pose,
            TermId::TrackerWarmup => self.warmup,
            TermId::Refraction => self.refraction,
            _ => None,
        }?;
        Some(self.slots[i].start)
    }

    fn term(&self, i: usize) -> &ConfiguredTerm {
        let n = self.machine_terms.terms.len();
        if i < n {
            &self.machine_terms.terms[i]
        } else {
            &self.instrument_terms.terms[i - n]
        }
    }

    fn part<'p>(&self, i: usize, p: &'p [f64]) -> &'p [f64] {
        let s = self.slots[i];
        &p[s.start..s.start + s.len]
    }

    fn check(&self, p: &[f64]) -> Result<(), PhysicsError> {
        if p.len() != self.n_params {
            return Err(PhysicsError::ParameterCount { term: "forward model".into(), expected: self.n_params, got: p.len() });
        }
        Ok(())
    }

    /// Set the axis signals from a joint vector and its velocity and approach directions: the
    /// first three joints of a cartesian, delta or five-axis machine (and a five-axis machine's
    /// B and C as rotary positions); none for an arm (it has no
    /// linear axes, and its terms were checked not to read axis signals).
    pub fn set_motion(&self, s: &mut Signals, q: &[f64], velocity: &[f64], approach: &[f64]) {
        if matches!(self.machine.kinematics, MachineKinematics::SerialArm(_)) {
            s.axis_position = [None; 3];
            s.approach_direction = [None; 3];
            s.axis_velocity = [None; 3];
        } else {
            s.axis_position = [Some(q[0]), Some(q[1]), Some(q[2])];
            s.approach_direction = [Some(approach[0]), Some(approach[1]), Some(approach[2])];
            s.axis_velocity = [Some(velocity[0]), Some(velocity[1]), Some(velocity[2])];
        }
        // a five-axis B/C table's rotary angles (rotary-axis location errors read them)
        s.rotary_position = match self.machine.kinematics {
            MachineKinematics::FiveAxis(_) if q.len() >= 5 => [None, Some(q[3]), Some(q[4])],
            _ => [None; 3],
        };
    }

    /// The kinematic part of the machine at parameters `p`.
    pub fn kinematic_truth(&self, p: &[f64]) -> Result<KinematicTruth, PhysicsError> {
        self.check(p)?;
        Ok(match &self.machine.kinematics {
            MachineKinematics::Delta(nominal) => {
                let mut g = *nominal;
                for (i, t) in self.machine_terms.terms.iter().enumerate() {
                    let v = self.part(i, p);
                    let add = |a: &mut [f64; 3]| (0..3).for_each(|k| a[k] += v[k]);
                    match t.term.id() {
                        TermId::DeltaRodLength => add(&mut g.rod_trim),
                        TermId::DeltaRadius => add(&mut g.radius_trim),
                        TermId::DeltaTowerAngle => add(&mut g.tower_angle_trim),
                        TermId::DeltaEndstop => add(&mut g.endstop),
                        _ => {}
                    }
                }
                KinematicTruth::Delta { nominal: *nominal, truth: g }
            }
            MachineKinematics::SerialArm(arm) => {
                let mut offsets = vec![0.0; arm.chain.dof()];
                let mut lengths = vec![0.0; arm.link_count()];
                for (i, t) in self.machine_terms.terms.iter().enumerate() {
                    let target = match t.term.id() {
                        TermId::JointOffset => &mut offsets,
                        TermId::LinkLength => &mut lengths,
                        _ => continue,
                    };
                    for (a, v) in target.iter_mut().zip(self.part(i, p)) {
                        *a += v;
                    }
                }
                let dh = arm.dh.as_ref().map(|d| {
                    let mut t = d.clone();
                    for (row, dl) in t.rows.iter_mut().zip(&lengths) {
                        row.a += dl;
                    }
                    t
                });
                KinematicTruth::Arm { chain: arm.true_chain(&offsets, &lengths), joint_offsets: offsets, dh }
            }
            _ => KinematicTruth::None,
        })
    }

    /// Σ of the machine terms' displacements for the nominal point `point` of the frame they
    /// act in. `tool_rotation` turns tool-frame terms (`Frame::Tool`, e.g. `tool_offset`) into
    /// that frame: identity where the tool does not turn, the tool frame's rotation on an arm.
    fn displacement(&self, p: &[f64], s: &mut Signals, point: Vector3<f64>, tool_rotation: &Matrix3<f64>, mut cache: Option<&mut DisplacementCache>) -> Result<Vector3<f64>, PhysicsError> {
        s.point = Some(point);
        let mut d = Vector3::zeros();
        for (i, t) in self.machine_terms.terms.iter().enumerate() {
            if t.term.effect() == EffectKind::Kinematic {
                continue;
            }
            if let Some(Some(c)) = cache.as_deref().map(|c| c.values[i]) {
                d += c;
                continue;
            }
            let v = v3(&t.term.predict(self.part(i, p), s)?.value);
            let v = if t.term.effect() == EffectKind::Displacement(Frame::Tool) { tool_rotation * v } else { v };
            if let Some(c) = cache.as_deref_mut() {
                if c.history_only[i] {
                    c.values[i] = Some(v);
                }
            }
            d += v;
        }
        Ok(d)
    }

    /// The tool at joint vector `q` for parameters `p` (`kin` = [`Self::kinematic_truth`] of the
    /// same `p`). `s` carries the axis signals ([`Self::set_motion`]), temperatures, load…;
    /// its `point` is set here. Forward kinematics runs once per call.
    pub fn tool_state(&self, p: &[f64], kin: &KinematicTruth, q: &[f64], s: &mut Signals, cache: Option<&mut DisplacementCache>) -> Result<ToolState, PhysicsError> {
        self.check(p)?;
        let mut cache = cache;
        self.tool_state_with(kin, q, |point, rotation| self.displacement(p, s, point, rotation, cache.as_deref_mut()))
    }

    /// The family's tool state, with the terms' displacement sum `displacement(nominal point of
    /// the frame the terms act in, tool rotation)`.
    fn tool_state_with(&self, kin: &KinematicTruth, q: &[f64], mut displacement: impl FnMut(Vector3<f64>, &Matrix3<f64>) -> Result<Vector3<f64>, PhysicsError>) -> Result<ToolState, PhysicsError> {
        let identity = Matrix3::identity();
        Ok(match &self.machine.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => {
                let qv = Vector3::new(q[0], q[1], q[2]);
                let n = self.machine.nominal_tool_point(&qv);
                // a delta's firmware inverts the nominal geometry; the carriages at those
                // heights put the effector where the true geometry says
                let kinematic = match kin {
                    KinematicTruth::Delta { nominal, truth } => {
                        let joints = nominal.inverse(&qv).map_err(|e| kin_error("delta kinematics", q, e))?;
                        truth.forward(&joints).map_err(|e| kin_error("delta kinematics", q, e))? - qv
                    }
                    _ => Vector3::zeros(),
                };
                let d = kinematic + displacement(n, &identity)?;
                ToolState { nominal: Isometry3::translation(n.x, n.y, n.z), truth: Isometry3::translation(n.x + d.x, n.y + d.y, n.z + d.z), d }
            }
            MachineKinematics::FiveAxis(f) => {
                // the spindle does not turn: the tool frame is the machine frame seen from the
                // workpiece, which turns with the table
                let tip = f.tip_machine(q);
                let d = displacement(tip, &identity)?;
                let workpiece_from_machine = f.geometry.machine_from_workpiece(q[3], q[4]).inverse();
                ToolState { nominal: workpiece_from_machine * Isometry3::translation(tip.x, tip.y, tip.z), truth: workpiece_from_machine * Isometry3::translation(tip.x + d.x, tip.y + d.y, tip.z + d.z), d }
            }
            MachineKinematics::SerialArm(a) => {
                let nominal = a.chain.tool_pose(q).map_err(|e| kin_error("arm forward kinematics", q, e))?;
                let true_pose = match kin {
                    KinematicTruth::Arm { chain, .. } => chain.tool_pose(q).map_err(|e| kin_error("true arm forward kinematics", q, e))?,
                    _ => nominal,
                };
                let n = nominal.translation.vector;
                let tool_rotation = true_pose.rotation.to_rotation_matrix().into_inner();
                let d = true_pose.translation.vector - n + displacement(n, &tool_rotation)?;
                ToolState { nominal, truth: Isometry3::from_parts((n + d).into(), true_pose.rotation), d }
            }
        })
    }

    /// The true tool point and its Jacobian w.r.t. the stacked parameters, written into `out`
    /// (3 × [`Self::param_count`]; columns of instrument terms are left zero). The point is the
    /// one [`Self::tool_state`] gives, bit for bit.
    pub fn tool_point_jacobian(&self, p: &[f64], kin: &KinematicTruth, q: &[f64], s: &mut Signals, out: &mut DMatrix<f64>) -> Result<Vector3<f64>, PhysicsError> {
        self.check(p)?;
        if out.nrows() != 3 || out.ncols() != self.n_params {
            return Err(PhysicsError::InvalidInput { what: "forward model, tool-point Jacobian buffer".into(), reason: format!("must be 3 × {}, is {} × {}", self.n_params, out.nrows(), out.ncols()) });
        }
        out.fill(0.0);
        // tool-frame displacement before turning (an arm's joint offsets turn it), and the
        // tool rotation the terms were turned by
        let mut tool_frame_sum = Vector3::zeros();
        let mut tool_rotation = Matrix3::identity();
        let tool = self.tool_state_with(kin, q, |point, rotation| {
            tool_rotation = *rotation;
            s.point = Some(point);
            let mut d = Vector3::zeros();
            let mut v = [0.0; 3];
            for (i, t) in self.machine_terms.terms.iter().enumerate() {
                let effect = t.term.effect();
                if effect == EffectKind::Kinematic {
                    continue;
                }
                let slot = self.slots[i];
                t.term.evaluate_into(self.part(i, p), s, &mut v, out.view_mut((0, slot.start), (3, slot.len)))?;
                let mut value = Vector3::new(v[0], v[1], v[2]);
                if effect == EffectKind::Displacement(Frame::Tool) {
                    tool_frame_sum += value;
                    value = rotation * value;
                    for c in slot.start..slot.start + slot.len {
                        let turned = rotation * out.fixed_view::<3, 1>(0, c);
                        out.fixed_view_mut::<3, 1>(0, c).copy_from(&turned);
                    }
                }
                d += value;
            }
            Ok(d)
        })?;
        if let MachineKinematics::FiveAxis(f) = &self.machine.kinematics {
            // the terms act in the machine frame; the tool point is in the workpiece frame
            let r = f.geometry.machine_from_workpiece(q[3], q[4]).inverse().rotation.to_rotation_matrix().into_inner();
            for c in 0..self.n_params {
                let turned = r * out.fixed_view::<3, 1>(0, c);
                out.fixed_view_mut::<3, 1>(0, c).copy_from(&turned);
            }
        }
        match kin {
            KinematicTruth::Delta { nominal, truth } => {
                let qv = Vector3::new(q[0], q[1], q[2]);
                let joints = nominal.inverse(&qv).map_err(|e| kin_error("delta kinematics", q, e))?;
                let fpj = truth.forward_parameter_jacobian(&joints).map_err(|e| kin_error("delta parameter Jacobian", q, e))?;
                for (i, t) in self.machine_terms.terms.iter().enumerate() {
                    // columns of DELTA_PARAMETER_NAMES: tower angle trims 2.., radius trims 5..,
                    // rod trims 8.., endstops 11..
                    let base = match t.term.id() {
                        TermId::DeltaTowerAngle => 2,
                        TermId::DeltaRadius => 5,
                        TermId::DeltaRodLength => 8,
                        TermId::DeltaEndstop => 11,
                        _ => continue,
                    };
                    let start = self.slots[i].start;
                    for k in 0..3 {
                        out.fixed_view_mut::<3, 1>(0, start + k).copy_from(&fpj.fixed_view::<3, 1>(0, base + k));
                    }
                }
            }
            KinematicTruth::Arm { chain, joint_offsets, dh } => {
                let geometric = chain.joint_offset_jacobian(q).map_err(|e| kin_error("arm Jacobian", q, e))?;
                let turned = tool_rotation * tool_frame_sum;
                let MachineKinematics::SerialArm(arm) = &self.machine.kinematics else { unreachable!("arm truth only for an arm") };
                for (i, t) in self.machine_terms.terms.iter().enumerate() {
                    let start = self.slots[i].start;
                    match t.term.id() {
                        TermId::JointOffset => {
                            for k in 0..chain.dof() {
                                let lin = geometric.fixed_view::<3, 1>(0, k).into_owned();
                                let ang = geometric.fixed_view::<3, 1>(3, k).into_owned();
                                // the offset turns the tool, and the tool-frame terms with it
                                out.fixed_view_mut::<3, 1>(0, start + k).copy_from(&(lin + ang.cross(&turned)));
                            }
                        }
                        TermId::LinkLength => match dh {
                            Some(table) => {
                                // a DH `a` translates everything after it along the row's x axis
                                let qo: Vec<f64> = q.iter().zip(joint_offsets).map(|(a, b)| a + b).collect();
                                let pj = table.parameter_jacobian(&qo).map_err(|e| kin_error("DH parameter Jacobian", q, e))?;
                                let base_rotation = chain.base.rotation.to_rotation_matrix().into_inner();
                                for k in 0..table.rows.len() {
                                    let col = base_rotation * pj.fixed_view::<3, 1>(0, 4 * k + 2);
                                    out.fixed_view_mut::<3, 1>(0, start + k).copy_from(&col);
                                }
                            }
                            None => {
                                // a URDF length stretches the joint's <origin xyz> along itself
                                let oj = chain.origin_translation_jacobian(q).map_err(|e| kin_error("URDF origin Jacobian", q, e))?;
                                for (k, joint) in arm.chain.joints.iter().enumerate() {
                                    let v = joint.pre.translation.vector;
                                    let n = v.norm();
                                    if n > 0.0 {
                                        let col = oj.fixed_view::<3, 3>(0, 3 * k) * (v / n);
                                        out.fixed_view_mut::<3, 1>(0, start + k).copy_from(&col);
                                    }
                                }
                            }
                        },
                        _ => {}
                    }
                }
            }
            KinematicTruth::None => {}
        }
        Ok(tool.truth.translation.vector)
    }

    fn tracker_pose_slot(&self) -> Result<usize, PhysicsError> {
        self.tracker_pose.ok_or_else(|| PhysicsError::InvalidInput { what: "forward model".into(), reason: "a tracker reading needs a `tracker_pose` instrument term".into() })
    }

    /// The tracker's reading of the true tool point `tool_point`. `s` carries
    /// `time_since_power_on` (warm-up) and the station's air (refraction); its `point` and
    /// `tracker_range` are set here.
    pub fn tracker(&self, p: &[f64], tool_point: Vector3<f64>, s: &mut Signals) -> Result<TrackerPrediction, PhysicsError> {
        self.check(p)?;
        let pose = self.tracker_pose_slot()?;
        s.point = Some(tool_point);
        let x = v3(&self.term(pose).term.predict(self.part(pose, p), s)?.value);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        let range_change = |i: Option<usize>, s: &Signals| -> Result<f64, PhysicsError> {
            match i {
                Some(i) => Ok(self.term(i).term.predict(self.part(i, p), s)?.value[0]),
                None => Ok(0.0),
            }
        };
        let warmup = range_change(self.warmup, s)?;
        let refraction = range_change(self.refraction, s)?;
        Ok(TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup, refraction })
    }

    /// The tracker reading at joint vector `q` and its Jacobian w.r.t. the stacked parameters,
    /// written into `out` ([`TRACKER_ROWS`] × [`Self::param_count`]: the reported point x, y, z
    /// in the tracker frame, then the measured range). The prediction is [`Self::tracker`]'s
    /// bit for bit. No allocation on cartesian and five-axis machines with the catalog's hot
    /// terms (see `PhysicsTerm::evaluate_into`); `work` holds the intermediate Jacobians.
    pub fn tracker_jacobian(&self, p: &[f64], kin: &KinematicTruth, q: &[f64], s: &mut Signals, work: &mut Workspace, out: &mut DMatrix<f64>) -> Result<TrackerPrediction, PhysicsError> {
        let n = self.n_params;
        if out.nrows() != TRACKER_ROWS || out.ncols() != n || work.tool.ncols() != n {
            return Err(PhysicsError::InvalidInput { what: "forward model, tracker Jacobian buffers".into(), reason: format!("must be {TRACKER_ROWS} × {n} (workspace: Workspace::new of this model), are {} × {} and 3 × {}", out.nrows(), out.ncols(), work.tool.ncols()) });
        }
        let pose = self.tracker_pose_slot()?;
        let tool_point = self.tool_point_jacobian(p, kin, q, s, &mut work.tool)?;
        // x = Rᵀ(P − T) and ∂x/∂pose
        s.point = Some(tool_point);
        let mut xv = [0.0; 3];
        let ps = self.slots[pose];
        self.term(pose).term.evaluate_into(self.part(pose, p), s, &mut xv, work.pose.columns_mut(0, ps.len))?;
        let x = Vector3::new(xv[0], xv[1], xv[2]);
        let (rho, az, el) = to_spherical(&x);
        s.tracker_range = Some(rho);
        if rho == 0.0 && self.warmup.is_none() && self.refraction.is_none() {
            // points given in the machine frame (pose = identity) can sit at the origin: with no
            // range terms the reported point is x itself, whose Jacobian needs no direction
            let rt: Matrix3<f64> = -work.pose.fixed_view::<3, 3>(0, 0).into_owned();
            work.point.gemm(1.0, &rt, &work.tool, 0.0);
            work.point.columns_mut(ps.start, ps.len).copy_from(&work.pose.columns(0, ps.len));
            out.rows_mut(0, 3).copy_from(&work.point);
            out.row_mut(3).fill(0.0);
            return Ok(TrackerPrediction { point: x, range: rho, azimuth: az, elevation: el, warmup: 0.0, refraction: 0.0 });
        }
        if !(rho > 0.0) {
            return Err(PhysicsError::InvalidInput { what: "forward model, tracker reading".into(), reason: "the target is at the tracker origin (range 0): no direction for the range terms".into() });
        }
        // ∂x/∂P = Rᵀ = −∂x/∂T
        let rt: Matrix3<f64> = -work.pose.fixed_view::<3, 3>(0, 0).into_owned();
        work.point.gemm(1.0, &rt, &work.tool, 0.0);
        work.point.columns_mut(ps.start, ps.len).copy_from(&work.pose.columns(0, ps.len));
        let mut range_changes = [0.0; 2];
        for (k, i) in [self.warmup, self.refraction].into_iter().enumerate() {
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
        for (row, i) in [self.warmup, self.refraction].into_iter().enumerate() {
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

/// Scratch Jacobians of [`ForwardModel::tracker_jacobian`], allocated once per model.
#[derive(Debug, Clone)]
pub struct Workspace {
    tool: DMatrix<f64>,
    point: DMatrix<f64>,
    pose: DMatrix<f64>,
    /// ∂Δρ/∂(own parameters): row 0 warm-up, row 1 refraction.
    range_terms: DMatrix<f64>,
}

impl Workspace {
    pub fn new(model: &ForwardModel) -> Self {
        let n = model.param_count();
        Self { tool: DMatrix::zeros(3, n), point: DMatrix::zeros(3, n), pose: DMatrix::zeros(3, 6), range_terms: DMatrix::zeros(2, 3) }
    }
}
