//! A simulator bag read by real peers: Python `rosbags` (metadata.yaml + its own CDR decoder)
//! and `mcap` + `mcap-ros2-support` (embedded schemas) both decode every message and agree
//! with the counts write_bag reports and with the field conventions.
//! Needs the project's Python (METROCELL_PYTHON, else <workspace>/.venv; run tests/run).

use std::path::{Path, PathBuf};
use std::process::Command;

use metrocell_simulation::sim_time::{parse_start_time, DEFAULT_START_TIME};
use metrocell_simulation::{write_bag, BagOptions};
use metrocell_twin::Cell;

fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    if venv.exists() {
        return venv;
    }
    panic!("no Python with rosbags/mcap: set METROCELL_PYTHON or run tests/run to create .venv");
}

#[test]
fn rosbags_and_mcap_ros2_decode_the_bag() {
    let root = std::env::temp_dir().join(format!("metrocell-sim-referee-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let dir = root.join("demo");
    let cell = Cell::from_path(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap();
    let summary = write_bag(cell, 40.0, 11, &dir, &BagOptions::default(), |_| {}).unwrap();

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/referee.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(&dir)
        .output()
        .expect("start python");
    assert!(
        out.status.success(),
        "referee.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();

    for peer in ["rosbags", "mcap"] {
        for (topic, n) in &summary.messages_per_topic {
            assert_eq!(v[peer][topic].as_u64(), Some(*n), "{peer} count of {topic}");
        }
    }
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let tr = &v["tracker"];
    assert!(tr["range"].as_f64().unwrap() > 1.0 && tr["range"].as_f64().unwrap() < 2.0);
    assert!(tr["cov0"].as_f64().unwrap() > 0.0);
    assert!((tr["humidity"].as_f64().unwrap() - 0.5).abs() < 0.05);
    assert!((tr["index"].as_f64().unwrap() - 1.00027).abs() < 2e-5);
    assert_eq!(tr["frame"], "tracker");
    assert_eq!(
        (tr["stamp_ns"].as_u64().unwrap() - start) % 100_000_000,
        0,
        "tracker stamps on the 10 Hz grid"
    );
    assert!((v["temperature"]["value"].as_f64().unwrap() - 21.0).abs() < 0.2);
    assert_eq!(v["temperature"]["frame"], "table");
    assert_eq!(v["joint_state"]["name"], serde_json::json!(["x", "y", "z"]));
    assert_eq!(
        v["clock_ns"],
        serde_json::json!([start, start + 100_000_000])
    );
    std::fs::remove_dir_all(&root).unwrap();
}
