//! The messages the node publishes, built from the library's results.

use metrocell_laser_tracker::dwell::DwellAverage;
use metrocell_laser_tracker::registration::Registration;
use metrocell_laser_tracker::total_station_gsi::InstrumentPoint;
use metrocell_laser_tracker::warmup::WarmupFit;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::{
    Point, Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, Transform,
    TransformStamped, Vector3 as RosVector3,
};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

fn header(stamp_ns: i64, frame: &str) -> Header {
    Header {
        stamp: Time::from_nanos(stamp_ns),
        frame_id: frame.to_string(),
    }
}

fn point(v: &Vector3<f64>) -> Point {
    Point {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// Row-major, as the messages' covariance fields are (nalgebra stores column-major).
fn row_major(m: &Matrix3<f64>) -> [f64; 9] {
    let mut a = [0.0; 9];
    a.copy_from_slice(m.transpose().as_slice());
    a
}

/// The averaged reading of a dwell, stamped at its mid time, with the status bits of what the
/// node found (turbulence, warming up).
pub fn dwell_measurement(
    d: &DwellAverage,
    covariance: &Matrix3<f64>,
    frame: &str,
    turbulence: bool,
    warming_up: bool,
) -> TrackerMeasurement {
    let mut status = TrackerMeasurement::STATUS_OK;
    if turbulence {
        status |= TrackerMeasurement::STATUS_TURBULENCE;
    }
    if warming_up {
        status |= TrackerMeasurement::STATUS_WARMING_UP;
    }
    TrackerMeasurement {
        header: header(d.mid_ns(), frame),
        target_id: d.target.clone(),
        point: point(&d.point),
        range: d.range,
        azimuth: d.azimuth,
        elevation: d.elevation,
        covariance: row_major(covariance),
        air_temperature: d.air.temperature,
        air_pressure: d.air.pressure,
        air_humidity: d.air.humidity,
        refractive_index: d.refractive_index,
        status,
    }
}

/// One total-station observation as a `tracker/measurements` reading: the point in the levelled
/// instrument frame (x toward Hz = 0, y toward Hz = 300 gon, z up), `range` = slope distance,
/// `azimuth` = −Hz and `elevation` = 100 gon − V (face I), the covariance of the angle and
/// distance noise, `target_id` = the GSI point id. The slope distance is the instrument's, its
/// own ppm applied: `refractive_index` 0 and the air NaN (the block carries no air).
pub fn total_station_measurement(
    point_id: &str,
    stamp_ns: i64,
    p: &InstrumentPoint,
    frame: &str,
) -> TrackerMeasurement {
    TrackerMeasurement {
        header: header(stamp_ns, frame),
        target_id: point_id.to_string(),
        point: point(&p.point),
        range: p.range,
        azimuth: p.azimuth,
        elevation: p.elevation,
        covariance: row_major(&p.covariance),
        air_temperature: f64::NAN,
        air_pressure: f64::NAN,
        air_humidity: f64::NAN,
        refractive_index: 0.0,
        status: TrackerMeasurement::STATUS_OK,
    }
}

/// A dwell's point in the machine frame, next to its nominal; the covariance includes the
/// tracker pose's.
pub fn measured_point(
    pose: &Registration,
    target: &str,
    stamp_ns: i64,
    p: &Vector3<f64>,
    cov: &Matrix3<f64>,
    nominal: &Vector3<f64>,
    frame: &str,
) -> MeasuredPoint {
    let (q, q_cov) = pose.to_machine(p, cov);
    MeasuredPoint {
        header: header(stamp_ns, frame),
        point_id: target.to_string(),
        source: MeasuredPoint::SOURCE_TRACKER.to_string(),
        nominal: point(nominal),
        measured: point(&q),
        covariance: row_major(&q_cov),
    }
}

/// The tracker pose as a static transform machine → tracker.
pub fn tf_static(
    pose: &Registration,
    stamp_ns: i64,
    machine_frame: &str,
    tracker_frame: &str,
) -> TFMessage {
    let q = UnitQuaternion::from_rotation_matrix(&pose.rotation);
    TFMessage {
        transforms: vec![TransformStamped {
            header: header(stamp_ns, machine_frame),
            child_frame_id: tracker_frame.to_string(),
            transform: Transform {
                translation: RosVector3 {
                    x: pose.translation.x,
                    y: pose.translation.y,
                    z: pose.translation.z,
                },
                rotation: Quaternion {
                    x: q.i,
                    y: q.j,
                    z: q.k,
                    w: q.w,
                },
            },
        }],
    }
}

/// The tracker pose with its covariance (translation first, as `Registration` and geometry_msgs order it).
pub fn pose_with_covariance(
    pose: &Registration,
    stamp_ns: i64,
    machine_frame: &str,
) -> PoseWithCovarianceStamped {
    let q = UnitQuaternion::from_rotation_matrix(&pose.rotation);
    let c = pose.covariance;
    let mut covariance = [0.0; 36];
    for i in 0..6 {
        for j in 0..6 {
            covariance[6 * i + j] = c[(i, j)];
        }
    }
    PoseWithCovarianceStamped {
        header: header(stamp_ns, machine_frame),
        pose: PoseWithCovariance {
            pose: Pose {
                position: point(&pose.translation),
                orientation: Quaternion {
                    x: q.i,
                    y: q.j,
                    z: q.k,
                    w: q.w,
                },
            },
            covariance,
        },
    }
}

/// The warm-up fit as an ErrorModel of the `tracker_warmup` term (offset A, amplitude B in m,
/// time constant τ in s; covariance in that order).
pub fn warmup_model(f: &WarmupFit, stamp_ns: i64, nest: &str) -> ErrorModel {
    let mut covariance = Vec::with_capacity(9);
    for i in 0..3 {
        for j in 0..3 {
            covariance.push(f.covariance[(i, j)]);
        }
    }
    ErrorModel {
        header: header(stamp_ns, nest),
        machine_id: String::new(),
        term_ids: vec!["tracker_warmup".into(); 3],
        parameter_names: vec![
            "tracker_warmup.offset".into(),
            "tracker_warmup.amplitude".into(),
            "tracker_warmup.time_constant".into(),
        ],
        units: vec!["m".into(), "m".into(), "s".into()],
        values: vec![f.a, f.b, f.tau],
        covariance,
        residual_rms: f.rms,
        observation_count: f.samples as u32,
        degrees_of_freedom: f.samples.saturating_sub(3) as u32,
        // the catalog's tracker_warmup term has no options
        term_labels: vec!["tracker_warmup".into()],
        term_catalog_ids: vec!["tracker_warmup".into()],
        term_options: vec!["{}".into()],
    }
}
