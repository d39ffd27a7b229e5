//! The five_axis and serial_arm example cells load and simulate deterministically, and bad cells
//! of these families give errors naming the key and the allowed values.

mod common;

use common::{assert_mentions, error_of};
use metrocell_twin::{Cell, Sample, Simulation};

const EXAMPLES: [&str; 2] = ["five_axis_table.yaml", "serial_arm_ur5.yaml"];

fn stream(file: &str, seed: u64) -> Vec<String> {
    let cell = Cell::from_path(common::cell_path(file)).unwrap();
    let sim = Simulation::new(cell, 90.0, seed).unwrap();
    // Debug text compares NaN fields of dropped samples as equal, unlike f64 ==.
    sim.samples().map(|s| format!("{s:?}")).collect()
}

#[test]
fn examples_simulate_every_configured_stream_deterministically() {
    for f in EXAMPLES {
        let a = stream(f, 42);
        assert_eq!(a, stream(f, 42), "{f}: same seed, same stream");
        let b = stream(f, 43);
        assert_eq!(a.len(), b.len());
        assert!(
            a.iter().zip(&b).filter(|(x, y)| x != y).count() > a.len() / 4,
            "{f}: another seed changes the noise"
        );
        let cell = Cell::from_path(common::cell_path(f)).unwrap();
        let sim = Simulation::new(cell, 90.0, 42).unwrap();
        let (mut tracker, mut temps, mut states, mut frames) = (0, 0, 0, 0);
        let mut moved = false;
        let mut first: Option<Vec<f64>> = None;
        for s in sim.samples() {
            match s {
                Sample::Tracker(_) => tracker += 1,
                Sample::Temperature(_) => temps += 1,
                Sample::MachineState(m) => {
                    assert_eq!(m.names.len(), m.commanded.len());
                    match &first {
                        None => first = Some(m.commanded.clone()),
                        Some(q) => moved |= *q != m.commanded,
                    }
                    states += 1;
                }
                Sample::CameraFrameRequest(c) => {
                    assert!(c.position.iter().all(|v| v.is_finite()));
                    frames += 1;
                }
                Sample::ProbeHit(_) => panic!("{f}: no probe configured"),
                Sample::StationPoint(_) | Sample::Acceleration(_) => {
                    panic!("{f}: no stationing program")
                }
            }
        }
        assert_eq!((tracker, temps, states), (900, 180, 1800), "{f}");
        assert!(moved, "{f}: the program moves the joints");
        if f.starts_with("five") {
            assert!(frames >= 5, "{f}: one camera frame per dwell, got {frames}");
        }
    }
}

