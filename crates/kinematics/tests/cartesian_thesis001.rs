//! Thesis digest 001: stacking orders, the kinematic identity with the tracker on the table, and first-order
//! agreement of the two chain versions.

use metrocell_kinematics::cartesian::{CartesianMachine, LinearAxis, StackingOrder};
use metrocell_kinematics::cartesian_error_chain::*;
use metrocell_kinematics::InstrumentPose;
use metrocell_kinematics::KinematicsError;
use nalgebra::Vector3;

const MM: f64 = 1e-3;

fn p3_tracker() -> InstrumentPose {
    // Thesis P3 tracker pose: (−863.527, 194.373, 677.782) mm, Euler XYZ (0.0339°, 0.0343°, 59.4652°).
    InstrumentPose::from_euler_xyz(
        Vector3::new(-863.527, 194.373, 677.782) * MM,
        [
            0.0339f64.to_radians(),
            0.0343f64.to_radians(),
            59.4652f64.to_radians(),
        ],
    )
}

fn all_orders() -> Vec<String> {
    let perms = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"];
    let mut v = Vec::new();
    for p in perms {
        for f in 0..=3 {
            let mut s: String = p.to_string();
            s.insert(f, 'F');
            v.push(s);
        }
    }
    v
}

#[test]
fn stacking_strings_parse_and_print_back() {
    let o: StackingOrder = "XFYZ".parse().unwrap();
    assert_eq!(o.workpiece_side, vec![LinearAxis::X]);
    assert_eq!(o.tool_side, vec![LinearAxis::Y, LinearAxis::Z]);
    assert_eq!(o.carriage_sign(LinearAxis::X), -1.0);
    let o: StackingOrder = "yxfz".parse().unwrap();
    assert_eq!(
        o.workpiece_side,
        vec![LinearAxis::X, LinearAxis::Y],
        "X sits on the bed, Y carries the part"
    );
    for s in all_orders() {
        assert_eq!(s.parse::<StackingOrder>().unwrap().to_string(), s);
    }
    for bad in ["XYZ", "XXFZ", "XFYW", "XFYZF", ""] {
        assert!(
            matches!(
                bad.parse::<StackingOrder>(),
                Err(KinematicsError::StackingOrder { .. })
            ),
            "{bad}"
        );
    }
}

#[test]
fn nominal_fk_ik_round_trip_every_order() {
    for s in all_orders() {
        let m = CartesianMachine::new(&s, Vector3::new(0.01, -0.02, -0.15)).unwrap();
        let q = Vector3::new(0.31, -0.12, 0.07);
        let p = m.forward(&q).unwrap();
        assert!((m.inverse(&p).unwrap() - q).norm() < 1e-15);
    }
}

#[test]
fn kinematic_identity_all_errors_zero_gives_tracker_frame_point_exactly() {
    let tracker = p3_tracker();
    let tool = Vector3::new(12.0, -7.0, -180.0) * MM;
    let errors = MachineErrors::default();
    for s in all_orders() {
        let order: StackingOrder = s.parse().unwrap();
        for q in [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(400.0, 400.0, 0.0) * MM,
            Vector3::new(123.4, 301.2, -55.0) * MM,
        ] {
            let got = tracker_point(&order, &q, &tool, &errors, &tracker).unwrap();
            let expected =
                tracker.rotation.try_inverse().unwrap() * (q + tool - tracker.translation);
            assert!(
                (got - expected).norm() < 1e-12,
                "{s} {q:?}: {got:?} vs {expected:?}"
            );
        }
    }
}

fn sample_errors(scale: f64) -> MachineErrors {
    let mut e = MachineErrors::default();
    e.axes[0] = AxisErrors {
        translation: Vector3::new(12.0, -8.0, 5.0) * 1e-6,
        rotation: Vector3::new(20.0, -15.0, 30.0) * 1e-6,
    };
    e.axes[1] = AxisErrors {
        translation: Vector3::new(-6.0, 9.0, 4.0) * 1e-6,
        rotation: Vector3::new(-25.0, 10.0, 18.0) * 1e-6,
    };
    e.axes[2] = AxisErrors {
        translation: Vector3::new(3.0, -5.0, 11.0) * 1e-6,
        rotation: Vector3::new(14.0, 22.0, -9.0) * 1e-6,
    };
    e.squareness = Squareness {
        xy: 40e-6,
        xz: -25e-6,
        yz: 15e-6,
    };
    for a in e.axes.iter_mut() {
        a.translation *= scale;
        a.rotation *= scale;
    }
    e.squareness.xy *= scale;
    e.squareness.xz *= scale;
    e.squareness.yz *= scale;
    e
}

#[test]
fn version_b_xfyz_matches_equation_3_5_written_out() {
    let order: StackingOrder = "XFYZ".parse().unwrap();
    let e = sample_errors(1.0);
    let tracker = p3_tracker();
    let (x, y, z) = (0.25, 0.31, -0.12);
    let tool = Vector3::new(0.0, 0.0, -0.2);
    let s = e.squareness;
    let xv = Vector3::new(-x, 0.0, 0.0) + e.axes[0].translation;
    let yv = Vector3::new(-y * s.xy, y, 0.0) + e.axes[1].translation;
    let zv = Vector3::new(-z * s.xz, -z * s.yz, z) + e.axes[2].translation;
    let r = |k: usize| small_angle_matrix(&e.axes[k].rotation);
    let inner =
        r(0).try_inverse().unwrap() * (r(1) * (r(2) * tool + zv) + yv - xv) - tracker.translation;
    let expected = tracker.rotation.try_inverse().unwrap() * inner;
    let got = tracker_point(&order, &Vector3::new(x, y, z), &tool, &e, &tracker).unwrap();
    assert!((got - expected).norm() < 1e-15);
}

