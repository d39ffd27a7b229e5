//! Every vendored standard ROS 2 type (msgs/interfaces) has, field by field and constant by
//! constant, the definition the `rosbags` type store holds for ROS 2 Jazzy — a copy of the
//! definitions made independently of the .msg files these were vendored from.
//! Needs the reference venv: METROCELL_PYTHON, or `tests/run` to create `.venv`.

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

use rosmsg::{ArrayKind, BaseType};

fn field_text(ty: &rosmsg::FieldType) -> String {
    let base = match &ty.base {
        BaseType::Message(t) => format!("{}/{}", t.package, t.name),
        other => other.to_string(),
    };
    match ty.array {
        ArrayKind::Single => base,
        ArrayKind::Fixed(n) => format!("{base}[{n}]"),
        ArrayKind::Bounded(n) => format!("{base}[<={n}]"),
        ArrayKind::Unbounded => format!("{base}[]"),
    }
}

#[test]
fn vendored_standard_types_match_the_rosbags_jazzy_store() {
    let registry = metrocell_msgs::registry();
    let standard: Vec<String> = metrocell_msgs::type_names()
        .into_iter()
        .filter(|t| !t.starts_with("metrocell_msgs/"))
        .collect();
    assert!(
        standard.len() >= 60,
        "{} standard types vendored",
        standard.len()
    );
    for t in [
        "rcl_interfaces/msg/Log",
        "rcl_interfaces/msg/ParameterEvent",
        "rcl_interfaces/msg/ParameterDescriptor",
        "std_msgs/msg/Float64MultiArray",
    ] {
        assert!(standard.iter().any(|s| s == t), "{t} vendored");
    }
    let mut child = Command::new(common::python())
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/rosbags_fields.py"
        ))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the reference Python");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(&standard).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "rosbags_fields.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let theirs: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut checked = 0;
    for ty in &standard {
        let spec = registry
            .get(ty)
            .unwrap_or_else(|| panic!("{ty} in the registry"));
        let Some(reference) = theirs[ty].as_object() else {
            panic!("{ty}: not in rosbags' Jazzy type store")
        };
        let mut ours: Vec<serde_json::Value> = spec
            .fields
            .iter()
            .map(|f| serde_json::json!([f.name, field_text(&f.ty)]))
            .collect();
        if ours.is_empty() {
            // A message without fields is one uint8 on the wire; rosbags writes that member out.
            ours.push(serde_json::json!([
                "structure_needs_at_least_one_member",
                "uint8"
            ]));
        }
        assert_eq!(
            serde_json::Value::Array(ours),
            reference["fields"],
            "{ty}: fields differ from rosbags' Jazzy definition"
        );
        let constants: Vec<serde_json::Value> = spec
            .constants
            .iter()
            .map(|c| serde_json::json!([c.name, c.ty.to_string(), rosmsg::to_json(&c.value)]))
            .collect();
        assert_eq!(
            serde_json::Value::Array(constants),
            reference["constants"],
            "{ty}: constants differ from rosbags' Jazzy definition"
        );
        checked += 1;
    }
    assert_eq!(checked, standard.len());
}
