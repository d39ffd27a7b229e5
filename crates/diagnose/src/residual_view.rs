//! The residuals of a fit seen from the workpiece: per record, measured − predicted in the
//! records' frame, its whitening, the rotation into the workpiece frame (the fitted instrument
//! pose; identity for records already in the machine frame), and where and when it was taken.
//! Localisation, evidence and the HTML plots read residuals along workpiece axes; the fits
//! read them whitened.

use metrocell_estimation::residuals::whitening;
use metrocell_estimation::{MeasurementRecord, PointResiduals, RecordFrame};
use metrocell_model::{ForwardModel, InstrumentPose};
use metrocell_physics::{PhysicsError, TermId};
use nalgebra::{DVector, Matrix3, Vector3};

use crate::residual::ResidualSample;

/// Per-record residual data.
#[derive(Debug, Clone)]
pub struct ResidualView {
    /// measured − predicted, records frame, m.
    pub residual: Vec<Vector3<f64>>,
    /// L⁻¹ (Σ = L·Lᵀ) of each record's covariance.
    pub whitening: Vec<Matrix3<f64>>,
    /// L of each record's covariance (whitened → metres).
    pub colouring: Vec<Matrix3<f64>>,
    /// Records frame → workpiece frame.
    /// Per record: the rotation of the records' frame into the workpiece frame (each record's
    /// own placement of the instrument, after a levelled instrument's base tilt).
    pub rotations: Vec<Matrix3<f64>>,
    /// Where each record was taken: the commanded axis positions (or the nominal tool point on
    /// machines whose joints are not positions), m.
    pub position: Vec<Vector3<f64>>,
    /// The frame of `position`, in words for a report ("machine axes"; "tracker frame" on a serial
    /// arm, whose records keep the measured point there).
    pub position_frame: String,
    pub time: Vec<f64>,
    /// Unit line of sight from the instrument to the point, records frame (range terms are read
    /// along it).
    pub line_of_sight: Vec<Vector3<f64>>,
}

/// Rotation records frame → workpiece frame at parameters x, for a record read with `signals`
/// (its setup's pose; a levelled instrument's base tilt undone).
pub fn records_rotation(
    model: &ForwardModel,
    x: &[f64],
    frame: &RecordFrame,
    signals: &metrocell_physics::Signals,
) -> Matrix3<f64> {
    match (frame, model.pose_param_start_for(signals)) {
        (RecordFrame::Instrument(_), Some(i)) => {
            let pose = InstrumentPose::from_euler_xyz(
                Vector3::new(x[i], x[i + 1], x[i + 2]),
                [x[i + 3], x[i + 4], x[i + 5]],
            )
            .rotation;
            match model.instrument_param_start(TermId::BaseTilt) {
                Some(t) => {
                    metrocell_physics::instrument::base_tilt::levelling(x[t], x[t + 1])
                        .0
                        .transpose()
                        * pose
                }
                None => pose,
            }
        }
        _ => Matrix3::identity(),
    }
}

/// The frame [`record_position`] gives the records' positions in, in words.
pub fn position_frame(
    model: &ForwardModel,
    records: &[MeasurementRecord],
    frame: &RecordFrame,
) -> String {
    let axes = |r: &MeasurementRecord| r.signals.axis_position.iter().all(Option::is_some);
    if records.iter().all(axes) {
        "machine axes".into()
    } else if records
        .iter()
        .all(|r| axes(r) || model.nominal_machine_point(&r.q, &r.signals).is_some())
    {
        "machine frame".into()
    } else {
        match frame {
            RecordFrame::Instrument(name) => format!("{name} frame"),
            RecordFrame::Machine => "machine frame".into(),
        }
    }
}

/// Where a record was taken: its commanded axis positions if it has all three, else the
/// machine-frame nominal point of its joints, else the measured point.
pub fn record_position(model: &ForwardModel, r: &MeasurementRecord) -> Vector3<f64> {
    if let metrocell_estimation::RecordKind::Reference { nest } = r.kind {
        // a reference nest sits where it is, whatever the machine does
        return nest;
    }
    match r.signals.axis_position {
        [Some(x), Some(y), Some(z)] => Vector3::new(x, y, z),
        _ => model
            .nominal_machine_point(&r.q, &r.signals)
            .unwrap_or(r.measured),
    }
}

