//! Serial arms from DH (standard and modified) and URDF: FK, geometric Jacobian, DLS IK, DH parameter Jacobian.

use metrocell_kinematics::dh::{DhConvention, DhRow, DhTable};
use metrocell_kinematics::serial::{IkSettings, IkTarget, JointKind};
use metrocell_kinematics::urdf_chain::chain_from_urdf_str;
use metrocell_kinematics::KinematicsError;
use metrocell_solver::numeric_jacobian::{
    central_difference, max_relative_difference, steps_with_unit_floor, Order,
};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};
use std::f64::consts::FRAC_PI_2;

/// UR5 standard DH (Universal Robots published parameters, metres).
fn ur5() -> DhTable {
    let d = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
    let a = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
    let alpha = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];
    DhTable::new(
        DhConvention::Standard,
        (0..6)
            .map(|i| DhRow::revolute(0.0, d[i], a[i], alpha[i]))
            .collect(),
    )
    .unwrap()
}

/// The same arm in modified (Craig) DH: row i holds (α_{i−1}, a_{i−1}, θ_i, d_i); the last standard
/// `Tx(a_6)·Rx(α_6)` is the identity here.
fn ur5_modified() -> DhTable {
    let s = ur5();
    let rows = (0..6)
        .map(|i| {
            let (a_prev, alpha_prev) = if i == 0 {
                (0.0, 0.0)
            } else {
                (s.rows[i - 1].a, s.rows[i - 1].alpha)
            };
            DhRow::revolute(s.rows[i].theta, s.rows[i].d, a_prev, alpha_prev)
        })
        .collect();
    DhTable::new(DhConvention::Modified, rows).unwrap()
}

const Q: [f64; 6] = [0.3, -1.1, 1.4, -0.7, 0.9, 0.25];

#[test]
fn ur5_home_pose_is_the_known_one() {
    let p = ur5()
        .to_chain()
        .tool_pose(&[0.0; 6])
        .unwrap()
        .translation
        .vector;
    // x = a2 + a3, y = −(d4 + d6), z = d1 − d5
    let expected = Vector3::new(-0.81725, -0.19145, 0.089159 - 0.09465);
    assert!((p - expected).norm() < 1e-12, "{p:?}");
}

#[test]
fn standard_and_modified_dh_give_the_same_tool_pose() {
    let a = ur5().to_chain().tool_pose(&Q).unwrap();
    let b = ur5_modified().to_chain().tool_pose(&Q).unwrap();
    assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
    assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
}

#[test]
fn forward_returns_every_link_frame() {
    let pose = ur5().to_chain().forward(&Q).unwrap();
    assert_eq!(pose.links.len(), 6);
    // First frame: Rz(q1)·Tz(d1)·Rx(π/2) — origin on the base axis at height d1.
    assert!((pose.links[0].translation.vector - Vector3::new(0.0, 0.0, 0.089159)).norm() < 1e-15);
}

fn pose_vec(t: &Isometry3<f64>, reference: &Isometry3<f64>) -> DVector<f64> {
    // position and the rotation vector of t relative to the reference (base frame): small-angle coordinates.
    let r = (t.rotation * reference.rotation.inverse()).scaled_axis();
    DVector::from_row_slice(&[
        t.translation.x,
        t.translation.y,
        t.translation.z,
        r.x,
        r.y,
        r.z,
    ])
}

#[test]
fn geometric_jacobian_matches_central_differences() {
    let chain = ur5().to_chain();
    let t0 = chain.tool_pose(&Q).unwrap();
    let f = |q: &[f64]| chain.tool_pose(q).ok().map(|t| pose_vec(&t, &t0));
    let fd = central_difference(f, &Q, &steps_with_unit_floor(&Q, 1e-6), Order::Second).unwrap();
    let an = chain.jacobian(&Q).unwrap();
    let rel = max_relative_difference(&an, &fd);
    assert!(rel < 1e-6, "rel {rel:e}\n{an}\n{fd}");
}

