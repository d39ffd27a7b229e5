//! The live node over DDS: run `metrocell-sim` on the quick demo cell at 15x real time and
//! check, with typed subscriptions in this process, that temperatures and tracker
//! measurements arrive with plausible values, that /clock advances in simulated time from the
//! configured epoch, and that the node exits cleanly at the end of the run and on SIGTERM; and a
//! stationing program (the mobile manipulator) live on the import layout's topics, its ground
//! tilted by the node's `ground_tilt` parameter, its duration its one pass (`duration:=auto`).
//! Must run in a private network namespace: `tests/isolated cargo test -p metrocell-sim-node`.

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_msgs::msg::{MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{Imu, Temperature};
use metrocell_node::{qos, testing::require_isolated_network, DdsEnvironment, MetrocellNode};

/// 2026-01-05T06:00:00Z, the default start of simulated time.
const START_S: i64 = 1_767_592_800;

fn demo_cell() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../crates/twin/examples/cells/quick_demo.yaml")
        .display()
        .to_string()
}

/// Start the node; `domain` keeps tests that run in parallel apart (ROS_DOMAIN_ID).
fn spawn(domain: u32, params: &[&str]) -> Child {
    let mut args = vec!["--ros-args".to_string()];
    for p in params {
        args.push("-p".into());
        args.push(p.to_string());
    }
    Command::new(env!("CARGO_BIN_EXE_metrocell-sim"))
        .env("ROS_DOMAIN_ID", domain.to_string())
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap()
}

fn wait_exit(child: &mut Child, timeout: Duration) -> Option<std::process::ExitStatus> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    None
}

fn listener(name: &str) -> MetrocellNode {
    listener_on(name, 0)
}

/// A listening node on `domain`, whatever the environment says, to meet the node started with
/// that ROS_DOMAIN_ID.
fn listener_on(name: &str, domain: u32) -> MetrocellNode {
    require_isolated_network();
    let (b, _) = MetrocellNode::builder(name)
        .handle_signals(false)
        .args(["test"])
        .unwrap();
    let env = DdsEnvironment::from_lookup(|k| {
        if k == "ROS_DOMAIN_ID" {
            Some(domain.to_string())
        } else {
            std::env::var(k).ok()
        }
    })
    .unwrap();
    b.environment(env).build().unwrap()
}

