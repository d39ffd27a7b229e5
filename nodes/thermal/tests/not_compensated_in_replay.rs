//! Issue 15's untested behaviour, end to end through `metrocell-thermal --bag`: a rejected
//! reading (NaN, out of range) is counted and not used, a sensor that falls silent makes points
//! `points_not_compensated` (stale_sensor), a non-finite point is counted (not_finite), and the
//! replay reports the counts.
//!
//! The bag: x_left and x_right at 10 Hz for 1 s, then x_left alone for 2 s. x_left sends NaN at
//! 0.5 s and 200 °C at 0.6 s. Points at 0.55 s and 1.5 s (x_right 0.6 s old: fresh with
//! stale_after 1 s), at 1.6 s a point with a NaN coordinate, and 2.5 s (x_right 1.6 s old: stale).

use std::path::Path;
use std::process::Command;

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_msgs::std_msgs::msg::Header;
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const MS: u64 = 1_000_000;

fn header(t: u64) -> Header {
    Header {
        stamp: Time::from_nanos(t as i64),
        frame_id: "machine".into(),
    }
}

fn write_bag(dir: &Path) {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    for t in ["/nc/temperature/x_left", "/nc/temperature/x_right"] {
        w.add_topic(t, Temperature::ROS_TYPE, Temperature::DEFINITION, &qos)
            .unwrap();
    }
    w.add_topic(
        "/nc/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    let mut events: Vec<(u64, &str, Vec<u8>)> = Vec::new();
    for k in 0..30u64 {
        let t = T0 + k * 100 * MS;
        let left = match k {
            5 => f64::NAN,
            6 => 200.0,
            _ => 22.0,
        };
        events.push((
            t,
            "/nc/temperature/x_left",
            encode_cdr(&Temperature {
                header: header(t),
                temperature: left,
                variance: 0.0004,
            })
            .unwrap(),
        ));
        if k < 10 {
            events.push((
                t,
                "/nc/temperature/x_right",
                encode_cdr(&Temperature {
                    header: header(t),
                    temperature: 21.0,
                    variance: 0.0004,
                })
                .unwrap(),
            ));
        }
    }
    for (j, ms) in [550u64, 1500, 2500, 1600].into_iter().enumerate() {
        let t = T0 + ms * MS;
        let mut p = MeasuredPoint {
            header: header(t),
            point_id: format!("p{j}"),
            source: "tracker".into(),
            nominal: Point {
                x: 0.4,
                y: 0.1,
                z: 0.2,
            },
            measured: Point {
                x: 0.4,
                y: 0.1,
                z: 0.2,
            },
            covariance: [1e-12, 0.0, 0.0, 0.0, 1e-12, 0.0, 0.0, 0.0, 1e-12],
        };
        if j == 3 {
            p.measured.y = f64::NAN;
        }
        events.push((t, "/nc/measured_points", encode_cdr(&p).unwrap()));
    }
    events.sort_by_key(|e| e.0);
    for (t, topic, cdr) in events {
        w.write(topic, t, t, &cdr).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn stale_and_rejected_inputs_are_counted_and_reported() {
    let tmp = std::env::temp_dir().join(format!(
        "metrocell-thermal-not-compensated-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let (input, output) = (tmp.join("input"), tmp.join("output"));
    write_bag(&input);
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-thermal"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args([
            "--ros-args",
            "-r",
            "__ns:=/nc",
            "-p",
            "sensors:=[x_left, x_right]",
            "-p",
            "sensor_axes:=[x, x]",
            "-p",
            "sensor_positions:=[0.0, 0.8]",
            "-p",
            "stale_after:=1.0",
        ])
        .output()
        .unwrap();
    let log =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{log}");
    assert!(
        log.contains(
            "2 points compensated, 2 not (not_finite: 1, stale_sensor: 1), 2 readings rejected"
        ),
        "{log}"
    );
    assert!(
        log.contains("temperature/x_left: rejected reading NaN"),
        "{log}"
    );
    assert!(
        log.contains("rejected reading 200 °C") && log.contains("outside temperature_limits"),
        "{log}"
    );
    assert!(log.contains("sensor 'x_right' is stale"), "{log}");
    assert!(
        log.contains("strain computed from the configured alpha"),
        "{log}"
    );

    let mut source = BagSource::open(&output).unwrap();
    source
        .subscribe::<MeasuredPoint>("/nc/measured_points/thermal_compensated")
        .unwrap();
    let mut ids = Vec::new();
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic.ends_with("thermal_compensated") {
            let p: MeasuredPoint = m.decode().unwrap();
            // x at 0.4 m, T(0.4) = (22 + 21)/2: the rejected 200 °C was never used
            assert!(
                (p.measured.x - (0.4 - 11.5e-6 * 0.4 * 1.5)).abs() < 1e-15,
                "{}: x = {}",
                p.point_id,
                p.measured.x
            );
            ids.push(p.point_id);
        }
    }
    assert_eq!(ids, ["p0", "p1"]);
    let _ = std::fs::remove_dir_all(&tmp);
}
