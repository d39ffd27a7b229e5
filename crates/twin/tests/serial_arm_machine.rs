//! Serial arms through the twin: the UR5 example's true tool point is the FK of its DH table with
//! the joint_offset and link_length errors applied (built here independently); tracker readings
//! agree with that FK within the stated noise; Cartesian pose targets are solved by IK, and an
//! unreachable one is named; a URDF arm is read relative to the cell file.

mod common;

use metrocell_kinematics::dh::{DhConvention, DhRow, DhTable};
use metrocell_kinematics::serial::SerialChain;
use metrocell_twin::{Cell, MachineKinematics, Sample, SampleTruth, Simulation};
use nalgebra::{Isometry3, Translation3, Vector3};
use std::f64::consts::FRAC_PI_2;

/// UR5 standard DH (Universal Robots' published parameters), `da2` added to a2, on the example's
/// 0.8 m pedestal with the 40 mm SMR offset, `offsets` added to the joint angles.
fn ur5(da2: f64, offsets: [f64; 6]) -> SerialChain {
    let rows = vec![
        DhRow::revolute(0.0, 0.089159, 0.0, FRAC_PI_2),
        DhRow::revolute(0.0, 0.0, -0.425 + da2, 0.0),
        DhRow::revolute(0.0, 0.0, -0.39225, 0.0),
        DhRow::revolute(0.0, 0.10915, 0.0, FRAC_PI_2),
        DhRow::revolute(0.0, 0.09465, 0.0, -FRAC_PI_2),
        DhRow::revolute(0.0, 0.0823, 0.0, 0.0),
    ];
    let mut c = DhTable::new(DhConvention::Standard, rows)
        .unwrap()
        .to_chain();
    c.base = Isometry3::from(Translation3::new(0.0, 0.0, 0.8));
    c.tool = Isometry3::from(Translation3::new(0.0, 0.0, 0.04));
    for (j, o) in c.joints.iter_mut().zip(offsets) {
        j.offset = o;
    }
    c
}

const OFFSETS: [f64; 6] = [0.0, 0.2e-3, -0.15e-3, 0.0, 0.0, 0.0];

