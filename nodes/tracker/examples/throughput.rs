//! Throughput of the tracker node's processing on one core, against a loop that only decodes
//! the same CDR messages (same run, same machine).
//!
//! 200 000 readings (TrackerMeasurement, dwells of 50 readings on 10 targets) interleaved with
//! commanded joint states at a tenth of the rate, CDR-encoded as on the wire. Loop 1 decodes
//! them; loop 2 decodes them and runs the node's logic (refraction re-correction, covariance,
//! dwell averaging, turbulence test, time alignment, registration, machine-frame points).
//!
//! Run: `cargo run --release -p metrocell-tracker-node --example throughput`

use std::time::Instant;

use metrocell_bagtools::{encode_cdr, SourcedMessage};
use metrocell_compensation::to_spherical;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_tracker_node::parameters::TrackerConfig;
use metrocell_tracker_node::tracker_state::{Output, TrackerState};
use nalgebra::Vector3;

const READINGS: usize = 200_000;
const PER_DWELL: usize = 50;
const T0: i64 = 1_700_000_000_000_000_000;
const PERIOD_NS: i64 = 1_000_000; // 1 kHz

fn config() -> TrackerConfig {
    TrackerConfig {
        registration_points: 10,
        ..TrackerConfig::defaults()
    }
}

fn message(topic: &str, payload: Vec<u8>, t: i64) -> SourcedMessage {
    SourcedMessage {
        topic: topic.into(),
        log_time_ns: t as u64,
        publish_time_ns: t as u64,
        payload,
    }
}

fn main() {
    let mut messages = Vec::new();
    for k in 0..READINGS {
        let t = T0 + k as i64 * PERIOD_NS;
        let target = (k / PER_DWELL) % 10;
        let q = Vector3::new(
            0.1 * target as f64,
            0.05 * (target % 3) as f64,
            0.02 * (target % 4) as f64,
        );
        if k % 10 == 0 {
            let j = JointState {
                header: Header {
                    stamp: Time::from_nanos(t),
                    frame_id: String::new(),
                },
                name: vec!["x".into(), "y".into(), "z".into()],
                position: vec![q.x, q.y, q.z],
                velocity: vec![],
                effort: vec![],
            };
            messages.push(message("c", encode_cdr(&j).unwrap(), t));
        }
        // tracker 2 m away along x, a few µm of deterministic scatter
        let p = q
            + Vector3::new(2.0, 0.0, 0.0)
            + Vector3::repeat(3e-6 * ((k * 7919) % 13) as f64 / 13.0);
        let (range, azimuth, elevation) = to_spherical(&p);
        let m = TrackerMeasurement {
            header: Header {
                stamp: Time::from_nanos(t),
                frame_id: "tracker".into(),
            },
            target_id: format!("point_{target}"),
            point: Point {
                x: p.x,
                y: p.y,
                z: p.z,
            },
            range,
            azimuth,
            elevation,
            covariance: [0.0; 9],
            air_temperature: 20.3,
            air_pressure: 101_300.0,
            air_humidity: 0.45,
            refractive_index: 1.00027,
            status: 0,
        };
        messages.push(message("m", encode_cdr(&m).unwrap(), t));
    }

    // loop 1: decode only
    let start = Instant::now();
    let mut checksum = 0.0;
    for m in &messages {
        if m.topic == "m" {
            checksum += m.decode::<TrackerMeasurement>().unwrap().range;
        } else {
            checksum += m.decode::<JointState>().unwrap().position[0];
        }
    }
    let decode_s = start.elapsed().as_secs_f64();

    // loop 2: decode and process
    let mut state = TrackerState::new(config());
    let start = Instant::now();
    let mut points = 0usize;
    for m in &messages {
        let out = if m.topic == "m" {
            state.measurement(&m.decode::<TrackerMeasurement>().unwrap())
        } else {
            state.commanded(&m.decode::<JointState>().unwrap())
        };
        points += out.iter().filter(|o| matches!(o, Output::Point(_))).count();
    }
    points += state
        .finish()
        .iter()
        .filter(|o| matches!(o, Output::Point(_)))
        .count();
    let process_s = start.elapsed().as_secs_f64();

    let rate = |s: f64| READINGS as f64 / s;
    println!("{READINGS} readings + {} commanded states, {points} measured points (checksum {checksum:.3})", messages.len() - READINGS);
    println!(
        "decode only:          {:>10.0} readings/s ({decode_s:.3} s)",
        rate(decode_s)
    );
    println!(
        "decode + processing:  {:>10.0} readings/s ({process_s:.3} s)",
        rate(process_s)
    );
    println!("processing/decode time ratio: {:.2}", process_s / decode_s);
    println!("headroom over 1 kHz: {:.0}×", rate(process_s) / 1000.0);
    assert_eq!(points, READINGS / PER_DWELL, "every dwell gives one point");
}
