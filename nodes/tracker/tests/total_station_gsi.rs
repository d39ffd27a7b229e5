//! The node with `backend:=tcp instrument:=total_station_gsi` against a test server playing a
//! total station that streams Leica GSI-16 blocks: every block comes out on
//! `/tracker/measurements` as a reading equal to the hand conversion (x toward Hz = 0, y toward
//! Hz = 300 gon, z up; face II mapped to face I); a malformed line is a WARN naming the line,
//! and the blocks after it still come through.
//!
//! Run: `tests/isolated cargo test -p metrocell-tracker-node --test total_station_gsi`

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::process::{Command, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};

const GON: f64 = std::f64::consts::PI / 200.0;
const MALFORMED: &str = "*110004+0000000000000004 21.022+00000000000x0000 22.022+0000000010000000 31..00+0000000000001000";

/// (GSI-16 line, point id, face-I Hz [rad] and V [rad] written by hand, slope distance [m])
fn blocks() -> Vec<(&'static str, &'static str, f64, f64, f64)> {
    vec![
        // Hz 50 gon, V 100 gon (horizontal), 10.000 m (unit 0: mm)
        ("*110001+00000000000000P1 21.022+0000000005000000 22.022+0000000010000000 31..00+0000000000010000 51....+000000000000+000 ", "P1", 50.0 * GON, 100.0 * GON, 10.0),
        // face II: Hz 300 gon, V 350 gon → face I Hz 100 gon, V 50 gon; 2.00000 m (unit 8: 1/100 mm)
        ("*110002+00000000000000P2 21.022+0000000030000000 22.022+0000000035000000 31..08+0000000000200000 ", "P2", 100.0 * GON, 50.0 * GON, 2.0),
        // 360° sexagesimal: Hz 30°00'00.0", V 60°00'00.0"; 5.0000 m (unit 6: 1/10 mm)
        ("*110003+00000000000000P3 21.024+0000000003000000 22.024+0000000006000000 31..06+0000000000050000", "P3", 30f64.to_radians(), 60f64.to_radians(), 5.0),
        // after the malformed line: Hz 123.45670 gon, V 95.43210 gon, 7.12345 m
        ("*110005+00000000000000P5 21.022+0000000012345670 22.022+0000000009543210 31..08+0000000000712345 ", "P5", 123.4567 * GON, 95.4321 * GON, 7.12345),
    ]
}

/// The hand conversion: Hz clockwise from x seen from above, V from the zenith.
fn by_hand(hz: f64, v: f64, sd: f64) -> [f64; 3] {
    [
        sd * v.sin() * hz.cos(),
        -sd * v.sin() * hz.sin(),
        sd * v.cos(),
    ]
}