#[test]
fn temperatures_tracker_and_clock_arrive_with_plausible_values() {
    let mut node = listener("sim_listener");
    let temps = node
        .subscription::<Temperature>("/temperature/x_left", qos::reliable())
        .unwrap();
    let tracker = node
        .subscription::<TrackerMeasurement>("/tracker/measurements", qos::reliable())
        .unwrap();
    let clock = node
        .subscription::<Clock>("/clock", qos::sensor_data())
        .unwrap();
    // 90 simulated seconds at 15x: 6 s of wall time.
    let cell = demo_cell();
    // Images off: a debug build renders a 5 MP frame in seconds, which would stall 15x pacing
    // (frames are checked in crates/sim/tests/camera_frames.rs).
    let mut child = spawn(
        0,
        &[
            &format!("cell:={cell}"),
            "duration:=90s",
            "speed:=15",
            "seed:=2",
            "camera_images:=false",
        ],
    );

    let (mut t_values, mut t_stamps, mut points, mut broken, mut clocks) =
        (vec![], vec![], vec![], 0, vec![]);
    let started = Instant::now();
    let mut status = None;
    while started.elapsed() < Duration::from_secs(30) {
        while let Ok(Some((t, _))) = temps.take() {
            t_values.push((t.temperature, t.variance));
            t_stamps.push(t.header.stamp.sec as i64);
        }
        while let Ok(Some((m, _))) = tracker.take() {
            if m.status == TrackerMeasurement::STATUS_OK {
                points.push(m);
            } else {
                broken += 1;
            }
        }
        while let Ok(Some((c, _))) = clock.take() {
            clocks.push(c.clock.sec as f64 + c.clock.nanosec as f64 * 1e-9 - START_S as f64);
        }
        if status.is_none() {
            status = child.try_wait().unwrap();
        } else {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = status.or_else(|| wait_exit(&mut child, Duration::from_secs(1)));
    assert!(
        status.is_some_and(|s| s.success()),
        "node did not exit cleanly at the end of the run: {status:?}"
    );

    eprintln!(
        "received {} temperatures, {} tracker points + {broken} beam breaks, {} clocks from {:.2} to {:.2} s",
        t_values.len(),
        points.len(),
        clocks.len(),
        clocks.first().copied().unwrap_or(f64::NAN),
        clocks.last().copied().unwrap_or(f64::NAN)
    );
    // Thermocouple x_left: 1 Hz for 90 s, table node starting at 21 °C, σ 0.02 K. Samples sent
    // before discovery completes are lost (volatile QoS), so expect most, not all.
    assert!(
        t_values.len() >= 60 && t_values.len() <= 90,
        "{} temperatures",
        t_values.len()
    );
    for (v, var) in &t_values {
        assert!((20.5..24.0).contains(v), "temperature {v} °C");
        assert!((var - 4e-4).abs() < 1e-12, "variance {var}");
    }
    assert!(
        t_stamps.windows(2).all(|w| w[1] == w[0] + 1),
        "one reading per simulated second, in order"
    );
    assert!(t_stamps.iter().all(|s| (START_S..START_S + 90).contains(s)));

    // Tracker: 10 Hz, ranges 1–2 m, stated σ of a few µm, air data of the cell.
    assert!(
        points.len() + broken >= 600 && points.len() + broken <= 900,
        "{} tracker samples",
        points.len() + broken
    );
    for m in &points {
        assert!(m.range > 1.0 && m.range < 2.0, "range {}", m.range);
        let sigma_x = m.covariance[0].sqrt();
        assert!(sigma_x > 1e-7 && sigma_x < 1e-4, "σx {sigma_x}");
        assert!((m.air_pressure - 101_300.0).abs() < 200.0);
        assert!((m.air_humidity - 0.5).abs() < 0.05);
        assert!((m.refractive_index - 1.00027).abs() < 2e-5);
    }

    // /clock: many ticks, never backwards, spanning most of the 90 s and ending at 90 s.
    assert!(clocks.len() >= 100, "{} clock messages", clocks.len());
    assert!(
        clocks.windows(2).all(|w| w[1] >= w[0]),
        "clock went backwards"
    );
    let (first, last) = (clocks[0], *clocks.last().unwrap());
    assert!(
        first < 30.0 && (last - 90.0).abs() < 1e-6,
        "clock from {first} to {last} s"
    );
}

#[test]
fn looping_node_stops_cleanly_on_sigterm() {
    require_isolated_network();
    let cell = demo_cell();
    let mut child = spawn(
        41,
        &[
            &format!("cell:={cell}"),
            "duration:=10s",
            "speed:=20",
            "loop:=true",
        ],
    );
    std::thread::sleep(Duration::from_secs(3));
    assert!(
        child.try_wait().unwrap().is_none(),
        "a looping node must still run after its 0.5 s run length"
    );
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let status = wait_exit(&mut child, Duration::from_secs(10));
    assert!(
        status.is_some_and(|s| s.success()),
        "exit on SIGTERM: {status:?}"
    );
}

#[test]
fn missing_cell_is_a_clear_error() {
    require_isolated_network();
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-sim"))
        .env("ROS_DOMAIN_ID", "42")
        .args(["--ros-args", "-p", "cell:=/nonexistent/cell.yaml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/cell.yaml"), "{err}");
}

#[test]
fn a_stationing_program_publishes_check_points_and_accelerometers_on_its_tilted_ground() {
    let mut node = listener_on("sim_station_listener", 42);
    let check = node
        .subscription::<MeasuredPoint>("/check_points", qos::reliable())
        .unwrap();
    let imu = node
        .subscription::<Imu>("/imu/base", qos::reliable())
        .unwrap();
    let cell = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../crates/twin/examples/cells/mobile_manipulator.yaml")
        .display()
        .to_string();
    // the program's pass (~42 min) at 1000x, after 2 s for discovery
    let mut child = spawn(
        42,
        &[
            &format!("cell:={cell}"),
            "duration:=auto",
            "ground_tilt:=0,15mrad",
            "speed:=1000",
            "start_delay:=2.0",
        ],
    );
    let (mut points, mut forces) = (Vec::new(), Vec::new());
    let started = Instant::now();
    let mut status = None;
    while started.elapsed() < Duration::from_secs(60) && status.is_none() {
        while let Ok(Some((p, _))) = check.take() {
            points.push(p);
        }
        while let Ok(Some((m, _))) = imu.take() {
            forces.push(m.linear_acceleration);
        }
        status = child.try_wait().unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    while let Ok(Some((p, _))) = check.take() {
        points.push(p);
    }
    let status = status.or_else(|| wait_exit(&mut child, Duration::from_secs(1)));
    assert!(
        status.is_some_and(|s| s.success()),
        "node did not finish its pass cleanly: {status:?}"
    );
    eprintln!(
        "received {} check points, {} base accelerometer readings",
        points.len(),
        forces.len()
    );
    assert!(
        points.len() >= 300 && points.len() <= 360,
        "{} of the 360 check points",
        points.len()
    );
    assert!(points
        .iter()
        .all(|p| p.header.frame_id.starts_with("total_station@S") && p.point_id.starts_with('G')));
    // 15 mrad nose down: the base sensor's specific force leans to −x by g·sin(15 mrad)
    assert!(
        !forces.is_empty() && forces.iter().all(|f| (f.x + 9.80665 * 0.015).abs() < 0.06),
        "{:?}",
        forces.first()
    );
}
