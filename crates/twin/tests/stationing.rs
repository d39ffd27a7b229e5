//! The stationing recording of `examples/cells/mobile_manipulator.yaml`: the plan (groups, roles,
//! setups), one row of samples per waypoint, readings that follow the twin's conventions
//! independently of the shared model's internals (the ground's tilt as gravity in the base and as
//! the levelled frame the instrument stands in, each setup's pose, the accelerometers' specific
//! force), determinism, and bad input named.

mod common;

use std::collections::BTreeMap;

use common::{cell_path, edited_example};
use metrocell_kinematics::transform::{rx, ry};
use metrocell_twin::{Cell, PointRole, Sample, SampleTruth, Simulation};
use nalgebra::Vector3;

const CELL: &str = "mobile_manipulator.yaml";

fn cell() -> Cell {
    Cell::from_path(cell_path(CELL)).unwrap()
}

fn tilted(roll: f64, pitch: f64) -> Cell {
    let mut c = cell();
    c.stationing.as_mut().unwrap().ground_tilt = [roll, pitch];
    c
}

fn run(cell: Cell, seed: u64) -> Vec<(Sample, SampleTruth)> {
    let duration = cell.natural_duration().unwrap();
    let sim = Simulation::new(cell, duration, seed).unwrap();
    let out: Vec<_> = sim.samples_with_truth().collect();
    assert!(sim.samples().error().is_none());
    out
}

#[test]
fn the_plan_has_groups_of_fit_and_check_points_each_measured_from_a_setup() {
    let c = cell();
    let st = c.stationing.as_ref().unwrap();
    // 3 levels × 4 configurations, 8 + 30 waypoints each
    assert_eq!(st.waypoints.len(), 12 * 38);
    for g in 0..12 {
        let group: Vec<_> = st.waypoints.iter().filter(|w| w.group == g).collect();
        assert_eq!(group.len(), 38);
        assert_eq!(
            group.iter().filter(|w| w.role == PointRole::Fit).count(),
            8,
            "group {g}"
        );
        assert!(
            group.iter().all(|w| w.setup == (g / 2) % 3),
            "group {g}: groups_per_setup 2 over S1..S3"
        );
        assert!(
            group.iter().all(|w| w.q[0] == [0.05, 0.30, 0.55][g / 4]),
            "group {g}: the column at its level"
        );
        assert_eq!(group[0].point_id, format!("G{:02}.001", g + 1));
    }
    // within the URDF's limits, the prism above min_tool_height
    let arm = match &c.machine.kinematics {
        metrocell_twin::MachineKinematics::SerialArm(a) => a,
        _ => unreachable!(),
    };
    for w in &st.waypoints {
        assert!(
            arm.chain.tool_pose(w.q.as_slice()).unwrap().translation.z >= 0.5,
            "{}",
            w.point_id
        );
    }
    // the plan is the program's own: the same whatever the noise seed, another with its seed
    assert_eq!(cell().stationing.unwrap().waypoints, st.waypoints);
    let other = Cell::from_yaml_str_in(
        &edited_example(CELL, "seed: 27", "seed: 28"),
        "other.yaml",
        std::path::Path::new(&cell_path("")),
    )
    .unwrap();
    assert_ne!(other.stationing.unwrap().waypoints[0].q, st.waypoints[0].q);
}

#[test]
fn each_waypoint_is_one_row_of_samples_with_its_stamp() {
    let samples = run(cell(), 1);
    let c = cell();
    let n = c.stationing.as_ref().unwrap().waypoints.len();
    let count = |f: &dyn Fn(&Sample) -> bool| samples.iter().filter(|(s, _)| f(s)).count();
    assert_eq!(count(&|s| matches!(s, Sample::StationPoint(_))), n);
    assert_eq!(count(&|s| matches!(s, Sample::MachineState(_))), n);
    assert_eq!(count(&|s| matches!(s, Sample::Acceleration(_))), 2 * n);
    assert_eq!(count(&|s| matches!(s, Sample::Temperature(_))), n);
    assert_eq!(
        samples.len(),
        5 * n,
        "nothing else: the periodic channels give way to the program"
    );
    // rows: machine state, point, base, tip, temperature — one stamp, times increasing
    for (k, row) in samples.chunks(5).enumerate() {
        let t = row[0].0.t();
        assert!(row.iter().all(|(s, _)| s.t() == t), "row {k}");
        let (Sample::MachineState(m), Sample::StationPoint(p)) = (&row[0].0, &row[1].0) else {
            panic!("row {k}: {:?}", row[0].0)
        };
        assert_eq!(
            m.commanded,
            c.stationing.as_ref().unwrap().waypoints[k].q.as_slice()
        );
        assert!(m.commanded_velocity.iter().all(|v| *v == 0.0));
        assert_eq!(
            p.point_id,
            c.stationing.as_ref().unwrap().waypoints[k].point_id
        );
        if k > 0 {
            assert!(t > samples[5 * k - 1].0.t());
        }
    }
}

