//! Every vendored standard type (msgs/interfaces, ROS 2 Jazzy per its README) against the
//! `rosbags` type store of ROS 2 Jazzy, field by field: names, order, types, array kinds and
//! bounds, and constants with their values. `definitions.rs` checks that the generated Rust types
//! equal the vendored files; this checks the files against a source metrocell did not write.
//!
//! Run: `METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-msgs --test vendored_vs_rosbags`

mod common;

use rosmsg::{ArrayKind, BaseType, FieldType};
use serde_json::{json, Value};

/// The release msgs/interfaces/README.md names.
const STORE: &str = "ROS2_JAZZY";

/// A field type as a .msg file spells it, nested types as `pkg/msg/Type`.
fn spell(t: &FieldType) -> String {
    let base = match &t.base {
        BaseType::Message(n) => n.ros_type(),
        other => other.to_string(),
    };
    match t.array {
        ArrayKind::Single => base,
        ArrayKind::Fixed(n) => format!("{base}[{n}]"),
        ArrayKind::Bounded(n) => format!("{base}[<={n}]"),
        ArrayKind::Unbounded => format!("{base}[]"),
    }
}

#[test]
fn every_vendored_standard_type_equals_the_rosbags_jazzy_store() {
    let registry = metrocell_msgs::registry();
    let vendored: Vec<String> = registry.ros_type_names().into_iter().filter(|t| !t.starts_with("metrocell_msgs/")).collect();
    assert!(vendored.len() >= 25, "only {} vendored types: {vendored:?}", vendored.len());
    let out = std::process::Command::new(common::python())
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/rosbags_typestore.py"))
        .arg(STORE)
        .args(&vendored)
        .output()
        .expect("run rosbags_typestore.py");
    assert!(out.status.success(), "rosbags_typestore.py: {}", String::from_utf8_lossy(&out.stderr));
    let theirs: Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut fields_checked = 0;
    for t in &vendored {
        let spec = registry.get(t).unwrap_or_else(|| panic!("{t} not in the registry"));
        let reference = &theirs[t];
        assert!(!reference.is_null(), "{t} is not in the rosbags {STORE} store");
        let ours_fields: Vec<Value> = spec.fields.iter().map(|f| json!([f.name, spell(&f.ty)])).collect();
        assert_eq!(Value::Array(ours_fields), reference["fields"], "{t}: fields (name, type) differ from rosbags {STORE}");
        fields_checked += spec.fields.len();
        let ours_constants: Vec<Value> = spec.constants.iter().map(|c| json!([c.name, c.ty.to_string(), rosmsg::to_json(&c.value)])).collect();
        assert_eq!(Value::Array(ours_constants), reference["constants"], "{t}: constants differ from rosbags {STORE}");
    }
    println!("{} vendored types, {fields_checked} fields equal to rosbags {STORE}", vendored.len());
}
