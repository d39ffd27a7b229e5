//! Pure conversions of the twin's samples into ROS messages (see [`crate::topic_map`] for the
//! topics). Field conventions, stated once:
//!
//! * Stamps: `header.stamp = start_time + t` ([`crate::sim_time`]).
//! * Covariances: 3×3 matrices are written **row-major** into `float64[9]`
//!   (`covariance[3·row + col]`), as the `.msg` files say ([`covariance_row_major`]).
//! * Tracker: `frame_id = "tracker"`; `target_id = "point_<i>"` while the machine dwells at
//!   program point i and `""` while it moves; humidity as a fraction 0..1 (the twin's %RH / 100);
//!   `refractive_index` is the group index the tracker applied (station Edlén); a beam-broken
//!   sample has `status = STATUS_BEAM_BREAK` and NaN point, spherical coordinates and
//!   covariance, but keeps its air data.
//! * Temperature: `frame_id` is the sensor's location (structure node name or `ambient`).
//! * Joint states: the names of the cell's joint vector as the twin gives them — `x y z` (m) for
//!   cartesian and delta, `x y z b c` (m, m, m, rad, rad) for five_axis, the arm's joint names
//!   (rad or m) for serial_arm — `effort` empty, `frame_id` empty. The commanded state carries
//!   the program's commanded velocities in `velocity` (m/s or rad/s); the actual state's
//!   `velocity` is empty (the twin does not differentiate the error terms).
//! * Power-on: `sensor_msgs/TimeReference` with `time_ref` = when the tracker was powered on
//!   (it may precede the start of the run), `source = "tracker"`, `frame_id` empty.
//! * Load: `geometry_msgs/WrenchStamped`, `frame_id = "machine"`, force in N, torque zero (the
//!   catalog's load terms read the force only).
//! * Stationing point: `metrocell_msgs/MeasuredPoint`, `frame_id` = `total_station@<setup>` (the
//!   instrument's frame at that placement, as `bag import` writes a `setup` column),
//!   `source = total_station`, `point_id` the waypoint's (`G03.017`), `nominal` the commanded tool
//!   point (the arm's base frame), covariance row-major.
//! * Accelerometer: `sensor_msgs/Imu`, `frame_id` the sensor's URDF link, `linear_acceleration`
//!   the specific force (m/s²) with its variance on the covariance's diagonal; orientation and
//!   angular velocity not measured (their covariances' first element −1, as ROS defines).
//! * Probe: `frame_id = "workpiece"`, `probe_id = "probe"`; the twin records the contact point
//!   as the machine reads it (nominal kinematics, no radius or pretravel compensation), so
//!   `stylus_centre = surface_point =` that point, `stylus_radius = pretravel = 0`, and
//!   `axis_positions` = point − tool offset (the axis reading). Program point and cycle are not
//!   carried by the message.

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::{Point, Vector3 as RosVector3, Wrench, WrenchStamped};
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{
    CameraInfo, Image, Imu, JointState, Temperature, TimeReference,
};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_twin::{
    AccelerationSample, MachineStateSample, ProbeHitSample, StationPointSample, TemperatureSample,
    TrackerSample, TrackerStatus, STATION_FRAME,
};
use nalgebra::{Matrix3, Vector3};

use crate::camera_intrinsics::CameraIntrinsics;

/// `header.frame_id` of tracker measurements.
pub const TRACKER_FRAME: &str = "tracker";
/// `header.frame_id` of probe hits.
pub const WORKPIECE_FRAME: &str = "workpiece";
/// `probe_id` of probe hits.
pub const PROBE_ID: &str = "probe";
/// `source` of the tracker's power-on time.
pub const TRACKER_SOURCE: &str = "tracker";
/// `header.frame_id` of the load.
pub const MACHINE_FRAME: &str = "machine";

/// 3×3 matrix → row-major `float64[9]`.
pub fn covariance_row_major(m: &Matrix3<f64>) -> [f64; 9] {
    let mut out = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            out[3 * r + c] = m[(r, c)];
        }
    }
    out
}

