//! The forward model: machine geometry + configured catalog terms + instrument terms + a stacked
//! parameter vector + [`Signals`] → the tool state and the predicted reading of every instrument
//! (tracker, touch probe, camera: see [`crate::tracker`], [`crate::probe`], [`crate::camera`]),
//! with the analytic Jacobian of each reading w.r.t. the whole stacked parameter vector.
//!
//! Parameter vector (stated once): the machine terms' parameters in term order, then the
//! instrument terms' parameters in term order; names are `label.param`
//! ([`ForwardModel::param_names`]). The machine terms are the cell's `terms`: displacements in
//! the machine, tool or workpiece frame, and the kinematic terms of a delta or an arm. The
//! instrument terms belong to instruments ([`crate::instruments`]): a tracker's `tracker_pose`,
//! `tracker_warmup`, `refraction`, `turbulence`; a probe's `probe_pretravel`; a camera's
//! `camera_scale`, `lens_distortion`.
//!
//! Frames (stated once for the model):
//! * machine- and tool-frame terms move the tool relative to the machine's idea of the workpiece
//!   frame: [`ToolState::truth`] (the physics convention: realised minus commanded tool point);
//! * workpiece-frame terms (`frame_misalignment`, `workpiece_expansion`) move the part: a feature
//!   with nominal position f (workpiece frame) truly lies at f + d_w(f), first order (both terms
//!   are first-order models). So an instrument that sights a part feature (a probe, a camera)
//!   sees it at f + d_w(f), and an instrument registered to the part (a tracker, whose pose is
//!   given in the workpiece frame) sees the tool at truth − d_w(nominal tool point)
//!   ([`ToolState::target`]). Both are the same first-order statement: only the tool's position
//!   relative to the part's features matters.
//!
//! Kinematic terms enter the Jacobian through crates/kinematics' analytic parameter Jacobians:
//! a delta's `forward_parameter_jacobian` at the firmware carriage heights, an arm's geometric
//! Jacobian (joint offsets, which also turn the tool), DH `parameter_jacobian` (DH `a`) or
//! `origin_translation_jacobian` (URDF origin lengths).

use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::dh::DhTable;
use metrocell_kinematics::serial::SerialChain;
use metrocell_kinematics::KinematicsError;
use metrocell_physics::model::TermModel;
use metrocell_physics::{
    ConfiguredTerm, EffectKind, Frame, PhysicsError, SignalKind, Signals, TermId,
};
use nalgebra::{DMatrix, Isometry3, Matrix3, Vector3};

use crate::arm_gravity::ArmGravity;
use crate::instruments::{group_instruments, Instrument};
use crate::machine::{MachineGeometry, MachineKinematics};

/// The tool at one instant. Poses are of the tool frame in the frame tool points are reported
/// in (workpiece: cartesian, delta, five_axis; cell: serial_arm), `p = pose·p_tool`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolState {
    pub nominal: Isometry3<f64>,
    /// The tool as the machine terms place it (relative to the machine's idea of the workpiece).
    pub truth: Isometry3<f64>,
    /// Displacement d (m): true − nominal tool point (cartesian, delta, arm); for a five-axis
    /// machine the linear axes' displacement in the machine frame. Machine terms only.
    pub d: Vector3<f64>,
    /// d_w: the workpiece terms' displacement of the part at the nominal tool point (workpiece
    /// frame, m; zero without workpiece terms).
    pub workpiece: Vector3<f64>,
}

impl ToolState {
    /// The tool point relative to the true part: `truth − d_w` (first order, see the module
    /// doc). What an instrument whose pose is given in the workpiece frame sights.
    pub fn target(&self) -> Vector3<f64> {
        self.truth.translation.vector - self.workpiece
    }
}

