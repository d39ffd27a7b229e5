//! README: every node "stops cleanly within a second on SIGINT/SIGTERM". Held here for every node
//! binary and both signals, while the node is working: the digital twin runs throughout (20×
//! real time, camera frames rendered) so the thermal node, the recorder, the fiducial and probe
//! nodes have traffic to handle (the estimator its commanded joints and temperatures), and the
//! camera node publishes its own frames.
//!
//! "Running" means the node's 1 Hz `/diagnostics` heartbeat has arrived (its DDS participant,
//! subscriptions and loop are up). Then the signal; the process must have exited, with status 0,
//! within 1 s.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test node_shutdown -- --nocapture`

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_node::{qos, MetrocellNode, Subscription};
use nix::sys::signal::Signal;
use system_tests::{bin, require_isolated_network, workspace_root, ChildGuard};

/// The bound the README states.
const STOP_BOUND: Duration = Duration::from_secs(1);

/// Waits (at most 30 s) for a heartbeat from the node named `fqn`.
fn wait_running(diagnostics: &Subscription<DiagnosticArray>, fqn: &str, child: &mut ChildGuard) {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        while let Ok(Some((d, _))) = diagnostics.take() {
            if d.status.iter().any(|s| s.name == fqn) {
                return;
            }
        }
        if let Some(status) = child.child().try_wait().unwrap() {
            panic!("{fqn} exited before its first heartbeat: {status}");
        }
        assert!(
            Instant::now() < deadline,
            "no /diagnostics heartbeat from {fqn} within 30 s"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Starts `exe` with `args`, waits until it runs, sends `signal` and returns how long it took to
/// exit; panics if it is still running after the bound or exits non-zero.
fn stop_time(
    diagnostics: &Subscription<DiagnosticArray>,
    exe: &Path,
    name: &str,
    args: &[String],
    signal: Signal,
) -> Duration {
    while let Ok(Some(_)) = diagnostics.take() {}
    let mut child = ChildGuard::spawn(
        Command::new(exe)
            .args(args)
            .args(["-r", &format!("__node:={name}")])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped()),
    );
    wait_running(diagnostics, &format!("/{name}"), &mut child);
    // Let it work for a moment (subscriptions matched, messages flowing) before the signal.
    std::thread::sleep(Duration::from_millis(700));
    assert!(
        child.child().try_wait().unwrap().is_none(),
        "{name} exited on its own"
    );
    let t0 = Instant::now();
    nix::sys::signal::kill(nix::unistd::Pid::from_raw(child.pid()), signal).unwrap();
    let status = loop {
        if let Some(s) = child.child().try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > STOP_BOUND {
            let out = child.0.take().map(|mut c| {
                let _ = c.kill();
                c.wait_with_output().unwrap()
            });
            panic!(
                "{name} still running {STOP_BOUND:?} after {signal}; stderr:\n{}",
                out.map(|o| String::from_utf8_lossy(&o.stderr).into_owned())
                    .unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let took = t0.elapsed();
    let out = child.0.take().unwrap().wait_with_output().unwrap();
    assert!(
        status.success(),
        "{name} after {signal}: exit {status}; stderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    took
}

#[test]
fn every_node_stops_within_a_second_on_sigint_and_sigterm() {
    require_isolated_network();
    let root = workspace_root();
    let tmp = std::env::temp_dir().join(format!("metrocell-node-shutdown-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    // One frame for the camera node.
    let frames = tmp.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    image::GrayImage::from_fn(640, 480, |x, y| {
        image::Luma([((x / 40 + y / 40) % 2 * 200 + 20) as u8])
    })
    .save(frames.join("f0.png"))
    .unwrap();

    let mut observer = MetrocellNode::builder("shutdown_observer")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let diagnostics = observer
        .subscription::<DiagnosticArray>("/diagnostics", qos::reliable())
        .unwrap();

    // The twin as the traffic source for the others (and the first node held to the bound).
    let cell = root.join("crates/twin/examples/cells/quick_demo.yaml");
    let sim_args: Vec<String> = [
        "--ros-args",
        "-p",
        &format!("cell:={}", cell.display()),
        "-p",
        "speed:=20",
        "-p",
        "loop:=true",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<String>>();
    let nodes: Vec<(&str, Vec<String>)> = vec![
        ("metrocell-sim", sim_args.clone()),
        // launch-configs/thermal.params.yaml's sensors, given with -p (its section is keyed by the node name `thermal`)
        (
            "metrocell-thermal",
            s(&[
                "--ros-args",
                "-p",
                "sensors:=[x_left, x_right]",
                "-p",
                "sensor_axes:=[x, x]",
                "-p",
                "sensor_positions:=[0.0, 0.4]",
            ]),
        ),
        (
            "metrocell-recorder",
            s(&[
                "--ros-args",
                "-p",
                &format!("output:={}", tmp.join("bag").display()),
            ]),
        ),
        (
            "metrocell-camera",
            s(&[
                "--ros-args",
                "-p",
                &format!("path:={}", frames.display()),
                "-p",
                "loop:=true",
                "-p",
                "rate:=20.0",
            ]),
        ),
        (
            "metrocell-fiducial",
            s(&[
                "--ros-args",
                "-r",
                "image:=/camera/image_raw",
                "-r",
                "camera_info:=/camera/camera_info",
            ]),
        ),
        (
            "metrocell-probe",
            s(&["--ros-args", "-r", "probe/trigger:=/machine/joint_states"]),
        ),
        // reads the twin's commanded joints and thermocouples (no measured points: no tracker node here)
        (
            "metrocell-estimator",
            s(&[
                "--ros-args",
                "-p",
                &format!(
                    "model:={}",
                    root.join("launch-configs/cells/demo_model.yaml").display()
                ),
            ]),
        ),
        // the twin's raw readings, diagnosed every 20 s of cell time, so a diagnosis may be running when the signal comes
        (
            "metrocell-diagnose",
            s(&[
                "--ros-args",
                "-p",
                &format!(
                    "model:={}",
                    root.join("launch-configs/cells/demo_model.yaml").display()
                ),
                "-p",
                "points:=/tracker/measurements",
                "-p",
                "points_type:=tracker",
                "-p",
                "every:=20.0",
                "-p",
                "min_records:=10",
            ]),
        ),
        // the twin's raw readings (registration from the first 6 targets, as in the demo)
        (
            "metrocell-tracker",
            s(&[
                "--ros-args",
                "-p",
                "tool_offset:=[0.0, 0.0, -0.1]",
                "-p",
                "registration_points:=6",
            ]),
        ),
        // its HTTP and Foxglove servers on free ports, so the bound covers closing them too
        (
            "metrocell-dashboard",
            s(&["--ros-args", "-p", "port:=0", "-p", "foxglove_port:=0"]),
        ),
        // serving its action and publishing poses
        ("metrocell-robot-twin", s(&["--ros-args"])),
        // waiting for a robot that never answers (its longest wait)
        (
            "metrocell-align",
            s(&["--ros-args", "-p", "move_timeout:=600.0"]),
        ),
    ];
    let mut load = ChildGuard::spawn(
        Command::new(bin("metrocell-sim"))
            .args(&sim_args)
            .args(["-r", "__node:=shutdown_load"])
            .stdout(Stdio::null())
            .stderr(Stdio::null()),
    );
    let mut worst = Duration::ZERO;
    for (k, (exe, args)) in nodes.iter().enumerate() {
        for (j, signal) in [Signal::SIGINT, Signal::SIGTERM].into_iter().enumerate() {
            // A distinct node name per run, so a heartbeat of an earlier run cannot count.
            let name = format!("shutdown_{k}_{j}");
            // The recorder refuses an existing output directory: a new one per run.
            let args: Vec<String> = args
                .iter()
                .map(|a| {
                    a.replace(
                        &tmp.join("bag").display().to_string(),
                        &tmp.join(format!("bag{j}")).display().to_string(),
                    )
                })
                .collect();
            let took = stop_time(&diagnostics, &bin(exe), &name, &args, signal);
            println!(
                "{exe:>20} {signal}: exited {:.0} ms after the signal",
                took.as_secs_f64() * 1e3
            );
            worst = worst.max(took);
        }
    }
    assert!(
        load.child().try_wait().unwrap().is_none(),
        "the load twin stopped during the test"
    );
    println!(
        "slowest stop: {:.0} ms (bound {STOP_BOUND:?})",
        worst.as_secs_f64() * 1e3
    );
    // Both recordings were finished on the signal: a readable bag each.
    for j in 0..2 {
        let bag = tmp.join(format!("bag{j}"));
        assert!(
            metrocell_bag::BagReader::open(&bag).is_ok(),
            "recorder bag {} not finished",
            bag.display()
        );
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