fn point(v: &Vector3<f64>) -> Point {
    Point {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn header(stamp: Time, frame_id: &str) -> Header {
    Header {
        stamp,
        frame_id: frame_id.to_string(),
    }
}

/// `rosgraph_msgs/Clock` at a stamp.
pub fn clock(stamp: Time) -> Clock {
    Clock { clock: stamp }
}

/// `target_id` of a tracker sample: `point_<i>` at a dwell, empty while moving.
pub fn tracker_target_id(target: Option<u32>) -> String {
    target.map(|i| format!("point_{i}")).unwrap_or_default()
}

/// Tracker sample → `TrackerMeasurement`.
pub fn tracker_measurement(s: &TrackerSample, stamp: Time) -> TrackerMeasurement {
    TrackerMeasurement {
        header: header(stamp, TRACKER_FRAME),
        target_id: tracker_target_id(s.target_id),
        point: point(&s.point),
        range: s.range,
        azimuth: s.azimuth,
        elevation: s.elevation,
        covariance: covariance_row_major(&s.covariance),
        air_temperature: s.air_temperature,
        air_pressure: s.air_pressure,
        air_humidity: s.air_humidity / 100.0,
        refractive_index: s.refractive_index,
        status: match s.status {
            TrackerStatus::Ok => TrackerMeasurement::STATUS_OK,
            TrackerStatus::BeamBroken => TrackerMeasurement::STATUS_BEAM_BREAK,
        },
    }
}

/// Thermocouple sample → `Temperature`; `location` becomes `frame_id`.
pub fn temperature(s: &TemperatureSample, stamp: Time, location: &str) -> Temperature {
    Temperature {
        header: header(stamp, location),
        temperature: s.value,
        variance: s.variance,
    }
}

/// Machine state → (actual, commanded) `JointState`s.
pub fn joint_states(s: &MachineStateSample, stamp: Time) -> (JointState, JointState) {
    let make = |position: &[f64], velocity: &[f64]| JointState {
        header: header(stamp.clone(), ""),
        name: s.names.to_vec(),
        position: position.to_vec(),
        velocity: velocity.to_vec(),
        effort: Vec::new(),
    };
    (
        make(&s.actual, &[]),
        make(&s.commanded, &s.commanded_velocity),
    )
}

/// When the tracker was powered on (`powered_on_ns`, ns since the Unix epoch), stamped `stamp`.
pub fn power_on(powered_on_ns: i64, stamp: Time) -> TimeReference {
    TimeReference {
        header: header(stamp, ""),
        time_ref: Time::from_nanos(powered_on_ns),
        source: TRACKER_SOURCE.into(),
    }
}

/// The load force (N, machine frame), stamped `stamp`.
pub fn load(force: &Vector3<f64>, stamp: Time) -> WrenchStamped {
    WrenchStamped {
        header: header(stamp, MACHINE_FRAME),
        wrench: Wrench {
            force: RosVector3 {
                x: force.x,
                y: force.y,
                z: force.z,
            },
            torque: RosVector3::default(),
        },
    }
}

/// A stationing program's point → `MeasuredPoint` (the topic follows its role).
pub fn station_point(s: &StationPointSample, stamp: Time) -> MeasuredPoint {
    MeasuredPoint {
        header: header(
            stamp,
            &format!(
                "{STATION_FRAME}{}{}",
                metrocell_msgs::topics::SETUP_SEPARATOR,
                s.setup
            ),
        ),
        point_id: s.point_id.clone(),
        source: STATION_FRAME.into(),
        nominal: point(&s.nominal),
        measured: point(&s.measured),
        covariance: covariance_row_major(&s.covariance),
    }
}

/// An accelerometer's reading → `Imu` (linear acceleration only).
pub fn imu(s: &AccelerationSample, stamp: Time) -> Imu {
    let f = &s.specific_force;
    let mut m = Imu {
        header: header(stamp, &s.link),
        linear_acceleration: RosVector3 {
            x: f.x,
            y: f.y,
            z: f.z,
        },
        ..Default::default()
    };
    m.linear_acceleration_covariance = covariance_row_major(&(Matrix3::identity() * s.variance));
    m.orientation_covariance[0] = -1.0;
    m.angular_velocity_covariance[0] = -1.0;
    m
}

/// Probe hit → `ProbeHit` (`tool_offset`: tool tip relative to the tool body at q = 0, m).
pub fn probe_hit(s: &ProbeHitSample, stamp: Time, tool_offset: &Vector3<f64>) -> ProbeHit {
    let q = s.recorded - tool_offset;
    ProbeHit {
        header: header(stamp, WORKPIECE_FRAME),
        probe_id: PROBE_ID.into(),
        axis_names: vec!["x".into(), "y".into(), "z".into()],
        axis_positions: q.as_slice().to_vec(),
        stylus_centre: point(&s.recorded),
        approach_direction: RosVector3 {
            x: s.direction.x,
            y: s.direction.y,
            z: s.direction.z,
        },
        stylus_radius: 0.0,
        pretravel: 0.0,
        surface_point: point(&s.recorded),
        covariance: covariance_row_major(&s.covariance),
    }
}

/// `CameraInfo` of the simulated camera: its lens as camera_info (K, R = I, P = [K | 0], the
/// lens's distortion model), no binning, full ROI.
pub fn camera_info(c: &CameraIntrinsics, stamp: Time) -> CameraInfo {
    CameraInfo {
        header: header(stamp, &c.frame_id),
        ..metrocell_camera_model::CameraInfo::from_model(&c.frame_id, &c.lens).to_msg()
    }
}

/// A mono8 `Image` (row-major, step = width, `is_bigendian` 0) in the camera's optical frame.
pub fn mono8_image(image: image::GrayImage, frame_id: &str, stamp: Time) -> Image {
    let (width, height) = image.dimensions();
    Image {
        header: header(stamp, frame_id),
        height,
        width,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: width,
        data: image.into_raw(),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    fn stamp() -> Time {
        Time {
            sec: 1_767_592_800,
            nanosec: 100_000_000,
        }
    }

    #[test]
    fn covariance_is_row_major() {
        let m = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        assert_eq!(
            covariance_row_major(&m),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
        );
    }

    fn tracker_sample(status: TrackerStatus) -> TrackerSample {
        let nan = f64::NAN;
        let ok = status == TrackerStatus::Ok;
        let v = |x: f64| if ok { x } else { nan };
        TrackerSample {
            t: 0.1,
            target_id: Some(4),
            cycle: Some(0),
            point: Vector3::new(v(1.0), v(0.5), v(-0.2)),
            range: v(1.135782),
            azimuth: v(0.4636),
            elevation: v(-0.1771),
            covariance: Matrix3::new(1e-11, 2e-12, 0.0, 2e-12, 3e-11, 4e-13, 0.0, 4e-13, 5e-11)
                .map(v),
            air_temperature: 20.3,
            air_pressure: 101_300.0,
            air_humidity: 45.0,
            refractive_index: 1.000_271_3,
            status,
        }
    }

    #[test]
    fn tracker_fields_units_and_status() {
        let m = tracker_measurement(&tracker_sample(TrackerStatus::Ok), stamp());
        assert_eq!(m.header.frame_id, "tracker");
        assert_eq!(
            (m.header.stamp.sec, m.header.stamp.nanosec),
            (1_767_592_800, 100_000_000)
        );
        assert_eq!(m.target_id, "point_4");
        assert_eq!((m.point.x, m.point.y, m.point.z), (1.0, 0.5, -0.2));
        assert_eq!(m.covariance[1], 2e-12);
        assert_eq!(m.covariance[5], 4e-13);
        assert_eq!(m.air_humidity, 0.45);
        assert_eq!(m.air_pressure, 101_300.0);
        assert_eq!(m.refractive_index, 1.000_271_3);
        assert_eq!(m.status, TrackerMeasurement::STATUS_OK);
    }

    #[test]
    fn beam_break_has_flag_nan_point_and_keeps_air_data() {
        let mut s = tracker_sample(TrackerStatus::BeamBroken);
        s.target_id = None;
        let m = tracker_measurement(&s, stamp());
        assert_eq!(m.status, TrackerMeasurement::STATUS_BEAM_BREAK);
        assert_eq!(m.status, 1);
        assert!(m.point.x.is_nan() && m.point.y.is_nan() && m.point.z.is_nan() && m.range.is_nan());
        assert!(m.covariance.iter().all(|c| c.is_nan()));
        assert_eq!(m.air_temperature, 20.3);
        assert_eq!(m.target_id, "");
    }

    #[test]
    fn temperature_keeps_value_variance_and_location() {
        let s = TemperatureSample {
            t: 1.0,
            sensor: Arc::from("x_left"),
            value: 20.512,
            variance: 0.0029,
        };
        let m = temperature(&s, stamp(), "table");
        assert_eq!((m.temperature, m.variance), (20.512, 0.0029));
        assert_eq!(m.header.frame_id, "table");
    }

    #[test]
    fn joint_states_split_actual_and_commanded() {
        let s = MachineStateSample {
            t: 0.01,
            names: Arc::from(vec!["x".to_string(), "y".into(), "z".into()]),
            commanded: vec![0.1, 0.2, 0.3],
            commanded_velocity: vec![0.05, 0.0, -0.01],
            actual: vec![0.100_008, 0.2, 0.299_999],
        };
        let (actual, commanded) = joint_states(&s, stamp());
        assert_eq!(actual.name, ["x", "y", "z"]);
        assert_eq!(actual.position, [0.100_008, 0.2, 0.299_999]);
        assert_eq!(commanded.position, [0.1, 0.2, 0.3]);
        assert_eq!(commanded.velocity, [0.05, 0.0, -0.01]);
        assert!(
            actual.velocity.is_empty() && actual.effort.is_empty() && commanded.effort.is_empty()
        );
    }

    #[test]
    #[allow(clippy::approx_constant)] // joint readings as a driver rounds them, not π/2
    fn joint_states_keep_any_number_of_named_joints() {
        let names: Vec<String> = (1..=6).map(|i| format!("joint_{i}")).collect();
        let s = MachineStateSample {
            t: 0.05,
            names: Arc::from(names.clone()),
            commanded: vec![0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
            commanded_velocity: vec![0.0; 6],
            actual: vec![0.0, -1.5706, 1.57065, -1.5708, -1.5708, 0.0],
        };
        let (actual, commanded) = joint_states(&s, stamp());
        assert_eq!(actual.name, names);
        assert_eq!(actual.position.len(), 6);
        assert_eq!(actual.position[1], -1.5706);
        assert_eq!(commanded.position[2], 1.5708);
    }

    #[test]
    fn power_on_and_load_carry_their_instants_and_force() {
        // powered on 20 min before a run starting at 2026-01-05T06:00:00Z
        let m = power_on(1_767_592_800_000_000_000 - 1_200_000_000_000, stamp());
        assert_eq!((m.time_ref.sec, m.time_ref.nanosec), (1_767_591_600, 0));
        assert_eq!(
            (m.header.stamp.sec, m.header.stamp.nanosec),
            (1_767_592_800, 100_000_000)
        );
        assert_eq!(m.source, "tracker");
        let w = load(&Vector3::new(0.0, 0.0, -196.2), stamp());
        assert_eq!(
            (w.wrench.force.x, w.wrench.force.z, w.wrench.torque.z),
            (0.0, -196.2, 0.0)
        );
        assert_eq!(w.header.frame_id, "machine");
    }

    #[test]
    fn probe_hit_axis_reading_is_point_minus_tool_offset() {
        let s = ProbeHitSample {
            t: 5.0,
            target_id: 1,
            cycle: 0,
            direction_index: 2,
            direction: Vector3::new(0.0, 1.0, 0.0),
            nominal: Vector3::new(0.2, 0.3, -0.05),
            recorded: Vector3::new(0.200_01, 0.299_98, -0.05),
            covariance: Matrix3::identity() * 2.5e-13,
        };
        let m = probe_hit(&s, stamp(), &Vector3::new(0.0, 0.0, -0.1));
        assert_eq!(m.axis_names, ["x", "y", "z"]);
        assert_eq!(m.axis_positions[0], 0.200_01);
        assert!((m.axis_positions[2] - 0.05).abs() < 1e-15);
        assert_eq!((m.surface_point.x, m.stylus_centre.y), (0.200_01, 0.299_98));
        assert_eq!((m.approach_direction.x, m.approach_direction.y), (0.0, 1.0));
        assert_eq!(
            (m.covariance[0], m.covariance[1], m.covariance[4]),
            (2.5e-13, 0.0, 2.5e-13)
        );
    }

    #[test]
    fn station_points_name_their_setup_and_imu_readings_their_link() {
        let s = StationPointSample {
            t: 3.0,
            point_id: "G02.007".into(),
            role: metrocell_twin::PointRole::Check,
            setup: Arc::from("S2"),
            measured: Vector3::new(-5.1, 0.4, 0.9),
            covariance: Matrix3::identity() * 5.625e-7,
            nominal: Vector3::new(1.0, 0.2, 1.8),
        };
        let m = station_point(&s, stamp());
        assert_eq!(
            (
                m.header.frame_id.as_str(),
                m.point_id.as_str(),
                m.source.as_str()
            ),
            ("total_station@S2", "G02.007", "total_station")
        );
        assert_eq!(
            (
                m.measured.x,
                m.nominal.z,
                m.covariance[0],
                m.covariance[1],
                m.covariance[8]
            ),
            (-5.1, 1.8, 5.625e-7, 0.0, 5.625e-7)
        );
        let a = AccelerationSample {
            t: 3.0,
            sensor: Arc::from("base"),
            link: Arc::from("base_imu"),
            specific_force: Vector3::new(0.01, -0.14, 9.806),
            variance: 2.5e-5,
        };
        let m = imu(&a, stamp());
        assert_eq!(m.header.frame_id, "base_imu");
        assert_eq!(
            (
                m.linear_acceleration.y,
                m.linear_acceleration_covariance[4],
                m.linear_acceleration_covariance[1]
            ),
            (-0.14, 2.5e-5, 0.0)
        );
        assert_eq!(
            (
                m.orientation_covariance[0],
                m.angular_velocity_covariance[0]
            ),
            (-1.0, -1.0)
        );
    }

    #[test]
    fn camera_info_projection_matches_intrinsics() {
        let c = CameraIntrinsics::default();
        let m = camera_info(&c, stamp());
        assert_eq!((m.width, m.height), (2448, 2048));
        assert!((m.k[0] - 3478.26).abs() < 0.01);
        assert_eq!((m.k[2], m.k[5], m.k[8]), (1223.5, 1023.5, 1.0));
        assert_eq!(
            (m.p[0], m.p[2], m.p[5], m.p[6], m.p[10]),
            (m.k[0], 1223.5, m.k[4], 1023.5, 1.0)
        );
        assert_eq!(m.d.len(), 5);
        assert_eq!(m.distortion_model, "plumb_bob");
    }
}