#[test]
fn five_axis_bad_cells() {
    let f = "five_axis_table.yaml";
    let msg = error_of(&common::edited_example(
        f,
        "  five_axis:                   # crates/kinematics FiveAxisGeometry\n",
        "  five_axis_geometry:\n",
    ));
    assert_mentions(
        &msg,
        &[
            "unknown field `five_axis_geometry`",
            "five_axis",
            "serial_arm",
        ],
    );
    let text = std::fs::read_to_string(common::cell_path(f)).unwrap();
    let (a, b) = (
        text.find("  five_axis:").unwrap(),
        text.find("  travel:").unwrap(),
    );
    let msg = error_of(&format!("{}{}", &text[..a], &text[b..]));
    assert_mentions(
        &msg,
        &[
            "machine.five_axis",
            "is required",
            "d0",
            "tool_length",
            "b_limits",
        ],
    );
    let msg = error_of(&common::edited_example(f, "d0: 600 mm", "d0: 600 K"));
    assert_mentions(&msg, &["machine.five_axis.d0", "`K`", "use `m`"]);
    let msg = error_of(&common::edited_example(
        f,
        "b_limits: [-90 deg, 90 deg]",
        "b_limits: [-90 mm, 90 deg]",
    ));
    assert_mentions(&msg, &["machine.five_axis.b_limits[0]", "use `rad`"]);
    let msg = error_of(&common::edited_example(f, "  - id: squareness\n    options: {pair: xy}\n    params: {s: 60 urad}", "  - id: joint_offset\n    options: {joints: 5}\n    params: {q1: 0, q2: 0, q3: 0, q4: 0, q5: 0}"));
    assert_mentions(
        &msg,
        &["terms[0]", "joint_offset", "machine.family: serial_arm"],
    );
    let msg = error_of(&common::edited_example(
        f,
        "    - {position: [0 mm, 0 mm, 50 mm]}  ",
        "    - {position: [0 mm, 0 mm, 50 mm], euler_xyz: [0, 0, 0]}  ",
    ));
    assert_mentions(
        &msg,
        &["program.poses[0].euler_xyz", "family: serial_arm", "axis"],
    );
    let msg = error_of(&common::edited_example(
        f,
        "  home_joints: [500 mm, 500 mm, 0 mm, 0 deg, 0 deg]",
        "  home_joints: [500 mm, 500 mm, 0 mm, 0 deg]",
    ));
    assert_mentions(&msg, &["program.home_joints", "has 4 values", "5 joints"]);
    let msg = error_of(&common::edited_example(
        f,
        "  home_joints: [500 mm, 500 mm, 0 mm, 0 deg, 0 deg]",
        "  home_joints: [500 mm, 500 mm, 0 mm, 120 deg, 0 deg]",
    ));
    assert_mentions(
        &msg,
        &["program.home", "b outside machine.five_axis.b_limits"],
    );
    let msg = error_of(&common::edited_example(
        f,
        "  home_joints: [500 mm, 500 mm, 0 mm, 0 deg, 0 deg]",
        "  home: [500 mm, 500 mm, 0 mm]",
    ));
    assert_mentions(
        &msg,
        &["program.home", "family: cartesian and delta", "home_joints"],
    );
    let msg = error_of(&common::edited_example(
        f,
        "  five_axis:                   # crates/kinematics FiveAxisGeometry\n",
        "  stacking: XFYZ\n  five_axis:\n",
    ));
    assert_mentions(
        &msg,
        &["machine.stacking", "family: cartesian", "machine.five_axis"],
    );
}

#[test]
fn serial_arm_bad_cells() {
    let f = "serial_arm_ur5.yaml";
    let msg = error_of(&common::edited_example(
        f,
        "convention: standard",
        "convention: craig",
    ));
    assert_mentions(&msg, &["craig", "standard", "modified"]);
    let msg = error_of(&common::edited_example(
        f,
        "        - {a: -0.425}",
        "        - {a: -0.425 rad}",
    ));
    assert_mentions(&msg, &["machine.serial_arm.dh.rows[1].a", "use `m`"]);
    let msg = error_of(&common::edited_example(
        f,
        "    dh:\n",
        "    urdf: {path: ur5.urdf, root_link: base, tip_link: tool0}\n    dh:\n",
    ));
    assert_mentions(&msg, &["machine.serial_arm", "exactly one of `dh`", "urdf"]);
    let msg = error_of(&common::edited_example(
        f,
        "    options: {joints: 6}",
        "    options: {joints: 5}",
    ));
    assert_mentions(&msg, &["terms[0]", "q6", "allowed parameters"]);
    let msg = error_of(&common::edited_example(f, "    options: {links: 6}\n    params: {l1: 0 m, l2: 0.3 mm, l3: 0 m, l4: 0 m, l5: 0 m, l6: 0 m}", "    options: {links: 7}\n    params: {l1: 0 m, l2: 0.3 mm, l3: 0 m, l4: 0 m, l5: 0 m, l6: 0 m, l7: 0 m}"));
    assert_mentions(
        &msg,
        &["terms[1]", "options.links", "is 7", "this arm has 6"],
    );
    let msg = error_of(&common::edited_example(f, "terms:                         # the arm's kinematic terms and displacements that read no axis\n", "terms:\n  - {id: positioning, options: {axis: x}, params: {c0: 0, c1: 1 um}}\n"));
    assert_mentions(
        &msg,
        &[
            "terms[0]",
            "positioning",
            "linear-axis signals",
            "joint_offset, link_length",
            "thermal_growth",
        ],
    );
    let msg = error_of(&common::edited_example(
        f,
        "    - [-60 deg, -60 deg, 60 deg, -90 deg, -80 deg, 20 deg]",
        "    - [-60 deg, -60 deg, 60 deg, -90 deg, -80 deg, 400 deg]",
    ));
    assert_mentions(
        &msg,
        &[
            "program point 4",
            "joint_6",
            "machine.serial_arm.joint_limits[5]",
        ],
    );
    let msg = error_of(&common::edited_example(
        f,
        "    - [30 deg, -100 deg, 80 deg, -70 deg, -90 deg, 10 deg]",
        "    - [30 deg, -100 deg, 80 deg, -70 deg, -90 deg, 10 mm]",
    ));
    assert_mentions(&msg, &["program.joints[1][5]", "use `rad`"]);
    let msg = error_of(&common::edited_example(
        f,
        "  joints:\n",
        "  points: [[0 m, 0 m, 0 m]]\n  joints:\n",
    ));
    assert_mentions(
        &msg,
        &[
            "program.points",
            "family: cartesian and delta",
            "`joints`",
            "`poses`",
        ],
    );
    let msg = error_of(&common::edited_example(f, "  machine_state: {rate: 20 Hz}", "  machine_state: {rate: 20 Hz}\n  probe: {directions: [[1, 0, 0]], hit_interval: 0.4 s, noise: 0.5 um}"));
    assert_mentions(&msg, &["sensors.probe", "cartesian and delta"]);
    let msg = error_of(&common::edited_example(
        f,
        "    base:",
        "    tool_offset: [0, 0, 0]\n    base:",
    ));
    assert_mentions(&msg, &["unknown field `tool_offset`", "joint_limits"]);
    let msg = error_of(&common::edited_example(
        f,
        "  family: serial_arm ",
        "  travel: {x: [0, 1], y: [0, 1], z: [0, 1]}\n  family: serial_arm ",
    ));
    assert_mentions(&msg, &["machine.travel", "serial_arm", "joint_limits"]);
}

