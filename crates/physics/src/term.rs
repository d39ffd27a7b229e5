//! The [`PhysicsTerm`] trait: one named piece of physics with SI parameters, declared signals,
//! a prediction of the effect it causes and the analytic Jacobian of that prediction with
//! respect to its parameters.
//!
//! Parameter vectors are plain `&[f64]` in the order of [`PhysicsTerm::params`], each value in
//! the canonical unit of its [`ParamSpec`]; this is the layout estimators stack into their
//! state vector.

use nalgebra::{DMatrix, DMatrixViewMut, DVector};

use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term_id::TermId;

/// An inclusive range of parameter values (SI); ±∞ where a side has no limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
}

impl Range {
    pub const UNBOUNDED: Range = Range {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };
    pub const fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }
    pub fn contains(&self, v: f64) -> bool {
        v >= self.lo && v <= self.hi
    }
    pub fn is_bounded(&self) -> bool {
        self.lo.is_finite() || self.hi.is_finite()
    }
}

/// Description of one parameter, with its two ranges:
/// * **usual** — what real machines and instruments show; it shapes the words a finding uses
///   ("a reversal of −9 µm, outside the usual 0 … 100 µm: …") and never decides a choice;
/// * **possible** — outside it a value is physically impossible (a negative time constant,
///   |α| above 100 µm/m/K): config validation refuses such values, fits bound parameters by
///   it, and diagnose refuses a candidate that needs one. Sign-free quantities (reversal,
///   squareness, scales, offsets) have no possible bound: their possible range is ±∞.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    pub name: String,
    /// Canonical unit string, parseable by [`crate::units::parse_unit`] (e.g. `m`, `rad`, `1/K`, `s`).
    pub unit: &'static str,
    pub usual: Range,
    pub possible: Range,
    pub default: f64,
    pub doc: String,
    /// What a value outside the usual range most likely means in practice (e.g. a negative
    /// reversal: the controller's backlash compensation set too high); "" when nothing
    /// particular.
    pub unusual_means: &'static str,
}

impl ParamSpec {
    /// A parameter whose usual range is `[usual_min, usual_max]` and whose possible range is
    /// unbounded (set it with [`Self::possible`]).
    pub fn new(
        name: impl Into<String>,
        unit: &'static str,
        usual_min: f64,
        usual_max: f64,
        default: f64,
        doc: impl Into<String>,
    ) -> Self {
        Self {
            name: name.into(),
            unit,
            usual: Range::new(usual_min, usual_max),
            possible: Range::UNBOUNDED,
            default,
            doc: doc.into(),
            unusual_means: "",
        }
    }
    /// The physically possible range (values outside are impossible).
    pub fn possible(mut self, lo: f64, hi: f64) -> Self {
        self.possible = Range::new(lo, hi);
        self
    }
    /// What a value outside the usual range most likely means in practice.
    pub fn unusual_means(mut self, text: &'static str) -> Self {
        self.unusual_means = text;
        self
    }
    /// A representative size of the parameter (the usual range's width): for step sizes and
    /// scaling, never a limit.
    pub fn typical_scale(&self) -> f64 {
        let w = self.usual.hi - self.usual.lo;
        if w.is_finite() && w > 0.0 {
            w
        } else {
            self.usual
                .hi
                .abs()
                .max(self.usual.lo.abs())
                .max(f64::MIN_POSITIVE)
        }
    }
}

/// Frame a displacement is expressed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// Machine (axis) frame; the displacement is of the tool point relative to the workpiece:
    /// realised relative position minus commanded relative position.
    Machine,
    /// Workpiece frame (feature displacement on the part or artefact).
    Workpiece,
    /// Probe frame (stylus): displacement of the recorded contact point.
    Probe,
    /// Camera frame (x right, y down, z along the optical axis).
    Camera,
    /// Laser-tracker frame.
    Tracker,
    /// Tool frame: a vector fixed to the tool (or probe, or reflector) as mounted, which turns
    /// with the tool. Where the tool does not turn (3-axis machines, a five-axis spindle) it is
    /// parallel to the machine frame; on an arm the caller turns it by the tool's rotation.
    Tool,
}

/// What a term's prediction is, and therefore its dimension and unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EffectKind {
    /// 3-vector displacement in metres, in the stated frame.
    Displacement(Frame),
    /// Change of a measured range, m (measured − true).
    RangeChange,
    /// Standard deviation of range readings, m (scatter; flagged, never fitted as a bias).
    RangeScatter,
    /// 2-vector shift in normalised image coordinates (distorted − ideal); multiply by the focal
    /// length in pixels to get pixels.
    ImageShift,
    /// 3-vector: the input point expressed in another frame, m.
    PointInFrame(Frame),
    /// The term changes parameters of a kinematic chain; crates/kinematics evaluates it.
    Kinematic,
    /// 6-vector change of an instrument's pose: translation (m) and pose-angle increments (rad),
    /// added to the instrument's `tracker_pose` by the forward model.
    PoseChange,
}