/// The kinematic part of the machine at one parameter vector (built once per parameter vector:
/// an arm's chain is cloned).
#[derive(Debug, Clone)]
pub enum KinematicTruth {
    /// Cartesian and five-axis machines: no kinematic terms.
    None,
    /// Delta: the nominal geometry the firmware inverts, and the true geometry (nominal + trims).
    Delta {
        nominal: DeltaGeometry,
        truth: DeltaGeometry,
    },
    /// Arm: the true chain (joint offsets and link lengths applied), the joint offsets, and the
    /// true DH table if the arm came from one.
    Arm {
        chain: SerialChain,
        joint_offsets: Vec<f64>,
        dh: Option<DhTable>,
    },
}

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
                !sig.is_empty()
                    && sig
                        .iter()
                        .all(|s| matches!(s, SignalKind::TemperatureHistory(_)))
            })
            .collect();
        Self {
            values: vec![None; history_only.len()],
            history_only,
        }
    }
    pub fn invalidate(&mut self) {
        self.values.iter_mut().for_each(|c| *c = None);
    }
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Slot {
    pub(crate) start: usize,
    pub(crate) len: usize,
}

/// The forward model over a machine, its terms and its instruments (borrowed; cheap to build).
#[derive(Debug)]
pub struct ForwardModel<'a> {
    pub machine: &'a MachineGeometry,
    pub machine_terms: &'a TermModel,
    pub instrument_terms: &'a TermModel,
    /// Column range of every term: machine terms, then instrument terms.
    pub(crate) slots: Vec<Slot>,
    pub(crate) n_params: usize,
    /// The instruments, their terms grouped by instance name.
    pub(crate) instruments: Vec<Instrument>,
    /// [`Self::linear_target_columns`], found once.
    pub(crate) linear_columns: Option<usize>,
}

pub(crate) fn kin_error(what: &str, q: &[f64], e: KinematicsError) -> PhysicsError {
    PhysicsError::InvalidInput {
        what: format!("{what} at q = {q:?}"),
        reason: e.to_string(),
    }
}

pub(crate) fn v3(v: &nalgebra::DVector<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

/// Which machine terms a displacement sum takes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Acting {
    /// Machine- and tool-frame displacements (they move the tool).
    OnTool,
    /// Workpiece-frame displacements (they move the part).
    OnPart,
}

impl Acting {
    fn takes(self, effect: EffectKind) -> bool {
        match self {
            Acting::OnTool => matches!(
                effect,
                EffectKind::Displacement(Frame::Machine | Frame::Tool)
            ),
            Acting::OnPart => effect == EffectKind::Displacement(Frame::Workpiece),
        }
    }
}

impl<'a> ForwardModel<'a> {
    /// Check that every term is one the model evaluates: machine terms are displacements in the
    /// machine, tool or workpiece frame or kinematic terms of the machine's family; instrument
    /// terms are those of a tracker, a probe or a camera, each at most once per instrument
    /// (instruments are told apart by the terms' `instrument` option, see
    /// [`crate::instruments`]).
    pub fn new(
        machine: &'a MachineGeometry,
        machine_terms: &'a TermModel,
        instrument_terms: &'a TermModel,
    ) -> Result<Self, PhysicsError> {
        let bad = |label: String, reason: &str| PhysicsError::InvalidInput {
            what: format!("forward model, term `{label}`"),
            reason: reason.into(),
        };
        let mut slots = Vec::new();
        let mut at = 0;
        for t in &machine_terms.terms {
            let id = t.term.id();
            let ok = match t.term.effect() {
                EffectKind::Displacement(Frame::Machine | Frame::Tool | Frame::Workpiece) => true,
                EffectKind::Kinematic => match &machine.kinematics {
                    MachineKinematics::Delta(_) => matches!(
                        id,
                        TermId::DeltaRodLength
                            | TermId::DeltaRadius
                            | TermId::DeltaTowerAngle
                            | TermId::DeltaEndstop
                    ),
                    MachineKinematics::SerialArm(_) => matches!(
                        id,
                        TermId::JointOffset
                            | TermId::LinkLength
                            | TermId::JointCompliance
                            | TermId::JointBacklash
                            | TermId::ColumnBending
                            | TermId::LinkThermalExpansion
                    ),
                    _ => false,
                },
                _ => false,
            };
            if !ok {
                return Err(bad(t.term.label(), "is not a machine term of this family (machine-, tool- or workpiece-frame displacement, or a kinematic term of the family)"));
            }
            let len = t.params.len();
            slots.push(Slot { start: at, len });
            at += len;
        }
        for t in &instrument_terms.terms {
            let len = t.params.len();
            slots.push(Slot { start: at, len });
            at += len;
        }
        let instruments = group_instruments(machine_terms.terms.len(), &instrument_terms.terms)?;
        let mut model = Self {
            machine,
            machine_terms,
            instrument_terms,
            slots,
            n_params: at,
            instruments,
            linear_columns: None,
        };
        model.linear_columns = model.find_linear_target_columns();
        Ok(model)
    }

