//! An instrument moved between groups of readings (one `tracker_pose` per setup) and levelled
//! (`base_tilt` shared by every setup): each reading goes through its own setup's pose, after the
//! base's tilt, and the analytic Jacobian (the tilt's columns through every pose, the machine's
//! through R_poseᵀ·R_tilt) matches central differences.

mod common;

use common::term;
use std::sync::Arc;

use metrocell_model::{
    ForwardModel, MachineGeometry, MachineKinematics, ToolState, Workspace, TRACKER_ROWS,
};
use metrocell_physics::model::TermModel;
use metrocell_physics::Signals;
use nalgebra::{DMatrix, Isometry3, Rotation3, Vector3};

fn machine() -> MachineGeometry {
    MachineGeometry {
        kinematics: MachineKinematics::Cartesian("XFYZ".parse().unwrap()),
        travel: [[0.0, 0.8], [0.0, 0.5], [0.0, 0.4]],
        tool_offset: Vector3::zeros(),
    }
}

fn instruments() -> TermModel {
    let mut m = TermModel::default();
    m.push(term("id: tracker_pose\noptions: {setup: S1}\nparams: {tx: -1.2 m, ty: 0.3 m, tz: 0.5 m, alpha: 0.0001 rad, beta: -0.0002 rad, delta: 2.5 rad}\n")).unwrap();
    m.push(term("id: tracker_pose\noptions: {setup: S2}\nparams: {tx: 3.1 m, ty: -2.0 m, tz: 0.4 m, alpha: -0.0001 rad, beta: 0.00005 rad, delta: -0.7 rad}\n")).unwrap();
    m.push(term(
        "id: base_tilt\nparams: {roll: 0.008 rad, pitch: -0.015 rad}\n",
    ))
    .unwrap();
    m
}

fn at(setup: &str) -> Signals {
    Signals {
        setup: Some(Arc::from(setup)),
        ..Default::default()
    }
}

fn sighting(point: Vector3<f64>) -> ToolState {
    ToolState {
        nominal: Isometry3::identity(),
        truth: Isometry3::translation(point.x, point.y, point.z),
        d: Vector3::zeros(),
        workpiece: Vector3::zeros(),
    }
}

#[test]
fn each_setup_reads_through_its_own_pose_after_the_base_tilt() {
    let machine = machine();
    let none = TermModel::default();
    let terms = instruments();
    let model = ForwardModel::new(&machine, &none, &terms).unwrap();
    assert_eq!(
        model
            .param_names()
            .iter()
            .filter(|n| n.starts_with("tracker_pose[S2]."))
            .count(),
        6
    );
    let p = model.params();
    let point = Vector3::new(0.3, 0.2, 0.1);
    // by hand: levelled point, then x = Rᵀ(P − T) of the setup's pose (Euler XYZ)
    let tilt = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.008)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), -0.015);
    let level = tilt * point;
    for (setup, t, e) in [
        ("S1", Vector3::new(-1.2, 0.3, 0.5), [0.0001, -0.0002, 2.5]),
        ("S2", Vector3::new(3.1, -2.0, 0.4), [-0.0001, 0.00005, -0.7]),
    ] {
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), e[0])
            * Rotation3::from_axis_angle(&Vector3::y_axis(), e[1])
            * Rotation3::from_axis_angle(&Vector3::z_axis(), e[2]);
        let want = r.transpose() * (level - t);
        let got = model
            .tracker(&p, &sighting(point), &mut at(setup))
            .unwrap()
            .point;
        assert!((got - want).norm() < 1e-12, "{setup}: {got} vs {want}");
    }
    // a setup the model has no pose for is named, with the ones it has
    let err = model
        .tracker(&p, &sighting(point), &mut at("S9"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("tracker_pose[S9]") && err.contains("S1, S2"),
        "{err}"
    );
}

#[test]
fn the_jacobian_of_every_setup_matches_central_differences() {
    let machine = machine();
    let none = TermModel::default();
    let terms = instruments();
    let model = ForwardModel::new(&machine, &none, &terms).unwrap();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let names = model.param_names();
    let reading = |x: &[f64], q: &[f64], setup: &str| {
        let mut s = at(setup);
        let kin = model.kinematic_truth(x).unwrap();
        let tool = model.tool_state(x, &kin, q, &mut s, None).unwrap();
        model.tracker(x, &tool, &mut s).unwrap().measured_point()
    };
    for (q, setup) in [([0.1, 0.2, 0.3], "S1"), ([0.7, 0.1, 0.05], "S2")] {
        let mut j = DMatrix::zeros(TRACKER_ROWS, model.param_count());
        let mut work = Workspace::new(&model);
        let pred = model
            .tracker_jacobian(&p, &kin, &q, &mut at(setup), &mut work, &mut j)
            .unwrap();
        assert!((pred.measured_point() - reading(&p, &q, setup)).norm() < 1e-15);
        for (c, name) in names.iter().enumerate() {
            let h = 1e-7;
            let (mut up, mut down) = (p.clone(), p.clone());
            up[c] += h;
            down[c] -= h;
            let numeric = (reading(&up, &q, setup) - reading(&down, &q, setup)) / (2.0 * h);
            for r in 0..3 {
                assert!(
                    (numeric[r] - j[(r, c)]).abs() <= 1e-6 * j[(r, c)].abs().max(1.0),
                    "{setup} {name} row {r}: analytic {} numeric {}",
                    j[(r, c)],
                    numeric[r]
                );
            }
            // the other setup's pose does not move this reading; the tilt does
            let other = if setup == "S1" {
                "tracker_pose[S2]."
            } else {
                "tracker_pose[S1]."
            };
            if name.starts_with(other) {
                assert_eq!(j.column(c).norm(), 0.0, "{name}");
            }
            if name.starts_with("base_tilt.") {
                assert!(j.column(c).norm() > 0.1, "{name}");
            }
        }
    }
}