impl EffectKind {
    /// Number of components of the prediction.
    pub fn dimension(&self) -> usize {
        match self {
            EffectKind::Displacement(_) | EffectKind::PointInFrame(_) => 3,
            EffectKind::RangeChange | EffectKind::RangeScatter => 1,
            EffectKind::ImageShift => 2,
            EffectKind::Kinematic => 0,
            EffectKind::PoseChange => 6,
        }
    }
}

/// A term's prediction: its kind and value (length = `kind.dimension()`).
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    pub kind: EffectKind,
    pub value: DVector<f64>,
}

/// Cloning a boxed term, so a configured model can be copied (an estimator's declared model
/// plus a `diagnose` candidate, a model per thread).
pub trait TermClone {
    fn clone_box(&self) -> Box<dyn PhysicsTerm>;
}

impl<T: PhysicsTerm + Clone + 'static> TermClone for T {
    fn clone_box(&self) -> Box<dyn PhysicsTerm> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn PhysicsTerm> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// One named piece of physics (see the crate docs for the catalog).
pub trait PhysicsTerm: TermClone + std::fmt::Debug + Send + Sync {
    /// Stable catalog id (DESIGN.md vocabulary).
    fn id(&self) -> TermId;
    /// Instance label, e.g. `angular[x:z]`; unique within one model.
    fn label(&self) -> String;
    /// The instrument instance an instrument term belongs to (option `instrument`), `None`
    /// for the cell's only instrument of its kind and for every machine term.
    fn instrument(&self) -> Option<&str> {
        None
    }
    /// The placement of its instrument a pose term is of (`tracker_pose` option `setup`: a
    /// recording's `setup` column), `None` for a pose that holds for every reading and for
    /// every other term.
    fn setup(&self) -> Option<&str> {
        None
    }
    /// What the prediction is.
    fn effect(&self) -> EffectKind;
    /// Parameter descriptors, in the order of the parameter vector.
    fn params(&self) -> Vec<ParamSpec>;
    /// Signals the prediction reads.
    fn signals(&self) -> Vec<SignalKind>;
    /// Effect of the term for parameter vector `p` at the instant described by `s`.
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError>;
    /// ∂prediction/∂p, analytic; rows = effect dimension, columns = parameters.
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError>;

    /// Prediction and Jacobian together into caller buffers: `value[..dimension]` and `jac`
    /// (dimension × parameters). The default goes through [`Self::predict`] and
    /// [`Self::jacobian`] (allocating); the terms on an estimator's hot path (the XFYZ geometry,
    /// the tracker's terms) override it without allocating, with the same arithmetic as
    /// `predict`.
    fn evaluate_into(
        &self,
        p: &[f64],
        s: &Signals,
        value: &mut [f64],
        mut jac: DMatrixViewMut<'_, f64>,
    ) -> Result<(), PhysicsError> {
        let v = self.predict(p, s)?.value;
        value[..v.len()].copy_from_slice(v.as_slice());
        jac.copy_from(&self.jacobian(p, s)?);
        Ok(())
    }

    /// Whether the prediction is linear in the parameters with a Jacobian that reads only the
    /// signals: prediction = [`Self::jacobian`]·p for every p, the Jacobian the same for every p
    /// at one instant (the geometric error series; not a time constant, a phase or a
    /// kinematic trim). A caller that evaluates the same instants at many parameter vectors (a
    /// batch fit) may then keep each instant's Jacobian and predict by a product. Only a term
    /// that states it is taken to be linear: the default is false.
    fn linear_in_params(&self) -> bool {
        false
    }

    /// Default parameter vector.
    fn defaults(&self) -> Vec<f64> {
        self.params().iter().map(|p| p.default).collect()
    }
}

/// Check the parameter count (used by every term at the top of predict/jacobian); the term's
/// label is formatted only on error.
pub(crate) fn check_len(
    term: &(impl crate::signals::TermLabel + ?Sized),
    p: &[f64],
    expected: usize,
) -> Result<(), PhysicsError> {
    if p.len() != expected {
        return Err(PhysicsError::ParameterCount {
            term: term.term_label(),
            expected,
            got: p.len(),
        });
    }
    Ok(())
}

/// Shorthand: a displacement prediction.
pub(crate) fn displacement(frame: Frame, v: nalgebra::Vector3<f64>) -> Prediction {
    Prediction {
        kind: EffectKind::Displacement(frame),
        value: DVector::from_column_slice(v.as_slice()),
    }
}