#[test]
fn versions_a_and_b_agree_to_first_order() {
    let order: StackingOrder = "XFYZ".parse().unwrap();
    let tool = Vector3::new(0.02, -0.01, -0.2);
    let q = Vector3::new(0.35, 0.28, -0.15);
    let q_a = Vector3::new(-q.x, q.y, q.z);
    let diff = |scale: f64| {
        let e = sample_errors(scale);
        let b = workpiece_point(&order, &q, &tool, &e).unwrap();
        let a = version_a_xfyz(&q_a, &tool, &version_a_errors_from_b(&e)).unwrap();
        let first_order_effect = (b - (q + tool)).norm();
        ((a - b).norm(), first_order_effect)
    };
    let (d1, effect1) = diff(1.0);
    let (d10, _) = diff(10.0);
    // The error effect itself is tens of µm; the disagreement is sub-nanometre and scales as ε².
    assert!(effect1 > 10e-6, "effect {effect1}");
    assert!(d1 < 1e-9, "A−B = {d1}");
    let ratio = d10 / d1;
    assert!(
        (ratio - 100.0).abs() < 5.0,
        "second-order scaling ratio {ratio}"
    );
    // With all errors zero the two agree exactly.
    let (d0, _) = diff(0.0);
    assert!(d0 < 1e-15);
}

#[test]
fn bad_error_values_are_rejected_by_name() {
    let order: StackingOrder = "FXYZ".parse().unwrap();
    let mut e = MachineErrors::default();
    e.squareness.xz = f64::NAN;
    let err = workpiece_point(&order, &Vector3::zeros(), &Vector3::zeros(), &e).unwrap_err();
    assert!(err.to_string().contains("s_xz"), "{err}");
}

#[test]
fn error_jacobian_matches_hand_derived_first_order_terms_xfyz() {
    // At zero errors, XFYZ, identity tracker: p = R_X⁻¹(p_bed − D_X) with p_bed = Y + R_Y(Z + R_Z T).
    let order: StackingOrder = "XFYZ".parse().unwrap();
    let (x, y, z) = (0.3, 0.2, -0.1);
    let q = Vector3::new(x, y, z);
    let tool = Vector3::new(0.0, 0.0, -0.2);
    let j = error_jacobian(
        &order,
        &q,
        &tool,
        &MachineErrors::default(),
        &InstrumentPose::identity(),
    )
    .unwrap();
    let col = |name: &str| {
        j.column(MACHINE_ERROR_NAMES.iter().position(|n| *n == name).unwrap())
            .into_owned()
    };
    let close = |a: Vector3<f64>, b: Vector3<f64>| (a - b).norm() < 1e-6 * b.norm().max(1e-3);
    // Table positioning moves the part, so the tool point in the part frame moves the opposite way.
    assert!(close(col("delta_x(x)"), Vector3::new(-1.0, 0.0, 0.0)));
    assert!(close(col("delta_y(y)"), Vector3::new(0.0, 1.0, 0.0)));
    // Table yaw: −e_z × (p_bed − D_X), with p_bed − D_X = (x, y, z + t_z) at zero errors.
    let lever = Vector3::new(x, y, z + tool.z);
    assert!(close(col("eps_z(x)"), -Vector3::z().cross(&lever)));
    // Column pitch about x on Y: e_x × (Z + T) = e_x × (0, 0, z + t_z).
    assert!(close(
        col("eps_x(y)"),
        Vector3::x().cross(&Vector3::new(0.0, 0.0, z + tool.z))
    ));
    // Ram rotation acts only on the tool offset: e_y × T.
    assert!(close(col("eps_y(z)"), Vector3::y().cross(&tool)));
    // Squareness: Y travel tilts by −s_xy in x; Z travel by −s_xz, −s_yz.
    assert!(close(col("s_xy"), Vector3::new(-y, 0.0, 0.0)));
    assert!(close(col("s_yz"), Vector3::new(0.0, -z, 0.0)));
}

#[test]
fn stacking_order_changes_the_abbe_lever_of_an_angular_error() {
    // FXYZ: X on the bed carries Y, Z and the tool, so X yaw acts on (0, y, z + t_z) and not on x.
    let q = Vector3::new(0.3, 0.2, -0.1);
    let tool = Vector3::new(0.0, 0.0, -0.2);
    let idx = MACHINE_ERROR_NAMES
        .iter()
        .position(|n| *n == "eps_z(x)")
        .unwrap();
    let j = |s: &str| {
        error_jacobian(
            &s.parse().unwrap(),
            &q,
            &tool,
            &MachineErrors::default(),
            &InstrumentPose::identity(),
        )
        .unwrap()
        .column(idx)
        .into_owned()
    };
    let fxyz = j("FXYZ");
    let xfyz = j("XFYZ");
    assert!((fxyz - Vector3::z().cross(&Vector3::new(0.0, q.y, q.z + tool.z))).norm() < 1e-9);
    assert!((xfyz - (-Vector3::z().cross(&Vector3::new(q.x, q.y, q.z + tool.z)))).norm() < 1e-9);
    assert!((fxyz - xfyz).norm() > 0.1);
}
