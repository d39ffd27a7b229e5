//! The gravity terms of a serial arm (crates/physics `gravity`) through the forward model: a
//! compliant joint sags by k·τ, and every gravity term's analytic Jacobian column matches central
//! differences — on a lifting column of two telescoping segments (a `<mimic>` pair) with a
//! two-joint arm on top, the base tilted.

mod common;

use common::term;
use metrocell_kinematics::urdf_chain::chain_from_urdf_str;
use metrocell_model::{ForwardModel, MachineGeometry, MachineKinematics, SerialArm};
use metrocell_physics::model::TermModel;
use metrocell_physics::Signals;
use nalgebra::{DMatrix, Vector3};

const ROBOT: &str = r#"<robot name="column_arm">
  <link name="base"/>
  <link name="seg1"><inertial><origin xyz="0 0 0.3"/><mass value="12"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="seg2"><inertial><origin xyz="0 0 0.25"/><mass value="8"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper_arm"><inertial><origin xyz="0.3 0 0"/><mass value="9"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="forearm"><inertial><origin xyz="0.25 0 0"/><mass value="4"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="prism"/>
  <joint name="lower" type="prismatic"><parent link="base"/><child link="seg1"/><origin xyz="0.2 0 0.4"/><axis xyz="0 0 1"/><limit lower="0" upper="0.6" effort="1" velocity="1"/></joint>
  <joint name="upper" type="prismatic"><parent link="seg1"/><child link="seg2"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="0" upper="0.6" effort="1" velocity="1"/><mimic joint="lower" multiplier="1"/></joint>
  <joint name="shoulder" type="revolute"><parent link="seg2"/><child link="upper_arm"/><origin xyz="0 0 0.85" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper_arm"/><child link="forearm"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="tool" type="fixed"><parent link="forearm"/><child link="prism"/><origin xyz="0.5 0.05 0.1"/></joint>
</robot>"#;

fn machine() -> MachineGeometry {
    let chain = chain_from_urdf_str(ROBOT, "base", "prism").unwrap();
    let revolute = vec![false, true, true];
    MachineGeometry {
        kinematics: MachineKinematics::SerialArm(SerialArm {
            chain,
            dh: None,
            joint_limits: None,
            revolute,
            accelerometers: Vec::new(),
        }),
        travel: [[f64::NEG_INFINITY, f64::INFINITY]; 3],
        tool_offset: Vector3::zeros(),
    }
}

fn gravity_terms() -> TermModel {
    let mut m = TermModel::default();
    m.push(term("id: joint_compliance\noptions: {joints: [shoulder, elbow]}\nparams: {k_shoulder: 12e-6 rad/(N m), k_elbow: 8e-6 rad/(N m)}\n")).unwrap();
    m.push(term(
        "id: joint_backlash\noptions: {joints: [elbow]}\nparams: {b_elbow: 0.3 mrad}\n",
    ))
    .unwrap();
    m.push(term("id: column_bending\noptions: {joint: lower, overlaps: [0.8 m, 0.9 m], length: 0.95 m}\nparams: {foot: 2e-5 rad/(N m), pads: 2e-7 rad m^2/(N m), flexure: 3e-6 1/(N m^2)}\n")).unwrap();
    m.push(term(
        "id: link_thermal_expansion\noptions: {sensor: ambient}\nparams: {alpha: 23e-6 1/K}\n",
    ))
    .unwrap();
    m
}

fn signals() -> Signals {
    let mut s = Signals {
        gravity: Some(Vector3::new(0.05, -0.08, -9.806)),
        ..Default::default()
    };
    s.temperatures.insert("ambient".into(), 9.0);
    s
}

fn point(model: &ForwardModel, p: &[f64], q: &[f64]) -> Vector3<f64> {
    let kin = model.kinematic_truth(p).unwrap();
    model
        .tool_state(p, &kin, q, &mut signals(), None)
        .unwrap()
        .target()
}

#[test]
fn every_gravity_term_s_jacobian_matches_central_differences() {
    let machine = machine();
    let terms = gravity_terms();
    let none = TermModel::default();
    let model = ForwardModel::new(&machine, &terms, &none).unwrap();
    let p = model.params();
    let names = model.param_names();
    let kin = model.kinematic_truth(&p).unwrap();
    for q in [[0.1, 0.4, -0.9], [0.45, -0.7, 1.3], [0.3, 1.2, 0.2]] {
        let mut j = DMatrix::zeros(3, model.param_count());
        let at = model
            .tool_point_jacobian(&p, &kin, &q, &mut signals(), &mut j)
            .unwrap();
        assert!(
            (at - point(&model, &p, &q)).norm() < 1e-12,
            "the Jacobian's point is the model's"
        );
        for (c, name) in names.iter().enumerate() {
            let h = 1e-3 * p[c].abs().max(1e-9);
            let (mut up, mut down) = (p.clone(), p.clone());
            up[c] += h;
            down[c] -= h;
            let numeric = (point(&model, &up, &q) - point(&model, &down, &q)) / (2.0 * h);
            let analytic = j.fixed_view::<3, 1>(0, c).into_owned();
            // the torques and the column's pivots are taken at the commanded joints (first order)
            assert!(
                (numeric - analytic).norm() <= 2e-3 * numeric.norm() + 1e-9,
                "{name} at q {q:?}: analytic {analytic:?} numeric {numeric:?}"
            );
            assert!(
                numeric.norm() > 0.0 || name.starts_with("joint_backlash"),
                "{name} moves the tool point"
            );
        }
    }
}

#[test]
fn a_compliant_shoulder_sags_by_its_torque_times_its_compliance() {
    let machine = machine();
    let none = TermModel::default();
    let mut terms = TermModel::default();
    terms.push(term("id: joint_compliance\noptions: {joints: [shoulder]}\nparams: {k_shoulder: 1e-5 rad/(N m)}\n")).unwrap();
    let model = ForwardModel::new(&machine, &terms, &none).unwrap();
    let MachineKinematics::SerialArm(arm) = &machine.kinematics else {
        unreachable!()
    };
    let q = [0.2, 0.0, 0.0];
    let g = signals().gravity.unwrap();
    let tau = metrocell_kinematics::gravity::gravity_torques(&arm.chain, &q, &g).unwrap();
    // the arm straight out: it sags by Δθ = k·τ about the shoulder, the tool point by Δθ × r
    let sag =
        point(&model, &model.params(), &q) - arm.chain.tool_pose(&q).unwrap().translation.vector;
    let moved = arm
        .chain
        .tool_pose(&[q[0], q[1] + 1e-5 * tau[1], q[2]])
        .unwrap()
        .translation
        .vector
        - arm.chain.tool_pose(&q).unwrap().translation.vector;
    assert!((sag - moved).norm() < 1e-15, "{sag:?} vs {moved:?}");
    assert!(
        tau[1] < -50.0 && sag.z < -0.5e-3,
        "gravity pulls the arm down: τ {} N·m, sag {sag:?}",
        tau[1]
    );
}