    /// Length of the stacked parameter vector.
    pub fn param_count(&self) -> usize {
        self.n_params
    }

    /// `label.param` of every parameter, in stacked order.
    pub fn param_names(&self) -> Vec<String> {
        self.machine_terms
            .param_specs()
            .into_iter()
            .chain(self.instrument_terms.param_specs())
            .map(|s| s.name)
            .collect()
    }

    /// The configured (true, for the twin) stacked parameter vector.
    pub fn params(&self) -> Vec<f64> {
        let mut p = self.machine_terms.params();
        p.extend(self.instrument_terms.params());
        p
    }

    /// Index in the stacked vector of the first parameter of the instrument term `id` (of the
    /// first instrument that has one).
    pub fn instrument_param_start(&self, id: TermId) -> Option<usize> {
        let n = self.machine_terms.terms.len();
        let k = self
            .instrument_terms
            .terms
            .iter()
            .position(|t| t.term.id() == id)?;
        Some(self.slots[n + k].start)
    }

    /// Every `tracker_pose` of the model: its setup (None: the pose of every reading) and where
    /// its six parameters start in the stacked vector, in the model's order.
    pub fn pose_param_starts(&self) -> Vec<(Option<String>, usize)> {
        let n = self.machine_terms.terms.len();
        self.instrument_terms
            .terms
            .iter()
            .enumerate()
            .filter(|(_, t)| t.term.id() == TermId::TrackerPose)
            .map(|(k, t)| (t.term.setup().map(str::to_string), self.slots[n + k].start))
            .collect()
    }

    /// Where the parameters of the pose that reads `signals` start: its setup's pose
    /// (`tracker_pose[<setup>]`) when the model has one, else the pose of every reading (the
    /// tracker chain's own choice, `pose_of` in crate::tracker).
    pub fn pose_param_start_for(&self, signals: &Signals) -> Option<usize> {
        let trackers = || {
            self.instruments
                .iter()
                .filter(|i| i.kind == crate::instruments::InstrumentKind::Tracker)
        };
        let setup = signals.setup.as_deref();
        let own = trackers().find_map(|i| {
            i.setup_poses
                .iter()
                .find(|(s, _)| Some(s.as_str()) == setup)
                .map(|(_, k)| *k)
        });
        own.or_else(|| trackers().find_map(|i| i.pose))
            .map(|k| self.slots[k].start)
    }

    /// Column range (start, length) of term `label` in the stacked vector.
    pub fn term_columns(&self, label: &str) -> Option<(usize, usize)> {
        let i = self
            .machine_terms
            .terms
            .iter()
            .chain(&self.instrument_terms.terms)
            .position(|t| t.term.label() == label)?;
        Some((self.slots[i].start, self.slots[i].len))
    }

    pub(crate) fn term(&self, i: usize) -> &ConfiguredTerm {
        let n = self.machine_terms.terms.len();
        if i < n {
            &self.machine_terms.terms[i]
        } else {
            &self.instrument_terms.terms[i - n]
        }
    }

