//! The node with `backend:=tcp` against a test server playing the instrument: lines split
//! across writes, garbage, a connection dropped mid-line and the buffer resent. Every dwell
//! appears once on `measured_points` at its nominal; nothing is accepted twice.
//!
//! Run: `tests/isolated cargo test -p metrocell-tracker-node --test tcp_backend`

use std::io::Write;
use std::net::TcpListener;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use metrocell_compensation::{to_spherical, AirData};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};
use nalgebra::{Rotation3, Vector3};

const T0: f64 = 1_764_000_000.0;
const NOMINALS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.4, 0.0, 0.1],
    [0.4, 0.3, 0.0],
    [0.0, 0.3, 0.2],
];

#[test]
fn tcp_instrument_feeds_measured_points_once_each() {
    metrocell_node::testing::require_isolated_network();
    let air = AirData {
        temperature: 20.2,
        pressure: 100_800.0,
        humidity: 0.45,
    };
    let (r, t) = (
        Rotation3::from_euler_angles(0.0, 0.0, 0.6),
        Vector3::new(-1.3, 0.1, 0.5),
    );
    // the stream: 10 readings per nominal at 10 Hz, 2 s between dwells, then one moving reading
    let mut lines = Vec::new();
    let mut commanded = Vec::new();
    let mut time = T0;
    for (k, q) in NOMINALS.iter().enumerate() {
        let q = Vector3::from(*q);
        let (range, az, el) = to_spherical(&(r.inverse() * (q - t)));
        for _ in 0..10 {
            time += 0.1;
            lines.push(format!(
                "{time:.3},p{k},{range:.9},{az:.9},{el:.9},{},{},{}\n",
                air.temperature, air.pressure, air.humidity
            ));
            commanded.push((time, q));
        }
        time += 2.0;
    }
    time += 1.0;
    lines.push(format!(
        "{time:.3},,1.5,0.1,0.1,{},{},{}\n",
        air.temperature, air.pressure, air.humidity
    ));
    commanded.push((time, Vector3::zeros()));

    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let (go_tx, go_rx) = mpsc::channel::<()>();
    let server_lines = lines.clone();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        go_rx.recv().unwrap();
        let half = server_lines.len() / 2;
        for l in &server_lines[..half] {
            s.write_all(l.as_bytes()).unwrap();
        }
        s.write_all(b"\x00\x01 garbage\n").unwrap();
        s.write_all(&server_lines[half].as_bytes()[..8]).unwrap(); // cut mid-line
        drop(s);
        let (mut s, _) = listener.accept().unwrap();
        for l in &server_lines[half - 5..] {
            s.write_all(l.as_bytes()).unwrap(); // resends five already-sent readings
            s.flush().unwrap();
        }
        std::thread::sleep(Duration::from_secs(2));
    });

    // the instrument applied the index of the air it reports: the node's re-correction is then exact
    let index = format!(
        "instrument_refractive_index:={:.15}",
        air.refractive_index()
    );
    let args = [
        "--ros-args",
        "-p",
        "backend:=tcp",
        "-p",
        &format!("tcp_address:={address}"),
        "-p",
        "registration_points:=4",
        "-p",
        "tcp_initial_backoff:=0.05",
        "-p",
        &index,
    ];
    let _node = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
            .args(args)
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut machine = MetrocellNode::builder("tracker_tcp_test")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let commanded_pub = machine
        .publisher::<JointState>("/machine/commanded_joint_states", qos::sensor_data())
        .unwrap();
    let points = machine
        .subscription::<MeasuredPoint>("/measured_points", qos::reliable())
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    while !machine
        .discovered_topics()
        .iter()
        .any(|t| t.name.ends_with("measured_points"))
    {
        assert!(Instant::now() < deadline, "tracker node not discovered");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_secs(1));
    for (time, q) in &commanded {
        let j = JointState {
            header: Header {
                stamp: Time::from_nanos((time * 1e9).round() as i64),
                frame_id: String::new(),
            },
            name: vec!["x".into(), "y".into(), "z".into()],
            position: vec![q.x, q.y, q.z],
            velocity: vec![],
            effort: vec![],
        };
        let _ = commanded_pub.publish(j);
        std::thread::sleep(Duration::from_millis(3));
    }
    std::thread::sleep(Duration::from_millis(500));
    go_tx.send(()).unwrap();
    let mut received = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(15);
    while Instant::now() < deadline && received.len() < 4 {
        while let Ok(Some((p, _))) = points.take() {
            received.push(p);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(500));
    while let Ok(Some((p, _))) = points.take() {
        received.push(p);
    }
    server.join().unwrap();
    assert_eq!(
        received
            .iter()
            .map(|p| p.point_id.as_str())
            .collect::<Vec<_>>(),
        ["p0", "p1", "p2", "p3"]
    );
    for (p, q) in received.iter().zip(NOMINALS) {
        assert_eq!([p.nominal.x, p.nominal.y, p.nominal.z], q);
        let m = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
        // 9-digit lines: sub-µm agreement after registration
        assert!(
            (m - Vector3::from(q)).norm() < 1e-6,
            "{}: {m:?}",
            p.point_id
        );
    }
}
