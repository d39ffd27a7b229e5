//! CDR bytes of sample values equal the bytes Cyclone DDS's Python serializer produces for the
//! same values (tests/cyclone_cdr.py declares every type as a cyclonedds IdlStruct).
//! Needs the reference venv: METROCELL_PYTHON, or `tests/run` to create `.venv`.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn cyclone_dds_serializes_every_type_to_the_same_bytes() {
    let registry = metrocell_msgs::registry();
    let types = metrocell_msgs::type_names();
    let mut items = Vec::new();
    let mut expected = Vec::new();
    for (i, ty) in types.iter().enumerate() {
        for seed in [7u64, 1000 + i as u64] {
            let value = rosmsg::sample_value(registry, ty, seed).unwrap();
            items.push(serde_json::json!({"type": ty, "value": rosmsg::to_json(&value)}));
            expected.push((
                ty.clone(),
                hex(&rosmsg::encode(registry, ty, &value).unwrap()),
            ));
        }
    }
    // Defaults too (empty strings and sequences, quaternion w = 1).
    for ty in [
        "metrocell_msgs/msg/FiducialDetectionArray",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
    ] {
        let value = rosmsg::default_value(registry, ty).unwrap();
        items.push(serde_json::json!({"type": ty, "value": rosmsg::to_json(&value)}));
        expected.push((
            ty.to_string(),
            hex(&rosmsg::encode(registry, ty, &value).unwrap()),
        ));
    }

    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/cyclone_cdr.py");
    let mut child = Command::new(common::python())
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the reference Python");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::Value::Array(items).to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "cyclone_cdr.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = std::str::from_utf8(&out.stdout).unwrap().lines().collect();
    assert_eq!(lines.len(), expected.len());
    for ((ty, ours), theirs) in expected.iter().zip(&lines) {
        assert_eq!(ours, theirs, "{ty}: ours vs Cyclone DDS");
    }
    for required in [
        "sensor_msgs/msg/Temperature",
        "metrocell_msgs/msg/TrackerMeasurement",
        "metrocell_msgs/msg/FiducialDetectionArray",
        "metrocell_msgs/msg/ErrorModel",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
    ] {
        assert!(
            expected.iter().any(|(t, _)| t == required),
            "{required} not compared"
        );
    }
}