    pub(crate) fn part<'p>(&self, i: usize, p: &'p [f64]) -> &'p [f64] {
        let s = self.slots[i];
        &p[s.start..s.start + s.len]
    }

    pub(crate) fn check(&self, p: &[f64]) -> Result<(), PhysicsError> {
        if p.len() != self.n_params {
            return Err(PhysicsError::ParameterCount {
                term: "forward model".into(),
                expected: self.n_params,
                got: p.len(),
            });
        }
        Ok(())
    }

    pub(crate) fn check_buffer(
        &self,
        what: &str,
        m: &DMatrix<f64>,
        rows: usize,
    ) -> Result<(), PhysicsError> {
        if m.nrows() != rows || m.ncols() != self.n_params {
            return Err(PhysicsError::InvalidInput {
                what: format!("forward model, {what} buffer"),
                reason: format!(
                    "must be {rows} × {}, is {} × {}",
                    self.n_params,
                    m.nrows(),
                    m.ncols()
                ),
            });
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
                KinematicTruth::Delta {
                    nominal: *nominal,
                    truth: g,
                }
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
                KinematicTruth::Arm {
                    chain: arm.true_chain(&offsets, &lengths),
                    joint_offsets: offsets,
                    dh,
                }
            }
            _ => KinematicTruth::None,
        })
    }

    /// Σ of the machine- and tool-frame terms' displacements for the nominal point `point` of
    /// the frame they act in (set as `s.machine_point`). `tool_rotation` turns tool-frame terms
    /// (`Frame::Tool`, e.g. `tool_offset`) into that frame: identity where the tool does not
    /// turn, the tool frame's rotation on an arm.
    fn displacement(
        &self,
        p: &[f64],
        s: &mut Signals,
        point: Vector3<f64>,
        tool_rotation: &Matrix3<f64>,
        mut cache: Option<&mut DisplacementCache>,
    ) -> Result<Vector3<f64>, PhysicsError> {
        s.machine_point = Some(point);
        let mut d = Vector3::zeros();
        for (i, t) in self.machine_terms.terms.iter().enumerate() {
            let effect = t.term.effect();
            if !Acting::OnTool.takes(effect) {
                continue;
            }
            if let Some(Some(c)) = cache.as_deref().map(|c| c.values[i]) {
                d += c;
                continue;
            }
            let v = v3(&t.term.predict(self.part(i, p), s)?.value);
            let v = if effect == EffectKind::Displacement(Frame::Tool) {
                tool_rotation * v
            } else {
                v
            };
            if let Some(c) = cache.as_deref_mut() {
                if c.history_only[i] {
                    c.values[i] = Some(v);
                }
            }
            d += v;
        }
        Ok(d)
    }

    /// Whether any machine term acts in the workpiece frame.
    pub fn has_workpiece_terms(&self) -> bool {
        self.machine_terms
            .terms
            .iter()
            .any(|t| Acting::OnPart.takes(t.term.effect()))
    }

    /// d_w: Σ of the workpiece terms' displacements of the part at its nominal point `point`
    /// (workpiece frame, m); `s.workpiece_point` is set to `point`. With `jac` (3 × parameters),
    /// `sign`·∂d_w/∂p is written into the workpiece terms' columns (the others are left as they
    /// are). No allocation when the terms override `evaluate_into`.
    pub fn workpiece_displacement(
        &self,
        p: &[f64],
        s: &mut Signals,
        point: Vector3<f64>,
        mut jac: Option<&mut DMatrix<f64>>,
        sign: f64,
    ) -> Result<Vector3<f64>, PhysicsError> {
        s.workpiece_point = Some(point);
        let mut d = Vector3::zeros();
        let mut v = [0.0; 3];
        for (i, t) in self.machine_terms.terms.iter().enumerate() {
            if !Acting::OnPart.takes(t.term.effect()) {
                continue;
            }
            match jac.as_deref_mut() {
                Some(out) => {
                    let slot = self.slots[i];
                    let mut view = out.view_mut((0, slot.start), (3, slot.len));
                    t.term
                        .evaluate_into(self.part(i, p), s, &mut v, view.rows_mut(0, 3))?;
                    if sign != 1.0 {
                        view *= sign;
                    }
                    d += Vector3::new(v[0], v[1], v[2]);
                }
                None => d += v3(&t.term.predict(self.part(i, p), s)?.value),
            }
        }
        Ok(d)
    }

    /// The tool at joint vector `q` for parameters `p` (`kin` = [`Self::kinematic_truth`] of the
    /// same `p`). `s` carries the axis signals ([`Self::set_motion`]), temperatures, load…;
    /// its `workpiece_point` is set here (the nominal tool point, for [`ToolState::workpiece`]).
    /// Forward kinematics runs once per call.
    pub fn tool_state(
        &self,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        cache: Option<&mut DisplacementCache>,
    ) -> Result<ToolState, PhysicsError> {
        self.check(p)?;
        let mut cache = cache;
        let gravity = self.gravity_of(p, q, s)?;
        let mut tool = self.tool_state_with(
            kin,
            q,
            s.tool_offset_shift,
            gravity.as_ref().map(|g| (g, p)),
            |point, rotation| self.displacement(p, s, point, rotation, cache.as_deref_mut()),
        )?;
        if self.has_workpiece_terms() {
            tool.workpiece =
                self.workpiece_displacement(p, s, tool.nominal.translation.vector, None, 1.0)?;
        }
        Ok(tool)
    }

    /// The nominal tool at joint vector `q` (no terms: `truth` = `nominal`, d = 0), e.g. for a
    /// nominal camera pose ([`Self::camera_pose`]).
    pub fn nominal_tool(&self, q: &[f64]) -> Result<ToolState, PhysicsError> {
        let n = self.machine.joint_names().len();
        if q.len() != n {
            return Err(PhysicsError::InvalidInput {
                what: "forward model, joint vector".into(),
                reason: format!(
                    "has {} values, the machine has {n} joints ({})",
                    q.len(),
                    self.machine.joint_names().join(", ")
                ),
            });
        }
        self.tool_state_with(&KinematicTruth::None, q, None, None, |_, _| {
            Ok(Vector3::zeros())
        })
    }

    /// The family's tool state, with the machine terms' displacement sum `displacement(nominal
    /// point of the frame the terms act in, tool rotation)` (tool-frame terms are turned by the
    /// rotation). `tool_shift`: the sighted target's offset from the model's tool point
    /// ([`Signals::tool_offset_shift`]; cartesian and delta machines, whose spindle does not turn).
    fn tool_state_with(
        &self,
        kin: &KinematicTruth,
        q: &[f64],
        tool_shift: Option<Vector3<f64>>,
        gravity: Option<(&ArmGravity, &[f64])>,
        mut displacement: impl FnMut(Vector3<f64>, &Matrix3<f64>) -> Result<Vector3<f64>, PhysicsError>,
    ) -> Result<ToolState, PhysicsError> {
        let identity = Matrix3::identity();
        let zero = Vector3::zeros();
        Ok(match &self.machine.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => {
                let qv = Vector3::new(q[0], q[1], q[2]);
                let n = self.machine.nominal_tool_point(&qv) + tool_shift.unwrap_or_default();
                // a delta's firmware inverts the nominal geometry; the carriages at those
                // heights put the effector where the true geometry says
                let kinematic = match kin {
                    KinematicTruth::Delta { nominal, truth } => {
                        let joints = nominal
                            .inverse(&qv)
                            .map_err(|e| kin_error("delta kinematics", q, e))?;
                        truth
                            .forward(&joints)
                            .map_err(|e| kin_error("delta kinematics", q, e))?
                            - qv
                    }
                    _ => Vector3::zeros(),
                };
                let d = kinematic + displacement(n, &identity)?;
                ToolState {
                    nominal: Isometry3::translation(n.x, n.y, n.z),
                    truth: Isometry3::translation(n.x + d.x, n.y + d.y, n.z + d.z),
                    d,
                    workpiece: zero,
                }
            }
            _ if tool_shift.is_some_and(|d| d != Vector3::zeros()) => {
                return Err(PhysicsError::InvalidInput {
                    what: "forward model, a reading's tool offset".into(),
                    reason: "a recorded tool offset (/machine/tool_offset) other than the model's is read on cartesian and delta machines only; record five-axis and arm targets with the model's tool".into(),
                })
            }
            MachineKinematics::FiveAxis(f) => {
                // the spindle does not turn: the tool frame is the machine frame seen from the
                // workpiece, which turns with the table
                let tip = f.tip_machine(q);
                let d = displacement(tip, &identity)?;
                let workpiece_from_machine =
                    f.geometry.machine_from_workpiece(q[3], q[4]).inverse();
                ToolState {
                    nominal: workpiece_from_machine * Isometry3::translation(tip.x, tip.y, tip.z),
                    truth: workpiece_from_machine
                        * Isometry3::translation(tip.x + d.x, tip.y + d.y, tip.z + d.z),
                    d,
                    workpiece: zero,
                }
            }
            MachineKinematics::SerialArm(a) => {
                let nominal = a
                    .chain
                    .tool_pose(q)
                    .map_err(|e| kin_error("arm forward kinematics", q, e))?;
                // the joints where gravity puts them (compliance, backlash)
                let deflected = gravity.map(|(g, _)| g.deflected(q));
                let q_true = deflected.as_deref().unwrap_or(q);
                let true_pose = match kin {
                    KinematicTruth::Arm { chain, .. } => chain
                        .tool_pose(q_true)
                        .map_err(|e| kin_error("true arm forward kinematics", q, e))?,
                    _ => nominal,
                };
                let n = nominal.translation.vector;
                let tool_rotation = true_pose.rotation.to_rotation_matrix().into_inner();
                // the column's tilt and the links' expansion move the tool point further
                let bent = gravity.map_or(Vector3::zeros(), |(g, params)| {
                    g.displacement(self, params, &true_pose.translation.vector)
                });
                let d = true_pose.translation.vector - n + bent + displacement(n, &tool_rotation)?;
                ToolState {
                    nominal,
                    truth: Isometry3::from_parts((n + d).into(), true_pose.rotation),
                    d,
                    workpiece: zero,
                }
            }
        })
    }

    /// The tool point an instrument registered to the part sights ([`ToolState::target`]) and
    /// its Jacobian w.r.t. the stacked parameters, written into `out` (3 × [`Self::param_count`];
    /// columns of instrument terms are left zero). The point is `tool_state(..).target()`, bit
    /// for bit.
    pub fn tool_point_jacobian(
        &self,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        out: &mut DMatrix<f64>,
    ) -> Result<Vector3<f64>, PhysicsError> {
        let mut tool = self.tool_jacobian(p, kin, q, s, out, None)?;
        if self.has_workpiece_terms() {
            tool.workpiece = self.workpiece_displacement(
                p,
                s,
                tool.nominal.translation.vector,
                Some(out),
                -1.0,
            )?;
        }
        Ok(tool.target())
    }

    /// The tool state at `q` (as [`Self::tool_state`], bit for bit, with `workpiece` left zero),
    /// ∂(true tool point)/∂p of the machine terms into `lin` (3 × parameters; every other column
    /// zero) and, with `ang`, ∂(tool rotation)/∂p as angular-velocity columns in the frame tool
    /// points are reported in (non-zero only for an arm's joint offsets: no other parameter
    /// turns the tool).
    pub(crate) fn tool_jacobian(
        &self,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        lin: &mut DMatrix<f64>,
        mut ang: Option<&mut DMatrix<f64>>,
    ) -> Result<ToolState, PhysicsError> {
        self.check(p)?;
        self.check_buffer("tool-point Jacobian", lin, 3)?;
        // through the slice: a memset, where nalgebra's fill walks the elements one by one
        lin.as_mut_slice().fill(0.0);
        if let Some(a) = ang.as_deref_mut() {
            self.check_buffer("tool-rotation Jacobian", a, 3)?;
            a.fill(0.0);
        }
        let out = lin;
        let ang_out = ang;
        // tool-frame displacement before turning (an arm's joint offsets turn it), and the
        // tool rotation the terms were turned by
        let mut tool_frame_sum = Vector3::zeros();
        let mut tool_rotation = Matrix3::identity();
        let gravity = self.gravity_of(p, q, s)?;
        let tool_shift = s.tool_offset_shift;
        let tool = self.tool_state_with(
            kin,
            q,
            tool_shift,
            gravity.as_ref().map(|g| (g, p)),
            |point, rotation| {
                tool_rotation = *rotation;
                s.machine_point = Some(point);
                let mut d = Vector3::zeros();
                let mut v = [0.0; 3];
                for (i, t) in self.machine_terms.terms.iter().enumerate() {
                    let effect = t.term.effect();
                    if !Acting::OnTool.takes(effect) {
                        continue;
                    }
                    let slot = self.slots[i];
                    t.term.evaluate_into(
                        self.part(i, p),
                        s,
                        &mut v,
                        out.view_mut((0, slot.start), (3, slot.len)),
                    )?;
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
            },
        )?;
        if let MachineKinematics::FiveAxis(f) = &self.machine.kinematics {
            // the terms act in the machine frame; the tool point is in the workpiece frame
            let r = f
                .geometry
                .machine_from_workpiece(q[3], q[4])
                .inverse()
                .rotation
                .to_rotation_matrix()
                .into_inner();
            for c in 0..self.n_params {
                let turned = r * out.fixed_view::<3, 1>(0, c);
                out.fixed_view_mut::<3, 1>(0, c).copy_from(&turned);
            }
        }
        match kin {
            KinematicTruth::Delta { nominal, truth } => {
                self.delta_columns(nominal, truth, q, out)?;
            }
            KinematicTruth::Arm {
                chain,
                joint_offsets,
                dh,
            } => {
                let turned = tool_rotation * tool_frame_sum;
                let arm = ArmTruth {
                    chain,
                    joint_offsets,
                    dh: dh.as_ref(),
                };
                let at = ArmReading {
                    q,
                    gravity: gravity.as_ref(),
                    turned: &turned,
                    point: &tool.truth.translation.vector,
                };
                self.arm_columns(&arm, &at, out, ang_out)?;
            }
            KinematicTruth::None => {}
        }
        Ok(tool)
    }

    /// A delta's trims: their columns of the true geometry's parameter Jacobian at the joints
    /// the nominal geometry commands for `q`.
    fn delta_columns(
        &self,
        nominal: &DeltaGeometry,
        truth: &DeltaGeometry,
        q: &[f64],
        out: &mut DMatrix<f64>,
    ) -> Result<(), PhysicsError> {
        let qv = Vector3::new(q[0], q[1], q[2]);
        let joints = nominal
            .inverse(&qv)
            .map_err(|e| kin_error("delta kinematics", q, e))?;
        let fpj = truth
            .forward_parameter_jacobian(&joints)
            .map_err(|e| kin_error("delta parameter Jacobian", q, e))?;
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
                out.fixed_view_mut::<3, 1>(0, start + k)
                    .copy_from(&fpj.fixed_view::<3, 1>(0, base + k));
            }
        }
        Ok(())
    }

    /// An arm's columns: its gravity terms', and its joint offsets' (which turn the tool, and
    /// the tool-frame terms with it) and link lengths' (a DH `a`, or a URDF origin's length).
    fn arm_columns(
        &self,
        arm_truth: &ArmTruth,
        at: &ArmReading,
        out: &mut DMatrix<f64>,
        mut ang_out: Option<&mut DMatrix<f64>>,
    ) -> Result<(), PhysicsError> {
        let (chain, q) = (arm_truth.chain, at.q);
        let deflected = at.gravity.map(|g| g.deflected(q));
        let geometric = chain
            .joint_offset_jacobian(deflected.as_deref().unwrap_or(q))
            .map_err(|e| kin_error("arm Jacobian", q, e))?;
        if let Some(g) = at.gravity {
            self.gravity_columns(
                g,
                &geometric,
                at.turned,
                at.point,
                out,
                ang_out.as_deref_mut(),
            );
        }
        let MachineKinematics::SerialArm(arm) = &self.machine.kinematics else {
            return Err(PhysicsError::InvalidInput {
                what: "forward model".into(),
                reason: "an arm's kinematic truth given for a machine that is not an arm".into(),
            });
        };
        for (i, t) in self.machine_terms.terms.iter().enumerate() {
            let start = self.slots[i].start;
            match t.term.id() {
                TermId::JointOffset => {
                    for k in 0..chain.dof() {
                        let lin = geometric.fixed_view::<3, 1>(0, k).into_owned();
                        let ang = geometric.fixed_view::<3, 1>(3, k).into_owned();
                        // the offset turns the tool, and the tool-frame terms with it
                        out.fixed_view_mut::<3, 1>(0, start + k)
                            .copy_from(&(lin + ang.cross(at.turned)));
                        if let Some(a) = ang_out.as_deref_mut() {
                            a.fixed_view_mut::<3, 1>(0, start + k).copy_from(&ang);
                        }
                    }
                }
                TermId::LinkLength => match arm_truth.dh {
                    Some(table) => {
                        // a DH `a` translates everything after it along the row's x axis
                        let qo: Vec<f64> = q
                            .iter()
                            .zip(arm_truth.joint_offsets)
                            .map(|(a, b)| a + b)
                            .collect();
                        let pj = table
                            .parameter_jacobian(&qo)
                            .map_err(|e| kin_error("DH parameter Jacobian", q, e))?;
                        let base_rotation = chain.base.rotation.to_rotation_matrix().into_inner();
                        for k in 0..table.rows.len() {
                            let col = base_rotation * pj.fixed_view::<3, 1>(0, 4 * k + 2);
                            out.fixed_view_mut::<3, 1>(0, start + k).copy_from(&col);
                        }
                    }
                    None => {
                        // a URDF length stretches the joint's <origin xyz> along itself
                        let oj = chain
                            .origin_translation_jacobian(q)
                            .map_err(|e| kin_error("URDF origin Jacobian", q, e))?;
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
        Ok(())
    }
}

/// An arm's kinematic truth (the parts of [`KinematicTruth::Arm`]).
struct ArmTruth<'k> {
    chain: &'k SerialChain,
    joint_offsets: &'k [f64],
    dh: Option<&'k DhTable>,
}

/// What an arm's columns are taken at: the reading's joints, the gravity terms' state, the
/// tool-frame displacement turned with the tool, and the true tool point.
struct ArmReading<'r> {
    q: &'r [f64],
    gravity: Option<&'r ArmGravity>,
    turned: &'r Vector3<f64>,
    point: &'r Vector3<f64>,
}

impl ForwardModel<'_> {
    /// The gravity terms' state of an arm at reading `q` (None on other machines, or an arm
    /// without them).
    fn gravity_of(
        &self,
        p: &[f64],
        q: &[f64],
        s: &Signals,
    ) -> Result<Option<ArmGravity>, PhysicsError> {
        match &self.machine.kinematics {
            MachineKinematics::SerialArm(arm) => self.arm_gravity(arm, p, q, s),
            _ => Ok(None),
        }
    }

    /// The gravity terms' Jacobian columns: a compliance's joint column times its torque, a
    /// backlash's times half the torque's sign (each joint column turning the tool-frame terms
    /// with it, `turned`), a column's compliances their unit tilts at the true tool point
    /// `point`, the links' expansion its direction times T − 20 °C.
    fn gravity_columns(
        &self,
        g: &ArmGravity,
        geometric: &DMatrix<f64>,
        turned: &Vector3<f64>,
        point: &Vector3<f64>,
        out: &mut DMatrix<f64>,
        mut ang: Option<&mut DMatrix<f64>>,
    ) {
        let mut joint_columns = |term: usize, vars: &[usize], factor: &dyn Fn(f64) -> f64| {
            let start = self.slots[term].start;
            for (c, &v) in vars.iter().enumerate() {
                let f = factor(g.torques[v]);
                let lin = geometric.fixed_view::<3, 1>(0, v).into_owned();
                let a = geometric.fixed_view::<3, 1>(3, v).into_owned();
                out.fixed_view_mut::<3, 1>(0, start + c)
                    .copy_from(&((lin + a.cross(turned)) * f));
                if let Some(ang) = ang.as_deref_mut() {
                    ang.fixed_view_mut::<3, 1>(0, start + c).copy_from(&(a * f));
                }
            }
        };
        for (term, vars) in &g.compliance {
            joint_columns(*term, vars, &|tau| tau);
        }
        for (term, vars) in &g.backlash {
            joint_columns(*term, vars, &|tau| 0.5 * tau.signum());
        }
        if let Some(c) = &g.column {
            let start = self.slots[c.term].start;
            for (k, u) in c.unit_effects(point).iter().enumerate() {
                out.fixed_view_mut::<3, 1>(0, start + k).copy_from(u);
            }
        }
        if let Some((term, dt, direction)) = g.thermal {
            out.fixed_view_mut::<3, 1>(0, self.slots[term].start)
                .copy_from(&(direction * dt));
        }
    }

    /// The nominal tool point in the machine (axis) frame at joint vector `q` for the target of
    /// `s` (its [`Signals::tool_offset_shift`]) — the point `Signals::machine_point` carries to
    /// the machine terms — without running the model (None for an arm: its nominal tool point
    /// needs forward kinematics; use [`Self::tool_state`]).
    pub fn nominal_machine_point(&self, q: &[f64], s: &Signals) -> Option<Vector3<f64>> {
        // a record without the machine's joints (a reference nest's: q is empty) has no tool point
        match &self.machine.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) if q.len() >= 3 => Some(
                self.machine
                    .nominal_tool_point(&Vector3::new(q[0], q[1], q[2]))
                    + s.tool_offset_shift.unwrap_or_default(),
            ),
            MachineKinematics::FiveAxis(f) if q.len() >= 5 => Some(f.tip_machine(q)),
            _ => None,
        }
    }
}
