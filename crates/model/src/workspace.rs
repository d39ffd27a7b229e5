//! Scratch Jacobians of the model's `*_jacobian` methods, allocated once per model so that an
//! estimator's inner loop does not allocate, and what the readings of one parameter vector
//! share (the tracker pose's rotation), so that it is computed once, not per reading.

use metrocell_physics::instrument::tracker_pose::PoseRotation;
use metrocell_physics::PhysicsError;
use nalgebra::DMatrix;

use crate::forward::ForwardModel;

/// Most parameters of one instrument term (`tracker_pose`: 6).
const TERM_COLUMNS: usize = 6;

/// Scratch Jacobians for one [`ForwardModel`] ([`Workspace::new`] of that model).
#[derive(Debug, Clone)]
pub struct Workspace {
    /// ∂(tool point)/∂p, 3 × parameters.
    pub(crate) tool: DMatrix<f64>,
    /// ∂(tool rotation)/∂p as angular-velocity columns, 3 × parameters.
    pub(crate) ang: DMatrix<f64>,
    /// ∂(a point in an instrument frame)/∂p, 3 × parameters.
    pub(crate) point: DMatrix<f64>,
    /// ∂d_w(feature)/∂p, 3 × parameters.
    pub(crate) feature: DMatrix<f64>,
    /// ∂x/∂(tracker pose), 3 × 6.
    pub(crate) pose: DMatrix<f64>,
    /// ∂(pose change)/∂(drift parameters), 6 × parameters, and ∂x/∂(drift parameters) = ∂x/∂pose
    /// times it, 3 × parameters (`instrument_drift`).
    pub(crate) drift_pose: DMatrix<f64>,
    pub(crate) drift: DMatrix<f64>,
    /// ∂Δρ/∂(own parameters): row 0 warm-up, row 1 refraction.
    pub(crate) range_terms: DMatrix<f64>,
    /// ∂(an instrument term)/∂(its parameters), up to 3 × 6.
    pub(crate) term: DMatrix<f64>,
    /// The tracker pose's rotation at the last pose evaluated: the readings of one parameter
    /// vector share it (see [`Self::pose_rotation`]).
    pose_rotation: Option<PoseRotation>,
    /// All parameters zero (a linear target's P₀ is the target there).
    pub(crate) zero_params: Vec<f64>,
}

impl Workspace {
    pub fn new(model: &ForwardModel) -> Self {
        let n = model.param_count();
        Self {
            tool: DMatrix::zeros(3, n),
            ang: DMatrix::zeros(3, n),
            point: DMatrix::zeros(3, n),
            feature: DMatrix::zeros(3, n),
            pose: DMatrix::zeros(3, 6),
            drift_pose: DMatrix::zeros(6, n),
            drift: DMatrix::zeros(3, n),
            range_terms: DMatrix::zeros(2, 3),
            term: DMatrix::zeros(3, TERM_COLUMNS),
            pose_rotation: None,
            zero_params: vec![0.0; n],
        }
    }

    /// The tracker pose's rotation at Euler angles `angles`: the one of the last call when the
    /// angles are the same bit for bit, else computed anew.
    pub(crate) fn pose_rotation(&mut self, angles: [f64; 3]) -> PoseRotation {
        let same = |r: &PoseRotation| {
            r.angles()
                .iter()
                .zip(&angles)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        };
        match self.pose_rotation {
            Some(r) if same(&r) => r,
            _ => *self
                .pose_rotation
                .insert(PoseRotation::new(angles[0], angles[1], angles[2])),
        }
    }

    /// Error unless this workspace was made for `model`.
    pub(crate) fn check(&self, model: &ForwardModel) -> Result<(), PhysicsError> {
        if self.tool.ncols() != model.param_count() {
            return Err(PhysicsError::InvalidInput {
                what: "forward model, workspace".into(),
                reason: format!(
                    "made for {} parameters, the model has {}: use Workspace::new of this model",
                    self.tool.ncols(),
                    model.param_count()
                ),
            });
        }
        Ok(())
    }
}