#[test]
fn true_tool_point_is_fk_of_the_perturbed_dh_table() {
    let mut cell = Cell::from_path(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    cell.terms
        .terms
        .retain(|t| t.term.id() != metrocell_physics::TermId::ThermalGrowth);
    let MachineKinematics::SerialArm(arm) = &cell.machine.kinematics else {
        panic!("not an arm")
    };
    assert_eq!(
        arm.joint_names(),
        ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"]
    );
    let nominal = ur5(0.0, [0.0; 6]);
    let truth = ur5(0.3e-3, OFFSETS);
    let sim = Simulation::new(cell, 120.0, 5).unwrap();
    let (mut n, mut states, mut biggest) = (0, 0, 0.0f64);
    for (s, t) in sim.samples_with_truth() {
        match (s, t) {
            (_, SampleTruth::Tracker(tt)) => {
                let expected = truth.tool_pose(&tt.joints).unwrap().translation.vector;
                assert!(
                    (tt.tool_point - expected).norm() < 1e-12,
                    "{:?} vs {expected:?}",
                    tt.tool_point
                );
                let nom = nominal.tool_pose(&tt.joints).unwrap().translation.vector;
                assert!((tt.commanded - nom).norm() < 1e-12);
                biggest = biggest.max((expected - nom).norm());
                n += 1;
            }
            (Sample::MachineState(m), SampleTruth::MachineState { displacement }) => {
                assert_eq!(m.names.len(), 6);
                for k in 0..6 {
                    assert!(
                        (m.actual[k] - m.commanded[k] - OFFSETS[k]).abs() < 1e-15,
                        "actual = commanded + zero offset"
                    );
                }
                let nom = nominal.tool_pose(&m.commanded).unwrap().translation.vector;
                let tru = truth.tool_pose(&m.commanded).unwrap().translation.vector;
                assert!((displacement - (tru - nom)).norm() < 1e-12);
                states += 1;
            }
            _ => {}
        }
    }
    println!(
        "UR5 true - nominal tool point: up to {:.1} um",
        biggest * 1e6
    );
    assert_eq!((n, states), (1200, 2400));
    // 0.2 mrad at ~0.8 m reach and a 0.3 mm link: a few tenths of a millimetre
    assert!(
        biggest > 0.1e-3 && biggest < 1e-3,
        "largest error {biggest}"
    );
}

/// Range residuals of the tracker against the FK of the true chain, divided by the stated σ, are
/// standard normal (no warm-up, no station error in this run).
#[test]
fn tracker_readings_agree_with_fk_within_the_noise() {
    let mut cell = Cell::from_path(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    cell.tracker.as_mut().unwrap().warmup = None;
    let spec = cell.tracker.clone().unwrap();
    let truth_chain = cell.true_arm_chain().unwrap();
    let sim = Simulation::new(cell, 300.0, 11).unwrap();
    let mut z = Vec::new();
    let mut thermal_seen = 0.0f64;
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::Tracker(s), SampleTruth::Tracker(tt)) = (s, t) {
            let fk = truth_chain
                .tool_pose(&tt.joints)
                .unwrap()
                .translation
                .vector;
            // the pedestal's thermal growth is the only other effect: along +z
            let growth = tt.tool_point - fk;
            assert!(
                growth.x.abs() < 1e-13 && growth.y.abs() < 1e-13,
                "{growth:?}"
            );
            thermal_seen = thermal_seen.max(growth.z.abs());
            let x = spec.pose.to_instrument(&tt.tool_point);
            let sigma = spec.range_noise_constant + spec.range_noise_per_metre * x.norm();
            z.push((s.range - x.norm()) / sigma);
        }
    }
    let (m, sd) = common::mean_std(&z);
    println!("normalised range residuals: mean {m:.4}, std {sd:.4} over {} samples; pedestal growth up to {:.2} um", z.len(), thermal_seen * 1e6);
    assert_eq!(z.len(), 3000);
    assert!(m.abs() < 0.1, "mean of normalised range residuals {m}");
    assert!(
        (sd - 1.0).abs() < 0.1,
        "std of normalised range residuals {sd}"
    );
    assert!(thermal_seen > 1e-6, "pedestal growth seen: {thermal_seen}");
}