impl ResidualView {
    pub fn new(
        model: &ForwardModel,
        x: &[f64],
        records: &[MeasurementRecord],
        frame: &RecordFrame,
    ) -> Result<Self, PhysicsError> {
        let problem =
            PointResiduals::new(model, records).map_err(|b| PhysicsError::InvalidInput {
                what: format!("record {} ({})", b.index, b.point_id),
                reason: "covariance is not positive definite".into(),
            })?;
        let residual = problem.raw_residuals(x)?;
        let mut whitening_v = Vec::with_capacity(records.len());
        let mut colouring = Vec::with_capacity(records.len());
        for r in records {
            let l = r
                .covariance
                .cholesky()
                .map(|c| c.l())
                .unwrap_or_else(Matrix3::identity);
            colouring.push(l);
            whitening_v.push(whitening(&r.covariance).unwrap_or_else(Matrix3::identity));
        }
        let rotations = records
            .iter()
            .map(|r| records_rotation(model, x, frame, &r.signals))
            .collect();
        let predicted = problem.predictions(x)?;
        let line_of_sight = predicted
            .iter()
            .map(|p| {
                if p.norm() > 0.0 {
                    p.normalize()
                } else {
                    Vector3::z()
                }
            })
            .collect();
        Ok(Self {
            residual,
            whitening: whitening_v,
            colouring,
            rotations,
            position: records.iter().map(|r| record_position(model, r)).collect(),
            position_frame: position_frame(model, records, frame),
            time: records.iter().map(|r| r.time).collect(),
            line_of_sight,
        })
    }

    pub fn len(&self) -> usize {
        self.residual.len()
    }

    pub fn is_empty(&self) -> bool {
        self.residual.is_empty()
    }

    /// Whitened residual rows (3 per record).
    pub fn whitened(&self) -> DVector<f64> {
        let mut b = DVector::zeros(3 * self.len());
        for i in 0..self.len() {
            b.fixed_rows_mut::<3>(3 * i)
                .copy_from(&(self.whitening[i] * self.residual[i]));
        }
        b
    }

    /// Residual of record i in the workpiece frame, m.
    pub fn workpiece(&self, i: usize) -> Vector3<f64> {
        self.rotations[i] * self.residual[i]
    }

    /// Whitened rows (3 per record, records frame) back to workpiece-frame metres.
    pub fn to_workpiece_metres(&self, z: &DVector<f64>) -> Vec<Vector3<f64>> {
        (0..self.len())
            .map(|i| self.rotations[i] * (self.colouring[i] * z.fixed_rows::<3>(3 * i)))
            .collect()
    }

    /// Rotation of record i's frame into the workpiece frame.
    pub fn rotation(&self, i: usize) -> &Matrix3<f64> {
        &self.rotations[i]
    }

    /// Stated σ of record i (covariance `covariance`) along each workpiece axis, m.
    pub fn workpiece_sigma(&self, i: usize, covariance: &Matrix3<f64>) -> Vector3<f64> {
        let c = self.rotations[i] * covariance * self.rotations[i].transpose();
        Vector3::new(c[(0, 0)].sqrt(), c[(1, 1)].sqrt(), c[(2, 2)].sqrt())
    }

    /// Residual samples along the workpiece axes for noise tests and localisation, with the
    /// records' conditions (temperatures, air, time since power-on, speed, load). `residual`
    /// gives each record's workpiece-frame residual (m).
    pub fn samples(
        &self,
        records: &[MeasurementRecord],
        residual: &[Vector3<f64>],
    ) -> Vec<ResidualSample> {
        let mut out = Vec::with_capacity(3 * records.len());
        for (i, r) in records.iter().enumerate() {
            let sigma = self.workpiece_sigma(i, &r.covariance);
            let s = &r.signals;
            let mut conditions: Vec<(String, f64)> = s
                .temperatures
                .iter()
                .map(|(n, v)| (format!("temperature.{n}"), *v))
                .collect();
            if let Some(t) = s.air_temperature {
                conditions.push(("air_temperature".into(), t));
            }
            if let Some(t) = s.time_since_power_on {
                conditions.push(("time_since_power_on".into(), t));
            }
            if s.axis_velocity.iter().all(|v| v.is_some()) {
                conditions.push((
                    "speed".into(),
                    s.axis_velocity
                        .iter()
                        .map(|v| v.unwrap_or(0.0).powi(2))
                        .sum::<f64>()
                        .sqrt(),
                ));
            }
            if let Some(f) = s.load_force {
                conditions.push(("load".into(), f.norm()));
            }
            for axis in 0..3 {
                out.push(ResidualSample {
                    channel: r.channel.clone(),
                    axis,
                    time: r.time,
                    position: self.position[i],
                    residual: residual[i][axis],
                    sigma: sigma[axis],
                    approach: s.approach_direction,
                    conditions: conditions.clone(),
                });
            }
        }
        out
    }
}
