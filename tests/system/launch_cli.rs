//! `metrocell launch` with real node processes: two nodes start, a launch argument overrides a
//! parameter and the node's output shows it took effect, Ctrl-C stops everything within 2 s, and
//! a malformed file is rejected naming file, line and key.

use std::io::Read;
use std::time::{Duration, Instant};

use system_tests::{alive, bin, interrupt, piped, require_isolated_network, run, ChildGuard};

const LAUNCH: &str = r#"# two thermal compensators of one cell
launch:
- arg: {name: alpha, default: "11.5e-6"}
- node:
    pkg: metrocell
    exec: metrocell-thermal
    name: thermal_x
    namespace: /cell
    param:
    - {name: sensors, value: [x_mid]}
    - {name: sensor_axes, value: [x]}
    - {name: sensor_positions, value: [0.5]}
    - {name: alpha, value: $(var alpha)}
    - {name: publish_period, value: 0.2}
- node:
    pkg: metrocell
    exec: metrocell-thermal
    name: thermal_y
    namespace: /cell
    param:
    - {name: sensors, value: [y_mid]}
    - {name: sensor_axes, value: [y]}
    - {name: sensor_positions, value: [0.3]}
    - {name: publish_period, value: 0.2}
    remap:
    - {from: thermal/error_model, to: thermal_y/error_model}
"#;

fn write_launch(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn tmp(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!(
        "metrocell-launch-test-{}-{name}",
        std::process::id()
    ))
}

/// The first value of the first ErrorModel seen on `topic`.
fn first_strain(topic: &str) -> f64 {
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "echo",
            topic,
            "--type",
            "metrocell_msgs/msg/ErrorModel",
            "--json",
            "--count",
            "1",
        ]),
        Duration::from_secs(30),
    );
    assert!(
        out.status.success(),
        "echo {topic}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(out.stdout.split(|b| *b == b'\n').next().unwrap()).unwrap();
    // the scale strain, by its catalog name `thermal_scale[<axis>].strain`
    let names = v["parameter_names"].as_array().unwrap();
    let i = names
        .iter()
        .position(|n| {
            n.as_str()
                .is_some_and(|n| n.starts_with("thermal_scale[") && n.ends_with("].strain"))
        })
        .unwrap_or_else(|| panic!("no scale strain in {names:?}"));
    assert_eq!(v["term_ids"][i], "thermal_scale");
    v["values"][i].as_f64().unwrap()
}

#[test]
fn two_nodes_start_take_the_override_and_stop_on_ctrl_c() {
    require_isolated_network();
    let file = write_launch(&tmp("ok"), "cell.launch.yaml", LAUNCH);
    let mut launcher = ChildGuard::spawn(
        piped(bin("metrocell"))
            .arg("launch")
            .arg(&file)
            .arg("alpha:=2.0e-5"),
    );
    let _tx = ChildGuard::spawn(piped(bin("metrocell")).args([
        "topic",
        "pub",
        "/cell/temperature/x_mid",
        "sensor_msgs/msg/Temperature",
        "{temperature: 25.0, variance: 0.0001}",
        "--rate",
        "10",
    ]));
    let _ty = ChildGuard::spawn(piped(bin("metrocell")).args([
        "topic",
        "pub",
        "/cell/temperature/y_mid",
        "sensor_msgs/msg/Temperature",
        "{temperature: 22.0, variance: 0.0001}",
        "--rate",
        "10",
    ]));
    // thermal_x took alpha from the launch argument: 2.0e-5 · (25 − 20) K.
    let strain_x = first_strain("/cell/thermal/error_model");
    assert!(
        (strain_x - 1.0e-4).abs() < 1e-12,
        "x strain {strain_x}: the alpha override did not take effect"
    );
    // thermal_y kept its default alpha and its output was remapped: 11.5e-6 · 2 K.
    let strain_y = first_strain("/cell/thermal_y/error_model");
    assert!((strain_y - 2.3e-5).abs() < 1e-12, "y strain {strain_y}");

    // Ctrl-C: the launcher and both nodes are gone within 2 s.
    let started = Instant::now();
    interrupt(launcher.pid());
    let mut stderr = String::new();
    let mut child = launcher.0.take().unwrap();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(
            started.elapsed() < Duration::from_secs(2),
            "launcher still running 2 s after SIGINT"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let stopped_in = started.elapsed();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    let pids: Vec<i32> = stderr
        .lines()
        .filter_map(|l| l.split("started, pid ").nth(1))
        .filter_map(|rest| {
            rest.split(|c: char| !c.is_ascii_digit())
                .next()?
                .parse()
                .ok()
        })
        .collect();
    assert_eq!(
        pids.len(),
        2,
        "two node processes expected in the launcher's report:\n{stderr}"
    );
    for pid in &pids {
        assert!(!alive(*pid), "node pid {pid} survived the launcher");
    }
    assert!(
        status.success(),
        "Ctrl-C is a normal stop, got {status:?}\n{stderr}"
    );
    eprintln!("stopped in {stopped_in:?}");
}

#[test]
fn malformed_launch_file_names_file_line_and_key() {
    let bad = "launch:\n- node:\n    pkg: metrocell\n    exec: metrocell-thermal\n    pkgg: typo\n";
    let file = write_launch(&tmp("bad"), "broken.launch.yaml", bad);
    let out = run(
        piped(bin("metrocell")).arg("launch").arg(&file),
        Duration::from_secs(20),
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("{}:5:", file.display())),
        "file and line 5 expected in: {err}"
    );
    assert!(err.contains("pkgg"), "the key expected in: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn launch_argument_not_declared_is_an_error() {
    let file = write_launch(&tmp("undeclared"), "cell.launch.yaml", LAUNCH);
    let out = run(
        piped(bin("metrocell"))
            .arg("launch")
            .arg(&file)
            .arg("alhpa:=1"),
        Duration::from_secs(20),
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("alhpa"), "{err}");
}
