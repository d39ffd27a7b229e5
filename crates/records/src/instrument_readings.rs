//! Probe hits and camera detections in a recording → what their records need (the parsing half
//! of [`crate::records_from_bags`] for these channels; the reading, its covariance and what the
//! model needs to predict it).
//!
//! * `/probe/hits` (`metrocell_msgs/ProbeHit`): the record measures `stylus_centre` — the axes'
//!   reading at the trigger plus the stylus offset, before any radius or pretravel compensation —
//!   with the message's covariance (of the compensated point: axis noise plus the radius's and
//!   pretravel's uncertainty along the approach, an upper bound for the raw centre). The
//!   nominal surface point is not in the message: it is taken where the commanded stylus centre
//!   touches, f = nominal tool point(q) + r·u, with q the commanded joints at the trigger (a
//!   probing move commanded to the nominal contact, as the twin's program dwells do); the
//!   approach u and the radius r are the message's. Cartesian and delta machines (crates/model
//!   `probe`).
//! * camera detections (`metrocell_msgs/FiducialDetectionArray`, the fiducial node's
//!   `/fiducials`): every detection with a marker pose gives a record of the pose's translation
//!   (the marker centre in the camera's optical frame, `header.frame_id`) with the translation
//!   block of the pose covariance. The marker's nominal position in the workpiece frame comes
//!   from [`CameraFeatures`]: the twin's fiducial plate in front of the nominal camera at the
//!   commanded joints (what `metrocell sim` renders), or fixed positions of a real cell's markers.
//!   Marker corners (image points) are not made records: a record is three numbers, an image point
//!   two (see the crate README).

use std::collections::BTreeMap;

use metrocell_model::{FiducialPlate, ForwardModel, ProbeTarget, PLATE_MARKERS};
use metrocell_msgs::msg::{FiducialDetectionArray, ProbeHit};
use nalgebra::{Matrix3, Vector3};

use metrocell_estimation::records::RecordKind;

/// Where the markers a camera detects are, nominally (workpiece frame).
#[derive(Debug, Clone, PartialEq)]
pub enum CameraFeatures {
    /// The twin's plate (crates/model `fiducial_plate`) in front of the nominal camera at each
    /// record's commanded joints: marker id k (0–3) is the plate's marker k.
    SimulatedPlate(FiducialPlate),
    /// Fixed marker centres by id, m (a real cell's surveyed plate).
    Fixed(BTreeMap<i32, Vector3<f64>>),
}

impl Default for CameraFeatures {
    fn default() -> Self {
        CameraFeatures::SimulatedPlate(FiducialPlate::default())
    }
}

/// A reading of one of these channels before its commanded joints are known.
#[derive(Debug, Clone, PartialEq)]
pub enum InstrumentReading {
    /// A probe trigger: approach direction (unit) and ball radius.
    ProbeHit {
        approach: Vector3<f64>,
        stylus_radius: f64,
    },
    /// A camera's marker pose: the marker id.
    Marker { id: i32 },
}

/// One measurement of these channels: what it measured and how well, with its reading.
#[derive(Debug, Clone, PartialEq)]
pub struct InstrumentMeasurement {
    pub point_id: String,
    pub channel: String,
    pub measured: Vector3<f64>,
    pub covariance: Matrix3<f64>,
    pub reading: InstrumentReading,
}

/// The measurement of a probe hit, or why it cannot be one.
pub fn probe_measurement(hit: &ProbeHit) -> Result<InstrumentMeasurement, String> {
    let u = Vector3::new(
        hit.approach_direction.x,
        hit.approach_direction.y,
        hit.approach_direction.z,
    );
    let norm = u.norm();
    if !(norm.is_finite() && norm > 1e-9) {
        return Err(format!(
            "approach direction ({}, {}, {}) has no direction",
            u.x, u.y, u.z
        ));
    }
    if !(hit.stylus_radius >= 0.0 && hit.stylus_radius.is_finite()) {
        return Err(format!(
            "stylus radius {} m is not a radius",
            hit.stylus_radius
        ));
    }
    Ok(InstrumentMeasurement {
        point_id: hit.probe_id.clone(),
        channel: if hit.probe_id.is_empty() {
            "probe".into()
        } else {
            hit.probe_id.clone()
        },
        measured: Vector3::new(
            hit.stylus_centre.x,
            hit.stylus_centre.y,
            hit.stylus_centre.z,
        ),
        covariance: Matrix3::from_row_slice(&hit.covariance),
        reading: InstrumentReading::ProbeHit {
            approach: u / norm,
            stylus_radius: hit.stylus_radius,
        },
    })
}

/// The measurements of a detection array's marker poses (detections without a pose give none).
pub fn marker_measurements(array: &FiducialDetectionArray) -> Vec<InstrumentMeasurement> {
    array
        .detections
        .iter()
        .filter(|d| d.has_pose)
        .map(|d| {
            let p = &d.pose.pose.position;
            let c = &d.pose.covariance;
            // row-major 6 × 6 over (x, y, z, rot_x, rot_y, rot_z): the translation block
            let covariance = Matrix3::from_fn(|r, k| c[6 * r + k]);
            InstrumentMeasurement {
                point_id: format!("marker_{}", d.id),
                channel: "camera".into(),
                measured: Vector3::new(p.x, p.y, p.z),
                covariance,
                reading: InstrumentReading::Marker { id: d.id },
            }
        })
        .collect()
}

/// What the model needs to predict `reading` at commanded joints `q`: the record kind.
pub fn record_kind(
    model: &ForwardModel,
    features: &CameraFeatures,
    reading: &InstrumentReading,
    q: &[f64],
) -> Result<RecordKind, String> {
    match reading {
        InstrumentReading::ProbeHit {
            approach,
            stylus_radius,
        } => {
            if q.len() < 3 {
                return Err("a probe hit needs the three linear axes".into());
            }
            let surface = model
                .machine
                .nominal_tool_point(&Vector3::new(q[0], q[1], q[2]))
                + approach * *stylus_radius;
            Ok(RecordKind::ProbeHit {
                target: ProbeTarget {
                    surface,
                    approach: *approach,
                    stylus_radius: *stylus_radius,
                },
                probe: None,
            })
        }
        InstrumentReading::Marker { id } => {
            let feature = match features {
                CameraFeatures::SimulatedPlate(plate) => {
                    let k = usize::try_from(*id).ok().filter(|k| *k < PLATE_MARKERS).ok_or_else(|| format!("marker {id} is not on the simulated plate (ids 0–{})", PLATE_MARKERS - 1))?;
                    let tool = model.nominal_tool(q).map_err(|e| e.to_string())?;
                    let (nominal_camera, _) = model.camera_pose(None, &tool).map_err(|e| e.to_string())?;
                    plate.pose(&nominal_camera).transform_point(&plate.marker_centre(k).into()).coords
                }
                CameraFeatures::Fixed(map) => *map.get(id).ok_or_else(|| format!("marker {id} has no nominal position (CameraFeatures::Fixed knows ids {:?})", map.keys().collect::<Vec<_>>()))?,
            };
            Ok(RecordKind::CameraPoint {
                feature,
                camera: None,
            })
        }
    }
}