#[test]
fn camera_intrinsics_are_read_and_checked() {
    let f = "five_axis_table.yaml";
    let cell = Cell::from_path(common::cell_path(f)).unwrap();
    let lens = cell.camera.as_ref().unwrap().intrinsics.unwrap();
    assert_eq!(
        (lens.width, lens.height, lens.fx, lens.cy),
        (1280, 1024, 1600.0, 511.5)
    );
    assert_eq!(
        lens.distortion,
        metrocell_camera_model::Distortion::BrownConrady([-0.08, 0.02, 0.0, 0.0, 0.0])
    );
    let msg = error_of(&common::edited_example(f, "cx: 639.5 px", "cx: 1639.5 px"));
    assert_mentions(
        &msg,
        &["sensors.camera.intrinsics.cx", "1639.5", "[0, 1280] px"],
    );
    let msg = error_of(&common::edited_example(f, "fx: 1600 px", "fx: 1600 mm"));
    assert_mentions(&msg, &["sensors.camera.intrinsics.fx", "`mm`", "use `px`"]);
    let msg = error_of(&common::edited_example(
        f,
        "distortion: [-0.08, 0.02, 0, 0, 0]",
        "distortion: [-0.08, 0.02, 0, 0, 0, 0.1]",
    ));
    assert_mentions(
        &msg,
        &["sensors.camera.intrinsics.distortion", "k1, k2, p1, p2, k3"],
    );
    // a fisheye lens: four coefficients
    let fisheye = common::edited_example(
        f,
        "distortion: [-0.08, 0.02, 0, 0, 0]",
        "distortion: [0.03, -0.01, 0.002]",
    )
    .replacen("model: plumb_bob", "model: equidistant", 1);
    let cell = Cell::from_yaml_str(&fisheye, "fisheye.yaml").unwrap();
    assert_eq!(
        cell.camera.unwrap().intrinsics.unwrap().distortion,
        metrocell_camera_model::Distortion::Fisheye([0.03, -0.01, 0.002, 0.0])
    );
    let msg = error_of(&fisheye.replace("[0.03, -0.01, 0.002]", "[0.03, -0.01, 0.002, 0, 0]"));
    assert_mentions(
        &msg,
        &[
            "sensors.camera.intrinsics.distortion",
            "at most 4",
            "k1, k2, k3, k4",
        ],
    );
    let msg = error_of(&fisheye.replace("model: equidistant", "model: rational_polynomial"));
    assert_mentions(
        &msg,
        &[
            "sensors.camera.intrinsics.model",
            "rational_polynomial",
            "plumb_bob",
            "equidistant",
        ],
    );
    let msg = error_of(&common::edited_example(
        f,
        "      width: 1280              # px",
        "      width: 1280
      skew: 0",
    ));
    assert_mentions(&msg, &["unknown field `skew`", "distortion"]);
}