#[test]
fn gsi_blocks_over_tcp_come_out_as_tracker_measurements() {
    metrocell_node::testing::require_isolated_network();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let (go_tx, go_rx) = mpsc::channel::<()>();
    let lines: Vec<String> = blocks().iter().map(|b| b.0.to_string()).collect();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        go_rx.recv().unwrap();
        for (k, l) in lines.iter().enumerate() {
            if k == 3 {
                s.write_all(format!("{MALFORMED}\r\n").as_bytes()).unwrap();
            }
            s.write_all(format!("{l}\r\n").as_bytes()).unwrap();
            s.flush().unwrap();
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_secs(2));
    });

    // σ 1″, 1 mm + 2 ppm
    let args = [
        "--ros-args",
        "-p",
        "backend:=tcp",
        "-p",
        "instrument:=total_station_gsi",
        "-p",
        &format!("tcp_address:={address}"),
        "-p",
        "total_station_angle_sigma:=1.0",
        "-p",
        "total_station_distance_sigma:=0.001",
        "-p",
        "total_station_distance_ppm:=2.0",
        "-p",
        "tracker_frame:=station_1",
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .args(args)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let _node = Killed(child);
    let log = Arc::new(Mutex::new(Vec::<String>::new()));
    let log_writer = log.clone();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            log_writer.lock().unwrap().push(line);
        }
    });

    let mut peer = MetrocellNode::builder("total_station_test")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let readings = peer
        .subscription::<TrackerMeasurement>("/tracker/measurements", qos::stream(qos::reliable()))
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !peer
        .discovered_topics()
        .iter()
        .any(|t| t.name.ends_with("tracker/measurements"))
    {
        assert!(
            Instant::now() < deadline,
            "the node's tracker/measurements was not discovered; its log: {:?}",
            log.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_secs(1));
    go_tx.send(()).unwrap();
    let mut received = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(15);
    while Instant::now() < deadline && received.len() < 4 {
        while let Ok(Some((m, _))) = readings.take() {
            received.push(m);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(500));
    while let Ok(Some((m, _))) = readings.take() {
        received.push(m);
    }
    server.join().unwrap();
    let log = log.lock().unwrap().clone();

    assert_eq!(
        received
            .iter()
            .map(|m| m.target_id.as_str())
            .collect::<Vec<_>>(),
        ["P1", "P2", "P3", "P5"],
        "log: {log:?}"
    );
    for (m, (_, id, hz, v, sd)) in received.iter().zip(blocks()) {
        let expected = by_hand(hz, v, sd);
        let got = [m.point.x, m.point.y, m.point.z];
        for k in 0..3 {
            assert!(
                (got[k] - expected[k]).abs() < 1e-12,
                "{id}: {got:?} vs by hand {expected:?}"
            );
        }
        assert!(
            (m.range - sd).abs() < 1e-12 && (m.elevation - (100.0 * GON - v)).abs() < 1e-12,
            "{id}"
        );
        assert!(
            (m.azimuth + hz).abs() < 1e-12
                || (m.azimuth + hz - 2.0 * std::f64::consts::PI).abs() < 1e-12,
            "{id}: azimuth {} vs −Hz {}",
            m.azimuth,
            -hz
        );
        assert_eq!(
            (m.header.frame_id.as_str(), m.status, m.refractive_index),
            ("station_1", TrackerMeasurement::STATUS_OK, 0.0)
        );
        assert!(m.air_temperature.is_nan() && m.air_pressure.is_nan() && m.air_humidity.is_nan());
        // along the line of sight the variance is σ_SD² = (1 mm + 2 ppm·SD)²
        let u: Vec<f64> = expected.iter().map(|c| c / sd).collect();
        let radial: f64 = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| u[i] * m.covariance[3 * i + j] * u[j])
                    .sum::<f64>()
            })
            .sum();
        assert!(
            (radial.sqrt() - (1e-3 + 2e-6 * sd)).abs() < 1e-12,
            "{id}: σ along the sight {}",
            radial.sqrt()
        );
    }
    // the hand values of the plain cases, spelled out
    assert!(
        (received[0].point.x - 10.0 / 2f64.sqrt()).abs() < 1e-12
            && (received[0].point.y + 10.0 / 2f64.sqrt()).abs() < 1e-12
            && received[0].point.z.abs() < 1e-12
    );
    assert!(
        (received[2].point.x - 3.75).abs() < 1e-12
            && (received[2].point.y + 5.0 * 0.75f64.sqrt() * 0.5).abs() < 1e-12
            && (received[2].point.z - 2.5).abs() < 1e-12
    );
    assert!(
        received
            .windows(2)
            .all(|w| w[1].header.stamp.nanos() > w[0].header.stamp.nanos()),
        "stamps increase"
    );
    let warned: Vec<&String> = log
        .iter()
        .filter(|l| l.contains("WARN") && l.contains(MALFORMED))
        .collect();
    assert_eq!(
        warned.len(),
        1,
        "one WARN naming the malformed line; log: {log:?}"
    );
    assert!(
        warned[0].contains("GSI word 2 at column 26") && warned[0].contains("not all digits"),
        "{}",
        warned[0]
    );
}

#[test]
fn a_total_station_without_the_tcp_backend_is_refused_at_start_up() {
    metrocell_node::testing::require_isolated_network();
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .args(["--ros-args", "-p", "instrument:=total_station_gsi"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("instrument:=total_station_gsi")
            && stderr.contains("set -p backend:=tcp -p tcp_address:=HOST:PORT"),
        "{stderr}"
    );
}