#[test]
fn dh_parameter_jacobian_matches_central_differences_both_conventions() {
    for table in [ur5(), ur5_modified()] {
        let an = table.parameter_jacobian(&Q).unwrap();
        let n = table.rows.len();
        let t0 = *table.frames(&Q).unwrap().last().unwrap();
        let x0 = DVector::from_iterator(
            4 * n,
            table.rows.iter().flat_map(|r| [r.theta, r.d, r.a, r.alpha]),
        );
        let f = |x: &[f64]| {
            let rows = (0..n)
                .map(|i| DhRow {
                    theta: x[4 * i],
                    d: x[4 * i + 1],
                    a: x[4 * i + 2],
                    alpha: x[4 * i + 3],
                    kind: JointKind::Revolute,
                })
                .collect();
            let t = DhTable::new(table.convention, rows).ok()?;
            t.frames(&Q)
                .ok()
                .map(|fr| pose_vec(fr.last().unwrap(), &t0))
        };
        let fd = central_difference(
            f,
            x0.as_slice(),
            &steps_with_unit_floor(x0.as_slice(), 1e-6),
            Order::Second,
        )
        .unwrap();
        let rel = max_relative_difference(&an, &fd);
        assert!(rel < 1e-6, "{:?}: rel {rel:e}", table.convention);
    }
}

#[test]
fn dls_ik_reaches_pose_and_position_targets_to_1e_9() {
    let chain = ur5().to_chain();
    let target = chain.tool_pose(&Q).unwrap();
    let q0: Vec<f64> = Q.iter().map(|v| v + 0.2).collect();
    let rep = chain
        .inverse(&IkTarget::Pose(target), &q0, &IkSettings::default())
        .unwrap();
    assert!(rep.converged, "{rep:?}");
    let back = chain.tool_pose(rep.q.as_slice()).unwrap();
    assert!((back.translation.vector - target.translation.vector).norm() < 1e-9);
    assert!(back.rotation.angle_to(&target.rotation) < 1e-9);

    let p = Vector3::new(0.35, -0.25, 0.30);
    let rep = chain
        .inverse(
            &IkTarget::Position(p),
            &[0.0, -1.0, 1.0, -1.0, 1.0, 0.0],
            &IkSettings::default(),
        )
        .unwrap();
    assert!(rep.converged, "{rep:?}");
    assert!(
        (chain
            .tool_pose(rep.q.as_slice())
            .unwrap()
            .translation
            .vector
            - p)
            .norm()
            < 1e-9
    );
}

#[test]
fn dls_ik_reports_non_convergence_for_unreachable_target() {
    let chain = ur5().to_chain();
    let rep = chain
        .inverse(
            &IkTarget::Position(Vector3::new(3.0, 0.0, 0.0)),
            &Q,
            &IkSettings::default(),
        )
        .unwrap();
    assert!(!rep.converged);
    assert!(rep.position_error > 1.9, "{rep:?}");
}

const PLANAR_URDF: &str = r#"<robot name="planar">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="slider"/><link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="extend" type="prismatic"><parent link="l2"/><child link="slider"/>
    <origin xyz="0.3 0 0" rpy="0 0 1.5707963267948966"/><axis xyz="0 1 0"/><limit lower="-0.1" upper="0.1" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="slider"/><child link="tip"/><origin xyz="0 0 -0.05"/></joint>
</robot>"#;

#[test]
fn urdf_chain_matches_hand_computed_planar_arm() {
    let chain = chain_from_urdf_str(PLANAR_URDF, "base", "tip").unwrap();
    assert_eq!(chain.dof(), 3);
    assert_eq!(chain.variable_names(), vec!["shoulder", "elbow", "extend"]);
    let (q1, q2, s) = (0.4, -0.7, 0.05);
    let p = chain.tool_pose(&[q1, q2, s]).unwrap().translation.vector;
    // The slider frame is yawed +90° from l2, so its local +y is l2's −x: extension shortens the arm.
    let reach = 0.3 - s;
    let expected = Vector3::new(
        0.4 * q1.cos() + reach * (q1 + q2).cos(),
        0.4 * q1.sin() + reach * (q1 + q2).sin(),
        0.05,
    );
    assert!((p - expected).norm() < 1e-12, "{p:?} vs {expected:?}");
    let jac = chain.jacobian(&[q1, q2, s]).unwrap();
    let f = |q: &[f64]| {
        chain
            .tool_pose(q)
            .ok()
            .map(|t| DVector::from_row_slice(t.translation.vector.as_slice()))
    };
    let fd = central_difference(
        f,
        &[q1, q2, s],
        &steps_with_unit_floor(&[q1, q2, s], 1e-6),
        Order::Second,
    )
    .unwrap();
    let lin: DMatrix<f64> = jac.rows(0, 3).into_owned();
    assert!(max_relative_difference(&lin, &fd) < 1e-6);
}

