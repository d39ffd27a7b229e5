//! The tracker's reading with an `instrument_drift`: the reading of a drifting instrument is the
//! reading at the moved pose, and the analytic Jacobian (the drift's columns through the pose)
//! matches central differences.

mod common;

use common::term;
use metrocell_model::{
    ForwardModel, MachineGeometry, MachineKinematics, ToolState, Workspace, TRACKER_ROWS,
};
use metrocell_physics::model::TermModel;
use metrocell_physics::Signals;
use nalgebra::{DMatrix, Isometry3, Vector3};

fn machine() -> MachineGeometry {
    MachineGeometry {
        kinematics: MachineKinematics::Cartesian("XFYZ".parse().unwrap()),
        travel: [[0.0, 0.8], [0.0, 0.5], [0.0, 0.4]],
        tool_offset: Vector3::zeros(),
    }
}

fn instruments(drift: bool) -> TermModel {
    let mut m = TermModel::default();
    m.push(term("id: tracker_pose\nparams: {tx: -1.2 m, ty: 0.3 m, tz: 0.5 m, alpha: 0.01 rad, beta: -0.02 rad, delta: 2.5 rad}\n")).unwrap();
    if drift {
        m.push(term("id: instrument_drift\noptions: {order: 2, span: [1000 s, 19000 s]}\nparams: {dx1: 3 um, dy1: -4 um, dz1: -9 um, rx1: 5 urad, ry1: -2 urad, rz1: 7 urad, dx2: 1 um, dy2: 2 um, dz2: -3 um, rx2: 1 urad, ry2: 1 urad, rz2: -4 urad}\n")).unwrap();
    }
    m
}

fn sighting(point: Vector3<f64>) -> ToolState {
    ToolState {
        nominal: Isometry3::identity(),
        truth: Isometry3::translation(point.x, point.y, point.z),
        d: Vector3::zeros(),
        workpiece: Vector3::zeros(),
    }
}

fn reading(model: &ForwardModel, p: &[f64], q: &[f64], t: f64) -> Vec<f64> {
    let mut s = Signals {
        time: Some(t),
        ..Default::default()
    };
    let kin = model.kinematic_truth(p).unwrap();
    let tool = model.tool_state(p, &kin, q, &mut s, None).unwrap();
    let y = model.tracker(p, &tool, &mut s).unwrap().measured_point();
    vec![y.x, y.y, y.z]
}

#[test]
fn a_drifting_instrument_reads_as_if_its_pose_had_moved() {
    let machine = machine();
    let none = TermModel::default();
    let with = instruments(true);
    let model = ForwardModel::new(&machine, &none, &with).unwrap();
    let p = model.params();
    let point = Vector3::new(0.3, 0.2, 0.1);
    let t = 19_000.0; // the span's end: P1 = 1, P2 = 1
    let mut s = Signals {
        time: Some(t),
        ..Default::default()
    };
    let drifting = model.tracker(&p, &sighting(point), &mut s).unwrap().point;
    // the same pose moved by Σ c_j·P_j(1) = c_1 + c_2, without a drift term
    let plain = instruments(false);
    let still = ForwardModel::new(&machine, &none, &plain).unwrap();
    let mut q = still.params();
    let moved = [
        3e-6 + 1e-6,
        -4e-6 + 2e-6,
        -9e-6 - 3e-6,
        5e-6 + 1e-6,
        -2e-6 + 1e-6,
        7e-6 - 4e-6,
    ];
    for k in 0..6 {
        q[k] += moved[k];
    }
    let want = still
        .tracker(
            &q,
            &sighting(point),
            &mut Signals {
                time: Some(t),
                ..Default::default()
            },
        )
        .unwrap()
        .point;
    assert!((drifting - want).norm() < 1e-15, "{drifting} vs {want}");
    // mid-span the linear part is zero and the quadratic one −c₂/2
    let mid = model
        .tracker(
            &p,
            &sighting(point),
            &mut Signals {
                time: Some(10_000.0),
                ..Default::default()
            },
        )
        .unwrap()
        .point;
    let mut q = still.params();
    let half = [-0.5e-6, -1e-6, 1.5e-6, -0.5e-6, -0.5e-6, 2e-6];
    for k in 0..6 {
        q[k] += half[k];
    }
    let want = still
        .tracker(
            &q,
            &sighting(point),
            &mut Signals {
                time: Some(10_000.0),
                ..Default::default()
            },
        )
        .unwrap()
        .point;
    assert!((mid - want).norm() < 1e-15);
}

#[test]
fn the_drift_columns_match_central_differences() {
    let machine = machine();
    let none = TermModel::default();
    let with = instruments(true);
    let model = ForwardModel::new(&machine, &none, &with).unwrap();
    let p = model.params();
    let kin = model.kinematic_truth(&p).unwrap();
    let names = model.param_names();
    for (q, t) in [
        ([0.1, 0.2, 0.3], 1500.0),
        ([0.7, 0.1, 0.05], 12_000.0),
        ([0.4, 0.45, 0.2], 18_500.0),
    ] {
        let mut j = DMatrix::zeros(TRACKER_ROWS, model.param_count());
        let mut work = Workspace::new(&model);
        let mut s = Signals {
            time: Some(t),
            ..Default::default()
        };
        model
            .tracker_jacobian(&p, &kin, &q, &mut s, &mut work, &mut j)
            .unwrap();
        for (c, name) in names.iter().enumerate() {
            let h = if name.starts_with("tracker_pose.t") {
                1e-6
            } else {
                1e-7
            };
            let (mut up, mut down) = (p.clone(), p.clone());
            up[c] += h;
            down[c] -= h;
            let (a, b) = (reading(&model, &up, &q, t), reading(&model, &down, &q, t));
            for r in 0..3 {
                let numeric = (a[r] - b[r]) / (2.0 * h);
                assert!(
                    (numeric - j[(r, c)]).abs() <= 1e-6 * j[(r, c)].abs().max(1.0) + 1e-9,
                    "{name} row {r} at t = {t}: analytic {} numeric {numeric}",
                    j[(r, c)]
                );
            }
        }
        // the drift has columns: a drift in z moves a reading
        let dz1 = names
            .iter()
            .position(|n| n == "instrument_drift.dz1")
            .unwrap();
        assert!(j.column(dz1).norm() > 0.1);
    }
}
