//! Bad input gets a clear error naming what is wrong and a non-zero exit, never a panic.

use std::process::Output;
use std::time::Duration;

use system_tests::{bin, piped, require_isolated_network, run};

fn check_error(out: &Output, must_mention: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "expected failure, got success; stderr: {err}"
    );
    assert!(
        !err.contains("panicked"),
        "a panic is not an error message: {err}"
    );
    for m in must_mention {
        assert!(err.contains(m), "error should mention {m:?}: {err}");
    }
}

#[test]
fn unknown_type_name() {
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "pub",
            "/x",
            "sensor_msgs/msg/Thermometer",
            "{}",
            "--once",
        ]),
        Duration::from_secs(20),
    );
    check_error(
        &out,
        &[
            "unknown message type",
            "sensor_msgs/msg/Thermometer",
            "sensor_msgs/msg/Temperature",
        ],
    );
}

#[test]
fn yaml_that_does_not_fit_the_type() {
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "pub",
            "/x",
            "sensor_msgs/msg/Temperature",
            "{temperature: warm}",
            "--once",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["temperature", "warm"]);
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "pub",
            "/x",
            "sensor_msgs/msg/Temperature",
            "{temprature: 20.0}",
            "--once",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["temprature"]);
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "pub",
            "/x",
            "sensor_msgs/msg/Temperature",
            "{temperature: [",
            "--once",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["YAML"]);
}

#[test]
fn invalid_parameter_values() {
    require_isolated_network();
    let out = run(
        piped(bin("metrocell-thermal")).args(["--ros-args", "-p", "alpha:=abc"]),
        Duration::from_secs(20),
    );
    check_error(&out, &["alpha", "abc"]);
    let out = run(
        piped(bin("metrocell-thermal")).args(["--ros-args", "-p", "alpha:=0.5"]),
        Duration::from_secs(20),
    );
    check_error(&out, &["alpha", "0.5"]);
    let out = run(
        piped(bin("metrocell-thermal")).args([
            "--ros-args",
            "-p",
            "sensors:=[a, b]",
            "-p",
            "sensor_axes:=[x]",
            "-p",
            "sensor_positions:=[0.0, 1.0]",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["sensor_axes", "same length"]);
    let out = run(
        piped(bin("metrocell-thermal")).args([
            "--ros-args",
            "-p",
            "sensors:=[a]",
            "-p",
            "sensor_axes:=[w]",
            "-p",
            "sensor_positions:=[0.0]",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["sensor_axes", "'w'", "x, y, z"]);
}

#[test]
fn missing_params_file() {
    require_isolated_network();
    let out = run(
        piped(bin("metrocell-thermal")).args([
            "--ros-args",
            "--params-file",
            "/nonexistent/thermal.yaml",
        ]),
        Duration::from_secs(20),
    );
    check_error(&out, &["/nonexistent/thermal.yaml"]);
}

#[test]
fn bad_ros_arguments() {
    let out = run(
        piped(bin("metrocell-thermal")).args(["--ros-args", "-p", "alpha"]),
        Duration::from_secs(20),
    );
    check_error(&out, &["alpha", ":="]);
}

#[test]
fn unknown_cli_subcommand_teaches() {
    let out = run(
        piped(bin("metrocell")).args(["topic", "ech", "/x"]),
        Duration::from_secs(20),
    );
    check_error(&out, &["echo"]);
}