/// The instrument's reading from the twin's conventions alone: the true tool point P (base
/// frame), levelled by Rx(roll)·Ry(pitch), seen from the setup's pose.
#[test]
fn readings_follow_the_ground_tilt_and_setup_conventions() {
    let (roll, pitch) = (0.004, -0.012);
    let c = tilted(roll, pitch);
    let poses = c.stationing.as_ref().unwrap().true_poses(5);
    let names: Vec<String> = c
        .stationing
        .as_ref()
        .unwrap()
        .placements
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let r_tilt = rx(roll) * ry(pitch);
    let g = r_tilt.transpose() * Vector3::new(0.0, 0.0, -9.80665);
    let samples = run(c, 5);
    let mut residuals = Vec::new();
    for (s, truth) in &samples {
        match (s, truth) {
            (
                Sample::StationPoint(p),
                SampleTruth::StationPoint {
                    tool_point,
                    levelled,
                    point,
                    ..
                },
            ) => {
                assert!((levelled - r_tilt * tool_point).norm() < 1e-12);
                let pose = &poses[names.iter().position(|n| **n == *p.setup).unwrap()];
                let expected = pose.rotation.transpose() * (r_tilt * tool_point - pose.translation);
                assert!(
                    (point - expected).norm() < 1e-9,
                    "{}: {point} vs {expected}",
                    p.point_id
                );
                residuals.push((p.measured - point) / 0.75e-3);
                assert_eq!(p.covariance[(0, 0)], 0.75e-3 * 0.75e-3);
            }
            (
                Sample::Acceleration(a),
                SampleTruth::Acceleration {
                    specific_force,
                    gravity,
                },
            ) => {
                assert!((gravity - g).norm() < 1e-12);
                // misalignment of mrad and bias of cm/s²: the reading is −g in the link's frame to that
                assert!(
                    (specific_force.norm() - 9.80665).abs() < 0.05,
                    "{}: {specific_force}",
                    a.sensor
                );
            }
            _ => {}
        }
    }
    // the noise: standard normal per axis
    let all: Vec<f64> = residuals.iter().flat_map(|r| [r.x, r.y, r.z]).collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let sd = (all.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (all.len() - 1) as f64).sqrt();
    assert!(
        mean.abs() < 0.1 && (sd - 1.0).abs() < 0.06,
        "mean {mean}, sd {sd} over {}",
        all.len()
    );
    // the setups' true tilts within a few tilt_sigma of level
    assert!(poses
        .iter()
        .all(|p| p.euler_xyz[0].abs() < 2e-4 && p.euler_xyz[1].abs() < 2e-4));
}

