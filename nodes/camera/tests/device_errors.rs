//! `metrocell-camera -p device:=...` on this camera-less machine: a missing device and a
//! non-V4L2 file stop the node with an error naming the device. (The capture path itself is
//! untested on hardware.) The node opens a DDS participant, so this runs isolated.
//!
//! Run: `tests/isolated cargo test -p metrocell-camera-node --test device_errors`

use std::process::Command;

fn run(device: &str) -> (bool, String) {
    run_with(device, &[])
}

fn run_with(device: &str, extra: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-camera"))
        .args(["--ros-args", "-p", &format!("device:={device}")])
        .args(extra)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn missing_or_non_capture_devices_stop_the_node_with_the_device_named() {
    metrocell_node::testing::require_isolated_network();
    let (ok, err) = run("/dev/video_metrocell_missing");
    assert!(!ok, "node must fail");
    assert!(
        err.contains("/dev/video_metrocell_missing: cannot open"),
        "{err}"
    );
    let (ok, err) = run("/dev/null");
    assert!(!ok && err.contains("/dev/null: not a V4L2 device"), "{err}");
    // A negative size is refused by its declared range before any device is touched.
    let (ok, err) = run_with("/dev/null", &["-p", "width:=-1"]);
    assert!(
        !ok && err.contains("'width'") && err.contains("[0, 16384]"),
        "{err}"
    );
}
