//! Reference nests: points fixed in the frame instrument poses are given in (a nest glued to the
//! floor, or to the table the instrument stands on) that the instrument re-measures through a
//! shift. The machine does not move them, so their readings change only with the instrument's
//! own terms — its pose drifting, its warm-up, the air on the beam — and they tell an
//! instrument that moved from a machine that grew.
//!
//! A nest's position is rarely known to the µm; it is a nuisance, estimated from the nest's own
//! readings: the position that makes the mean of its residuals zero at the model's parameters.
//! What a nest's readings then carry is their change over time, which is what instrument terms
//! fit (a diagnosis also frees each nest's position in its linear stages).

use std::collections::BTreeMap;

use metrocell_model::ForwardModel;
use metrocell_physics::{PhysicsError, TermId};
use nalgebra::{Matrix3, Vector3};

use crate::records::{MeasurementRecord, RecordFrame, RecordKind};
use crate::residuals::PointResiduals;

/// The rotation of the instrument frame into the frame its pose is given in at `x` (identity
/// for records already in the machine frame).
fn pose_at(model: &ForwardModel, x: &[f64], frame: &RecordFrame) -> (Matrix3<f64>, Vector3<f64>) {
    match (frame, model.instrument_param_start(TermId::TrackerPose)) {
        (RecordFrame::Instrument(_), Some(i)) => {
            let pose = metrocell_model::InstrumentPose::from_euler_xyz(
                Vector3::new(x[i], x[i + 1], x[i + 2]),
                [x[i + 3], x[i + 4], x[i + 5]],
            );
            (pose.rotation, pose.translation)
        }
        _ => (Matrix3::identity(), Vector3::zeros()),
    }
}

/// Whether a record is a reference nest's reading.
pub fn is_reference(r: &MeasurementRecord) -> bool {
    matches!(r.kind, RecordKind::Reference { .. })
}

/// Set every reference record's nest (one per `point_id`) to the position that makes the mean of
/// that nest's residuals zero at parameters `x`: first the mean of its readings mapped through
/// the instrument's pose, then refined twice by the mean residual (the instrument's range terms
/// and drift move a reading by µm, so two steps leave nothing of it). A nest whose position was
/// given (finite) is kept unless `all`.
pub fn estimate_nests(
    model: &ForwardModel,
    x: &[f64],
    records: &mut [MeasurementRecord],
    frame: &RecordFrame,
    all: bool,
) -> Result<usize, PhysicsError> {
    let (rotation, translation) = pose_at(model, x, frame);
    let mut readings: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (i, r) in records.iter().enumerate() {
        if let RecordKind::Reference { nest } = &r.kind {
            if all || !nest.iter().all(|v| v.is_finite()) {
                readings.entry(r.point_id.clone()).or_default().push(i);
            }
        }
    }
    for idx in readings.values() {
        let mean = idx
            .iter()
            .map(|&i| rotation * records[i].measured + translation)
            .sum::<Vector3<f64>>()
            / idx.len() as f64;
        for &i in idx {
            records[i].kind = RecordKind::Reference { nest: mean };
        }
    }
    for _ in 0..2 {
        let subset: Vec<usize> = readings.values().flatten().copied().collect();
        if subset.is_empty() {
            break;
        }
        let refs: Vec<MeasurementRecord> = subset.iter().map(|&i| records[i].clone()).collect();
        let problem =
            PointResiduals::new(model, &refs).map_err(|b| PhysicsError::InvalidInput {
                what: format!("reference record `{}`", b.point_id),
                reason: "covariance is not positive definite".into(),
            })?;
        let residuals = problem.raw_residuals(x)?;
        for idx in readings.values() {
            let shift = idx
                .iter()
                .map(|i| {
                    rotation * residuals[subset.iter().position(|s| s == i).expect("in the subset")]
                })
                .sum::<Vector3<f64>>()
                / idx.len() as f64;
            for &i in idx {
                if let RecordKind::Reference { nest } = &mut records[i].kind {
                    *nest += shift;
                }
            }
        }
    }
    Ok(readings.len())
}