#[test]
fn the_base_accelerometer_gives_the_grounds_gravity_the_tip_one_turns_with_its_mount() {
    let (roll, pitch) = (0.0, 0.015);
    let c = tilted(roll, pitch);
    let arm = match &c.machine.kinematics {
        metrocell_twin::MachineKinematics::SerialArm(a) => a.clone(),
        _ => unreachable!(),
    };
    let st = c.stationing.clone().unwrap();
    let g = st.gravity();
    let mut clean = BTreeMap::new();
    let mut tip_readings = Vec::new();
    for (s, truth) in run(c, 2) {
        if let (Sample::Acceleration(a), SampleTruth::Acceleration { specific_force, .. }) =
            (s, truth)
        {
            if &*a.sensor == "base" {
                clean.insert("base".to_string(), specific_force);
            } else {
                tip_readings.push(specific_force);
            }
        }
    }
    // the model's gravity from the base sensor: the ground's, to its misalignment and bias/g (≈ 3 mrad)
    let from_sensor = arm.gravity_from(&clean).unwrap();
    let angle = from_sensor.angle(&g);
    assert!(
        angle > 5e-4 && angle < 5e-3,
        "the base sensor's mounting error moves the gravity by {angle} rad"
    );
    // pitched nose down by 15 mrad: gravity has a +x component in the base
    assert!(
        (g.x - 9.80665 * 0.015f64.sin()).abs() < 1e-9 && g.y.abs() < 1e-12,
        "{g}"
    );
    // the tip sensor, on the column's top (turned 90° about z), reads the same at every level
    assert!(tip_readings
        .windows(2)
        .all(|w| (w[0] - w[1]).norm() < 1e-12));
    // the specific force −g_B has −g·sin(pitch) along the base's x, which is the tip sensor's −y
    // (x_tip = y_base, y_tip = −x_base): +g·sin(pitch) on its y, to its misalignment and bias
    assert!(
        (tip_readings[0].y - 9.80665 * 0.015f64.sin()).abs() < 0.08
            && tip_readings[0].x.abs() < 0.08,
        "{}",
        tip_readings[0]
    );
}

#[test]
fn same_seed_same_samples_another_seed_other_noise() {
    let a = run(cell(), 7);
    let b = run(cell(), 7);
    assert_eq!(a, b);
    let c = run(cell(), 8);
    let point = |v: &[(Sample, SampleTruth)]| match &v[1].0 {
        Sample::StationPoint(p) => p.measured,
        other => panic!("{other:?}"),
    };
    assert_ne!(point(&a), point(&c));
}

#[test]
fn bad_stationing_input_is_named() {
    let base = std::path::Path::new(&cell_path("")).to_path_buf();
    let err = |from: &str, to: &str| {
        Cell::from_yaml_str_in(&edited_example(CELL, from, to), "bad.yaml", &base)
            .unwrap_err()
            .to_string()
    };
    let e = err("    point_noise: 0.75 mm       # σ per axis of its levelled frame (EDM, angles, prism centring)\n", "");
    assert!(
        e.contains("sensors.tracker.point_noise") && e.contains("0.75 mm"),
        "{e}"
    );
    let e = err("    levelled: true ", "    levelled: false ");
    assert!(e.contains("sensors.tracker.levelled"), "{e}");
    let e = err("    fit_points: 8\n", "    fit_points: 1\n");
    assert!(
        e.contains("program.stationing.fit_points") && e.contains("at least 2"),
        "{e}"
    );
    let e = err(
        "[0 deg, 40 deg, -70 deg, -30 deg, -90 deg, 0 deg]",
        "[0 deg, 40 deg, -70 deg]",
    );
    assert!(
        e.contains("program.stationing.configurations[1].joints")
            && e.contains("shoulder_pan, shoulder_lift, elbow, wrist_1, wrist_2, wrist_3"),
        "{e}"
    );
    let e = err("    min_tool_height: 0.5 m", "    min_tool_height: 5 m");
    assert!(
        e.contains("program.stationing.configurations[0]") && e.contains("min_tool_height"),
        "{e}"
    );
    let e = err("      link: column_tip_imu\n", "      link: forearm_link\n");
    assert!(
        e.contains("sensors.accelerometers[1].link") && e.contains("turned by joint"),
        "{e}"
    );
    let e = err(
        "  ground_tilt: {roll: 0 mrad, pitch: 0 mrad}",
        "  ground_tilt: {roll: 0 mrad, pitch: 15 deg}",
    );
    assert!(
        e.contains("environment.ground_tilt.pitch") && e.contains("±0.2 rad"),
        "{e}"
    );
    let e = err("    seed: 27 ", "    seed: 27\n    order: raster ");
    assert!(e.contains("unknown field `order`"), "{e}");
    // a cell without a stationing program takes no setups
    let text = std::fs::read_to_string(cell_path("serial_arm_ur5.yaml"))
        .unwrap()
        .replace(
            "    angular_noise: 3 urad\n",
            "    angular_noise: 3 urad\n    point_noise: 1 mm\n",
        );
    let e = Cell::from_yaml_str_in(&text, "bad.yaml", &base)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sensors.tracker.point_noise") && e.contains("stationing program"),
        "{e}"
    );
}