fn ur5_with_program(program: &str) -> Result<Cell, metrocell_twin::CellError> {
    let text = std::fs::read_to_string(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    let start = text.find("  joints:\n").unwrap();
    let end = text.find("  home_joints:").unwrap();
    let text = format!("{}{}{}", &text[..start], program, &text[end..]);
    Cell::from_yaml_str(&text, "poses.yaml")
}

#[test]
fn cartesian_pose_targets_are_solved_by_ik_and_unreachable_ones_are_named() {
    let cell = ur5_with_program("  poses:\n    - {position: [0.4 m, 0.2 m, 1.1 m]}\n    - {position: [-0.3 m, 0.35 m, 0.9 m], euler_xyz: [180 deg, 0 deg, 0 deg]}\n").unwrap();
    let chain = ur5(0.0, [0.0; 6]);
    let p0 = chain.tool_pose(cell.program.points[0].as_slice()).unwrap();
    assert!(
        (p0.translation.vector - Vector3::new(0.4, 0.2, 1.1)).norm() < 1e-9,
        "{:?}",
        p0.translation
    );
    let p1 = chain.tool_pose(cell.program.points[1].as_slice()).unwrap();
    assert!((p1.translation.vector - Vector3::new(-0.3, 0.35, 0.9)).norm() < 1e-9);
    // tool z axis down (Rx(180°))
    assert!((p1.rotation * Vector3::z() + Vector3::z()).norm() < 1e-8);

    let err = ur5_with_program(
        "  poses:\n    - {position: [0.4 m, 0.2 m, 1.1 m]}\n    - {position: [3 m, 0 m, 1 m]}\n",
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("program.poses[1]") && err.contains("did not converge") && err.contains("mm"),
        "{err}"
    );
}

/// A planar two-link URDF arm, referenced relative to the cell file: the tool point is
/// (0.5 cos q1 + (0.4 + l3) cos(q1 + q2 + δ2), …, 0.3) with the link_length and joint_offset terms.
#[test]
fn urdf_arm_is_read_relative_to_the_cell_file() {
    let dir = std::env::temp_dir().join(format!("metrocell-twin-urdf-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("robots")).unwrap();
    std::fs::write(dir.join("robots/two_link.urdf"), common::TWO_LINK_URDF).unwrap();
    let text = std::fs::read_to_string(common::cell_path("serial_arm_ur5.yaml")).unwrap();
    let m0 = text.find("  serial_arm:\n").unwrap();
    let m1 = text.find("\nsensors:").unwrap();
    let p0 = text.find("  joints:\n").unwrap();
    let p1 = text.find("  feed_rate:").unwrap();
    let t0 = text.find("\nterms:").unwrap();
    let arm = "  serial_arm:\n    urdf: {path: robots/two_link.urdf, root_link: base, tip_link: tip}\n    joint_limits: [[-170 deg, 170 deg], [-170 deg, 170 deg]]\n";
    let program = "  joints:\n    - [0 deg, 0 deg]\n    - [30 deg, 60 deg]\n";
    let terms = "\nterms:\n  - {id: joint_offset, options: {joints: 2}, params: {q1: 0, q2: 0.5 mrad}}\n  - {id: link_length, options: {links: 3}, params: {l1: 0, l2: 0, l3: 0.2 mm}}\n";
    let text = format!(
        "{}{}{}{}{}{}",
        &text[..m0],
        arm,
        &text[m1..p0],
        program,
        &text[p1..t0],
        terms
    );
    std::fs::write(dir.join("cell.yaml"), &text).unwrap();
    let mut cell = Cell::from_path(dir.join("cell.yaml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(cell.machine.joint_names(), ["shoulder", "elbow"]);
    cell.tracker = None;
    let sim = Simulation::new(cell, 60.0, 1).unwrap();
    let mut n = 0;
    for (s, t) in sim.samples_with_truth() {
        if let (Sample::MachineState(m), SampleTruth::MachineState { displacement }) = (s, t) {
            let (q1, q2) = (m.commanded[0], m.commanded[1]);
            let tip = |d2: f64, l3: f64| {
                Vector3::new(
                    0.5 * q1.cos() + (0.4 + l3) * (q1 + q2 + d2).cos(),
                    0.5 * q1.sin() + (0.4 + l3) * (q1 + q2 + d2).sin(),
                    0.3,
                )
            };
            assert!(
                (displacement - (tip(0.5e-3, 0.2e-3) - tip(0.0, 0.0))).norm() < 1e-12,
                "{displacement:?}"
            );
            n += 1;
        }
    }
    assert_eq!(n, 1200);
    // a URDF joint without an origin offset has no length to change
    std::fs::write(
        dir.join("robots/two_link.urdf"),
        common::TWO_LINK_URDF.replace(
            r#"<origin xyz="0 0 0.3" rpy="0 0 0"/>"#,
            r#"<origin xyz="0 0 0" rpy="0 0 0"/>"#,
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("cell.yaml"),
        text.replace("l1: 0, l2", "l1: 0.1 mm, l2"),
    )
    .unwrap();
    let err = Cell::from_path(dir.join("cell.yaml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("terms[1]")
            && err.contains("params.l1")
            && err.contains("`shoulder`")
            && err.contains("zero-length"),
        "{err}"
    );
    // the same file read from elsewhere names the resolved path
    let err = Cell::from_yaml_str(&text, "elsewhere.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("machine.serial_arm.urdf") && err.contains("robots/two_link.urdf"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The UR5 example with a camera on the flange: 30 mm off the tool point, turned 90° about the
/// tool z axis, and without the (translation-only) pedestal growth.
fn ur5_with_camera(extra_terms: &str) -> Cell {
    let text = common::edited_example("serial_arm_ur5.yaml", "  machine_state: {rate: 20 Hz}", "  camera: {mount: {translation: [30 mm, 0 mm, 20 mm], euler_xyz: [0 deg, 0 deg, 90 deg]}, delay: 1 s}\n  machine_state: {rate: 20 Hz}");
    let text = text.replacen(
        "  - id: thermal_growth\n",
        &format!("{extra_terms}  - id: thermal_growth\n"),
        1,
    );
    let mut cell = Cell::from_yaml_str(&text, "ur5_camera.yaml").unwrap();
    cell.terms
        .terms
        .retain(|t| t.term.id() != metrocell_physics::TermId::ThermalGrowth);
    cell
}

/// A camera on the flange turns with it: its true pose is the FK of the perturbed chain followed
/// by the mount, its nominal pose the nominal FK followed by the mount, and the joint offsets of
/// the parallel joints 2 and 3 (0.2 and −0.15 mrad) tilt it by their sum, 0.05 mrad.
#[test]
fn camera_on_the_flange_turns_with_the_true_joints() {
    let cell = ur5_with_camera("");
    let mount = cell.camera.as_ref().unwrap().mount.isometry();
    let (nominal, truth) = (ur5(0.0, [0.0; 6]), ur5(0.3e-3, OFFSETS));
    let sim = Simulation::new(cell, 120.0, 5).unwrap();
    let mut frames = 0;
    for (s, t) in sim.samples_with_truth() {
        let (Sample::CameraFrameRequest(r), SampleTruth::CameraFrameRequest { joints: q, .. }) =
            (s, t)
        else {
            continue;
        };
        let (n, c) = (
            nominal.tool_pose(&q).unwrap() * mount,
            truth.tool_pose(&q).unwrap() * mount,
        );
        assert!(
            (r.nominal_position - n.translation.vector).norm() < 1e-12
                && (r.nominal_rotation - n.rotation.to_rotation_matrix().into_inner()).norm()
                    < 1e-12,
            "q {q:?}"
        );
        assert!(
            (r.position - c.translation.vector).norm() < 1e-12
                && (r.rotation - c.rotation.to_rotation_matrix().into_inner()).norm() < 1e-12,
            "q {q:?}"
        );
        let tilt = nalgebra::Rotation3::from_matrix(&(r.nominal_rotation.transpose() * r.rotation))
            .angle();
        assert!((tilt - 0.05e-3).abs() < 1e-9, "tilt {tilt} rad");
        frames += 1;
    }
    assert!(frames >= 5, "{frames} frames");
}

/// `tool_offset` on an arm is an error of the tool vector on the flange: the true tool point is
/// the true tool pose applied to δ = (2, 0, −1) mm, R_tool(q)·δ away from the FK, not δ.
#[test]
fn tool_offset_on_an_arm_turns_with_the_flange() {
    let cell =
        ur5_with_camera("  - id: tool_offset\n    params: {dx: 2 mm, dy: 0 mm, dz: -1 mm}\n");
    let truth = ur5(0.3e-3, OFFSETS);
    let delta = Vector3::new(2e-3, 0.0, -1e-3);
    let sim = Simulation::new(cell, 120.0, 5).unwrap();
    let (mut n, mut turned) = (0, 0);
    for (_, t) in sim.samples_with_truth() {
        let SampleTruth::Tracker(tt) = t else {
            continue;
        };
        let pose = truth.tool_pose(&tt.joints).unwrap();
        let expected = (pose * nalgebra::Point3::from(delta)).coords;
        assert!(
            (tt.tool_point - expected).norm() < 1e-12,
            "{:?} vs {expected:?}",
            tt.tool_point
        );
        // a fixed cell-frame δ would miss by |R·δ − δ|
        if (pose.rotation * delta - delta).norm() > 1e-3 {
            turned += 1;
        }
        n += 1;
    }
    assert!(
        n == 1200 && turned > n / 2,
        "{turned} of {n} samples with the tool turned"
    );
}
