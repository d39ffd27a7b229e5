//! The full definitions (MCAP `ros2msg` schema data) parse with mcap-ros2-support, and its
//! independent CDR decoder reads our encodings back to the same values.
//! Needs the reference venv: METROCELL_PYTHON, or `tests/run` to create `.venv`.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

#[test]
fn mcap_ros2_decodes_our_cdr_with_our_definitions() {
    let registry = metrocell_msgs::registry();
    let mut items = Vec::new();
    let mut expected = Vec::new();
    for ty in metrocell_msgs::type_names() {
        let value = rosmsg::sample_value(registry, &ty, 11).unwrap();
        let cdr = rosmsg::encode(registry, &ty, &value).unwrap();
        let hex: String = cdr.iter().map(|b| format!("{b:02x}")).collect();
        items.push(serde_json::json!({
            "type": ty,
            "definition": registry.full_definition(&ty).unwrap(),
            "cdr": hex,
        }));
        expected.push((ty, rosmsg::to_json(&value)));
    }
    let mut child = Command::new(common::python())
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/mcap_decode.py"))
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
        "mcap_decode.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<&str> = std::str::from_utf8(&out.stdout).unwrap().lines().collect();
    assert_eq!(lines.len(), expected.len());
    for ((ty, ours), line) in expected.iter().zip(lines) {
        let theirs: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(
            &theirs, ours,
            "{ty}: mcap-ros2-support decoded something else"
        );
    }
}