#[test]
fn urdf_errors_name_the_problem() {
    assert!(matches!(
        chain_from_urdf_str(PLANAR_URDF, "base", "nowhere"),
        Err(KinematicsError::Urdf { .. })
    ));
    assert!(matches!(
        chain_from_urdf_str(PLANAR_URDF, "tip", "base"),
        Err(KinematicsError::Urdf { .. })
    ));
    assert!(matches!(
        chain_from_urdf_str("<robot", "a", "b"),
        Err(KinematicsError::Urdf { .. })
    ));
    let chain = chain_from_urdf_str(PLANAR_URDF, "base", "tip").unwrap();
    assert!(matches!(
        chain.forward(&[0.0, 0.0]),
        Err(KinematicsError::LengthMismatch { .. })
    ));
}

#[test]
fn urdf_origin_and_joint_offset_jacobians_match_central_differences() {
    let chain = chain_from_urdf_str(PLANAR_URDF, "base", "tip").unwrap();
    let q = [0.4, -0.7, 0.05];
    let an = chain.origin_translation_jacobian(&q).unwrap();
    let n = chain.joints.len();
    let x0 = DVector::from_iterator(
        3 * n,
        chain
            .joints
            .iter()
            .flat_map(|j| j.pre.translation.vector.iter().cloned().collect::<Vec<_>>()),
    );
    let f = |x: &[f64]| {
        let mut c = chain.clone();
        for (i, j) in c.joints.iter_mut().enumerate() {
            j.pre.translation.vector = Vector3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
        }
        c.tool_pose(&q)
            .ok()
            .map(|t| DVector::from_row_slice(t.translation.vector.as_slice()))
    };
    let fd = central_difference(
        f,
        x0.as_slice(),
        &steps_with_unit_floor(x0.as_slice(), 1e-6),
        Order::Second,
    )
    .unwrap();
    let lin: DMatrix<f64> = an.rows(0, 3).into_owned();
    assert!(max_relative_difference(&lin, &fd) < 1e-6);
    assert!(an.rows(3, 3).amax() == 0.0);

    let an = chain.joint_offset_jacobian(&q).unwrap();
    let movable: Vec<usize> = (0..n)
        .filter(|&i| chain.joints[i].kind != JointKind::Fixed)
        .collect();
    let off0 = DVector::zeros(movable.len());
    let f = |o: &[f64]| {
        let mut c = chain.clone();
        for (k, &i) in movable.iter().enumerate() {
            c.joints[i].offset = o[k];
        }
        c.tool_pose(&q)
            .ok()
            .map(|t| DVector::from_row_slice(t.translation.vector.as_slice()))
    };
    let fd = central_difference(
        f,
        off0.as_slice(),
        &steps_with_unit_floor(off0.as_slice(), 1e-6),
        Order::Second,
    )
    .unwrap();
    let lin: DMatrix<f64> = an.rows(0, 3).into_owned();
    assert!(max_relative_difference(&lin, &fd) < 1e-6);
}

/// A lifting column of two telescoping segments driven by one motor (the second a `<mimic>` of
/// the first), a revolute arm joint on top, inertials on the links.
const COLUMN_URDF: &str = r#"<robot name="column">
  <link name="base"><inertial><origin xyz="0 0 0.1"/><mass value="80"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="seg1"><inertial><origin xyz="0 0 0.3"/><mass value="12"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="seg2"><inertial><origin xyz="0 0 0.25"/><mass value="8"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="lower" type="prismatic"><parent link="base"/><child link="seg1"/><origin xyz="0 0 0.5"/><axis xyz="0 0 1"/><limit lower="0" upper="0.6" effort="1" velocity="1"/></joint>
  <joint name="upper" type="prismatic"><parent link="seg1"/><child link="seg2"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="0" upper="0.6" effort="1" velocity="1"/><mimic joint="lower" multiplier="1.0" offset="0.01"/></joint>
  <joint name="shoulder" type="revolute"><parent link="seg2"/><child link="arm"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/></joint>
</robot>"#;

