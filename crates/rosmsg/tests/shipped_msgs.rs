//! Every `.msg` file shipped in `msgs/` parses, resolves, and has the layout upstream defines.

use rosmsg::{ArrayKind, BaseType, Primitive, Registry, Value};
use std::path::Path;

fn shipped() -> Registry {
    let msgs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../msgs");
    let mut r = Registry::new();
    let own = r
        .add_package_dir("metrocell_msgs", &msgs.join("msg"))
        .unwrap();
    assert_eq!(own, 6);
    let std = r.add_tree(&msgs.join("interfaces")).unwrap();
    assert_eq!(std, 70, "standard interfaces shipped in msgs/interfaces (66 + Wrench, WrenchStamped, TimeReference, Imu)");
    r.check().unwrap();
    r
}

#[test]
fn every_shipped_msg_parses_and_resolves() {
    let r = shipped();
    for spec in r.specs() {
        r.full_definition(&spec.type_name.short()).unwrap();
    }
    let q = r.spec("geometry_msgs/msg/Quaternion").unwrap();
    assert_eq!(q.field("w").unwrap().default, Some(Value::Float(1.0)));
    let cam = r.spec("sensor_msgs/CameraInfo").unwrap();
    assert_eq!(cam.field("k").unwrap().ty.array, ArrayKind::Fixed(9));
    assert_eq!(cam.field("p").unwrap().ty.array, ArrayKind::Fixed(12));
    assert_eq!(cam.field("d").unwrap().ty.array, ArrayKind::Unbounded);
    assert_eq!(
        cam.field("roi").unwrap().ty.base,
        BaseType::Message(rosmsg::TypeName::new("sensor_msgs", "RegionOfInterest"))
    );
    let status = r.spec("diagnostic_msgs/DiagnosticStatus").unwrap();
    assert_eq!(
        status
            .constants
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>(),
        ["OK", "WARN", "ERROR", "STALE"]
    );
    assert_eq!(
        status.field("level").unwrap().ty.base,
        BaseType::Primitive(Primitive::Byte)
    );
    let tm = r.spec("metrocell_msgs/TrackerMeasurement").unwrap();
    assert_eq!(tm.constants.len(), 6);
    assert_eq!(
        tm.field("target_id").unwrap().ty.base,
        BaseType::String { bound: Some(64) }
    );
    assert!(tm.comment.starts_with("One laser-tracker observation"));
    let fd = r.spec("metrocell_msgs/FiducialDetectionArray").unwrap();
    assert_eq!(
        fd.field("detections").unwrap().ty.base,
        BaseType::Message(rosmsg::TypeName::new("metrocell_msgs", "FiducialDetection"))
    );
    let mp = r.spec("metrocell_msgs/MeasuredPoint").unwrap();
    assert_eq!(mp.constants[0].value, Value::String("tracker".into()));
    let header = r.spec("std_msgs/Header").unwrap();
    assert_eq!(
        header.field("stamp").unwrap().comment,
        "Two-integer timestamp that is expressed as seconds and nanoseconds."
    );
}
