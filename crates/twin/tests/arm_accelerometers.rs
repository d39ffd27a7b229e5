//! `sensors.accelerometers` of a serial arm: each sensor's link looked up in the URDF; one fixed
//! to the root link (on a branch of its own) gets its rotation in the base frame and gives the
//! ground's gravity, one behind a movable joint is kept without it; bad input names the key.

use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;
use std::path::PathBuf;

use metrocell_twin::families::SerialArm;
use metrocell_twin::{CellModel, MachineKinematics};
use nalgebra::{Matrix3, Rotation3, Vector3};

/// base_link ─fixed→ base_imu (turned +90° about z); base_link ─prismatic→ top ─fixed→ top_imu;
/// top ─revolute→ tip: the arm's chain is base_link → tip, both IMUs are off it.
const URDF: &str = r#"<robot name="lifter">
  <link name="base_link"/><link name="base_imu"/><link name="top"/><link name="top_imu"/><link name="tip"/>
  <joint name="imu_mount" type="fixed"><parent link="base_link"/><child link="base_imu"/><origin xyz="0.1 0 0.05" rpy="0 0 1.5707963267948966"/></joint>
  <joint name="lift" type="prismatic"><parent link="base_link"/><child link="top"/><origin xyz="0 0 0.4" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="0" upper="0.6" effort="1" velocity="1"/></joint>
  <joint name="top_imu_mount" type="fixed"><parent link="top"/><child link="top_imu"/></joint>
  <joint name="pan" type="revolute"><parent link="top"/><child link="tip"/><origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"#;

/// A directory per model (the tests run in parallel) holding the URDF.
fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-twin-accel-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("lifter.urdf"), URDF).unwrap();
    d
}

fn model(machine: &str, accelerometers: &str) -> Result<CellModel, String> {
    let text = format!(
        "name: accel_test\nmachine:\n{machine}\nsensors:\n  accelerometers:\n{accelerometers}\n"
    );
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let d = dir(&N
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        .to_string());
    let m = CellModel::from_yaml_str_in(&text, "accel_model.yaml", &d).map_err(|e| e.to_string());
    let _ = std::fs::remove_dir_all(&d);
    m
}

const ARM: &str = "  family: serial_arm\n  serial_arm:\n    urdf: {path: lifter.urdf, root_link: base_link, tip_link: tip}";
const BOTH: &str = "    - {name: base, link: base_imu}\n    - {name: top, link: top_imu}";

fn arm(m: &CellModel) -> &SerialArm {
    match &m.machine.kinematics {
        MachineKinematics::SerialArm(a) => a,
        other => panic!("not an arm: {other:?}"),
    }
}

fn rz(angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), angle).into_inner()
}

#[test]
fn a_fixed_imu_turned_90_degrees_gives_rz90_and_the_grounds_gravity() {
    let m = model(ARM, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let a = arm(&m);
    assert_eq!(a.accelerometers.len(), 2);
    assert_eq!(
        (
            a.accelerometers[0].name.as_str(),
            a.accelerometers[0].link.as_str()
        ),
        ("base", "base_imu")
    );
    let r = a.accelerometers[0]
        .base_from_sensor
        .expect("base_imu is fixed to base_link");
    assert!((r - rz(FRAC_PI_2)).norm() < 1e-12, "{r}");
    // behind the prismatic `lift`: kept by name, no constant rotation
    assert_eq!(
        (
            a.accelerometers[1].name.as_str(),
            a.accelerometers[1].base_from_sensor
        ),
        ("top", None)
    );
    // ground pitched nose down by 15 mrad: gravity in the base g_B; at rest the sensor reads the
    // specific force −g_B in its own frame (x_sensor = y_base, y_sensor = −x_base)
    let g_b = Vector3::new(0.015f64.sin(), 0.0, -0.015f64.cos()) * 9.80665;
    let reading = rz(FRAC_PI_2).transpose() * -g_b;
    assert!(
        reading.y > 0.1 && reading.x.abs() < 1e-12,
        "the force along the base's −x is the sensor's +y: {reading}"
    );
    let mut acc = BTreeMap::new();
    acc.insert("top".to_string(), Vector3::new(1.0, 0.0, 9.0)); // not used: it moves
    assert_eq!(a.gravity_from(&acc), None);
    acc.insert("base".to_string(), reading * 1.01); // a scale error does not tilt it
    let g = a.gravity_from(&acc).unwrap();
    assert!((g - g_b).norm() < 1e-9, "{g} vs {g_b}");
}

#[test]
fn the_arms_base_pose_turns_the_sensor_into_the_chains_base_frame() {
    let placed = format!(
        "{ARM}\n    base: {{translation: [1 m, 2 m, 0 m], euler_xyz: [0 deg, 0 deg, 30 deg]}}"
    );
    let m = model(&placed, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let r = arm(&m).accelerometers[0].base_from_sensor.unwrap();
    assert!(
        (r - rz(FRAC_PI_2 + 30f64.to_radians())).norm() < 1e-12,
        "{r}"
    );
}

#[test]
fn bad_accelerometers_are_named_with_the_next_step() {
    let e = model(
        ARM,
        "    - {name: base, link: base_imu}\n    - {name: top, link: column_imu}",
    )
    .unwrap_err();
    assert!(
        e.contains("sensors.accelerometers[1].link")
            && e.contains("no link `column_imu`")
            && e.contains("base_link, base_imu, top, top_imu, tip"),
        "{e}"
    );
    let e = model(
        ARM,
        "    - {name: base, link: base_imu}\n    - {name: base, link: top_imu}",
    )
    .unwrap_err();
    assert!(
        e.contains("sensors.accelerometers[1].name") && e.contains("`base`"),
        "{e}"
    );
    let e = model(ARM, "    - {name: base, link: base_imu, frame: imu}").unwrap_err();
    assert!(e.contains("unknown field `frame`"), "{e}");
    let cartesian = "  family: cartesian\n  stacking: XFYZ\n  travel: {x: [0 m, 1 m], y: [0 m, 1 m], z: [0 m, 1 m]}";
    let e = model(cartesian, "    - {name: base, link: base_imu}").unwrap_err();
    assert!(
        e.contains("sensors.accelerometers") && e.contains("serial arm") && e.contains("cartesian"),
        "{e}"
    );
    let dh = "  family: serial_arm\n  serial_arm:\n    dh: {convention: standard, rows: [{a: 0.5 m, joint: revolute}]}";
    let e = model(dh, "    - {name: base, link: base_imu}").unwrap_err();
    assert!(
        e.contains("sensors.accelerometers") && e.contains("machine.serial_arm.urdf"),
        "{e}"
    );
}