#[test]
fn a_mimic_joint_follows_its_master_and_is_no_variable() {
    let chain = chain_from_urdf_str(COLUMN_URDF, "base", "tip").unwrap();
    assert_eq!(chain.dof(), 2, "the mimic takes no variable");
    assert_eq!(chain.variable_names(), vec!["lower", "shoulder"]);
    let (e, a) = (0.3, 0.7);
    let p = chain.tool_pose(&[e, a]).unwrap().translation.vector;
    // both segments extend by e (the upper one by 1·e + 0.01 m)
    let expected = Vector3::new(
        0.5 * a.cos(),
        0.5 * a.sin(),
        0.5 + e + 0.1 + (e + 0.01) + 0.2,
    );
    assert!((p - expected).norm() < 1e-12, "{p:?} vs {expected:?}");
    // the master's Jacobian column carries both segments: ∂z/∂e = 2
    let jac = chain.jacobian(&[e, a]).unwrap();
    let f = |q: &[f64]| {
        chain
            .tool_pose(q)
            .ok()
            .map(|t| DVector::from_row_slice(t.translation.vector.as_slice()))
    };
    let fd = central_difference(
        f,
        &[e, a],
        &steps_with_unit_floor(&[e, a], 1e-6),
        Order::Second,
    )
    .unwrap();
    assert!(max_relative_difference(&jac.rows(0, 3).into_owned(), &fd) < 1e-6);
    assert!((jac[(2, 0)] - 2.0).abs() < 1e-12);
    // limits and inertials are read
    let upper = &chain.joints[1];
    assert_eq!(upper.limits, Some([0.0, 0.6]));
    let inertial = upper.inertial.expect("seg2's inertial");
    assert_eq!(
        (inertial.mass, inertial.centre_of_mass),
        (8.0, Vector3::new(0.0, 0.0, 0.25))
    );
    assert!(
        chain.joints[3].inertial.is_none(),
        "the tip has no inertial"
    );
}

#[test]
fn a_mimic_of_a_joint_off_the_path_and_a_planar_joint_are_refused_by_name() {
    let off_path = COLUMN_URDF.replace(r#"<mimic joint="lower""#, r#"<mimic joint="gripper""#);
    let e = chain_from_urdf_str(&off_path, "base", "tip")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("upper") && e.contains("gripper") && e.contains("mimic"),
        "{e}"
    );
    let planar = COLUMN_URDF.replace(
        r#"name="shoulder" type="revolute""#,
        r#"name="shoulder" type="planar""#,
    );
    let e = chain_from_urdf_str(&planar, "base", "tip")
        .unwrap_err()
        .to_string();
    assert!(e.contains("shoulder") && e.contains("not supported"), "{e}");
}

/// The gravity torque on each variable is −∂V/∂q of the chain's potential energy
/// V = −Σ m_i·gᵀ·c_i (central differences), on the mimic column with a revolute joint on top and
/// the base tilted; the carried moment about the column's top is the lever of what it carries.
#[test]
fn gravity_torques_are_minus_the_potential_energys_gradient() {
    use metrocell_kinematics::gravity::{carried_moment, gravity_torques, placed_masses};
    let chain = chain_from_urdf_str(COLUMN_URDF, "base", "tip").unwrap();
    let g = Vector3::new(0.3, -0.2, -9.79);
    let potential = |q: &[f64]| -> f64 {
        -placed_masses(&chain, q)
            .unwrap()
            .iter()
            .map(|m| m.mass * g.dot(&m.centre))
            .sum::<f64>()
    };
    for q in [[0.1, 0.3], [0.45, -1.2], [0.0, 2.5]] {
        let tau = gravity_torques(&chain, &q, &g).unwrap();
        for k in 0..2 {
            let h = 1e-6;
            let (mut up, mut down) = (q, q);
            up[k] += h;
            down[k] -= h;
            let numeric = -(potential(&up) - potential(&down)) / (2.0 * h);
            assert!(
                (tau[k] - numeric).abs() < 1e-5 * numeric.abs().max(1.0),
                "q {q:?} variable {k}: {} vs {numeric}",
                tau[k]
            );
        }
        // the column lifts 12 + 8 + 5 kg through both segments (the mimic doubles it)
        assert!(
            (tau[0] - 2.0 * (8.0 + 5.0) * g.z - 12.0 * g.z).abs() < 1e-9,
            "{tau:?}"
        );
    }
    // what the upper segment carries: the arm's 5 kg, 0.2 m out along its own x at angle 0
    let q = [0.2, 0.0];
    let frames = chain.joint_frames(&q).unwrap();
    let top = frames[1].1.translation.vector;
    let m = carried_moment(&chain, &q, &g, 1, &top).unwrap();
    let lever = Vector3::new(0.2, 0.0, 0.2);
    assert!((m - lever.cross(&(g * 5.0))).norm() < 1e-9, "{m}");
}
