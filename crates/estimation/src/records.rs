//! Measurement records: what one measured point says, with everything the model needs to
//! predict it. Built from recordings by [`crate::records_from_bags`] (bags recorded by the nodes,
//! simulated by `metrocell sim`, or imported with `bag import`), or directly by tests.
//!
//! Frame convention (stated once): a [`RecordKind::Point`]'s `measured` is in the frame of the
//! [`RecordSet`]. When that is the instrument's own frame (a tracker frame), the instrument pose
//! is a nuisance parameter of the fit (`tracker_pose.*`, the workpiece → instrument transform of
//! crates/kinematics `instrument_pose`). When the points are already in the machine (workpiece) frame,
//! the pose is the identity and fixed. The other kinds are in the frame their reading is in,
//! whatever the set's frame: a probe hit's stylus-centre reading in the workpiece (machine) frame,
//! a camera point in its camera's optical frame.
//!
//! Every kind is three numbers with a 3 × 3 covariance, so a record is three whitened residual
//! rows whatever it measured.

use metrocell_model::ProbeTarget;
use metrocell_physics::Signals;
use nalgebra::{Matrix3, Vector3};

/// What a record measured, and what the model needs beyond its signals to predict it.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordKind {
    /// A measured point of the tool (a tracker reading, or a point already in the machine frame):
    /// predicted by the model's tracker reading of the sighted tool point.
    Point,
    /// A touch-probe trigger: `measured` is the stylus-centre reading (axes + stylus offset, no
    /// radius or pretravel compensation), predicted by the model's probe reading of `target`
    /// (crates/model `probe`) with the probe `probe` (None: the model's only probe).
    ProbeHit {
        target: ProbeTarget,
        probe: Option<String>,
    },
    /// A camera's metric reading of a part feature (a marker pose's translation): `measured` in
    /// the camera's optical frame, predicted by the model's camera point of the feature whose
    /// nominal position (workpiece frame) is `feature`, seen by camera `camera` (None: the only one).
    CameraPoint {
        feature: Vector3<f64>,
        camera: Option<String>,
    },
    /// A reference nest the tracker re-measures: a point fixed in the frame instrument poses are
    /// given in (on the floor, or on the table the instrument stands on), which the machine does
    /// not move — only the instrument's own terms act on its reading (its pose, drift, warm-up,
    /// refraction). `nest` is its position there, NaN until known (a diagnosis estimates it from
    /// its readings). Predicted by the tracker's reading of `nest`.
    Reference { nest: Vector3<f64> },
}

/// One measurement (a point, a probe hit, a camera point: [`RecordKind`]).
#[derive(Debug, Clone)]
pub struct MeasurementRecord {
    /// Time of the measurement, s (the bag's clock: seconds since the Unix epoch for recordings).
    pub time: f64,
    pub point_id: String,
    /// The instrument or stream it came from (`tracker`, an import's `source`, …).
    pub channel: String,
    /// Commanded joint vector of the machine family at `time` (cartesian and delta: x, y, z in m;
    /// five-axis: x y z b c; arm: its joints).
    pub q: Vec<f64>,
    /// Measured point, m: in the record set's frame for [`RecordKind::Point`], else in the frame
    /// of its kind (module doc).
    pub measured: Vector3<f64>,
    /// Its covariance, m², same frame. Positive definite.
    pub covariance: Matrix3<f64>,
    /// Signals at `time`: axis positions, velocities and approach directions, temperatures and
    /// their histories, station air, time since the instrument was powered on, load.
    /// The points of each frame, `tracker_range` and the probe's direction are set by the
    /// model when it predicts.
    pub signals: Signals,
    /// What was measured.
    pub kind: RecordKind,
}

/// The frame the records' points are in.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordFrame {
    /// The machine's (workpiece) frame: instrument pose = identity, fixed.
    Machine,
    /// An instrument frame (`header.frame_id`): the pose is estimated with the model. A frame id
    /// `<frame>@<setup>` (bag import's `setup` column) is this frame, read from the placement
    /// `<setup>` of the instrument: the record's `signals.setup`, a pose of its own.
    Instrument(String),
}

/// A measurement dropped while building records, and why (shown to the user, never silent).
#[derive(Debug, Clone, PartialEq)]
pub struct Rejected {
    /// Where it was: topic and index, or file and line.
    pub at: String,
    pub point_id: String,
    pub reason: String,
}

/// Records of one recording (or several concatenated), in one frame.
#[derive(Debug, Clone)]
pub struct RecordSet {
    /// The frame of the [`RecordKind::Point`] records.
    pub frame: RecordFrame,
    pub records: Vec<MeasurementRecord>,
    /// Points whose `role` is `check` (bag import: `/check_points`): kept out of every fit, to
    /// judge the model's predictions; same frame, same signals as [`Self::records`].
    pub check: Vec<MeasurementRecord>,
    /// Measurements dropped, with where and why; entries with an empty `point_id` are signal
    /// samples a topic gave that could not be used (one entry per topic, with the count).
    pub rejected: Vec<Rejected>,
    /// Topics (or columns) each signal came from, for reports and error messages.
    pub sources: Vec<(String, String)>,
}

impl RecordSet {
    /// Commanded tool points are not stored: the model computes them from `q`.
    pub fn len(&self) -> usize {
        self.records.len()
    }
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }
}
