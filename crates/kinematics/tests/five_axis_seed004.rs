//! Seed 004 (five-axis prototype digest): fixtures K1, K2 and the B/C extension's FK/IK round trip.

use metrocell_kinematics::five_axis::{FiveAxisGeometry, FiveAxisJoints, ToolPose};
use metrocell_kinematics::KinematicsError;
use nalgebra::{Matrix4, Vector3};

const MM: f64 = 1e-3;

fn assert_homogeneous(t: &nalgebra::Isometry3<f64>, expected_mm: [[f64; 4]; 3], what: &str) {
    let m: Matrix4<f64> = t.to_homogeneous();
    for r in 0..3 {
        for c in 0..4 {
            let got = if c == 3 { m[(r, c)] / MM } else { m[(r, c)] };
            assert!(
                (got - expected_mm[r][c]).abs() < 1e-9,
                "{what}[{r}][{c}] = {got}, expected {}",
                expected_mm[r][c]
            );
        }
    }
}

#[test]
fn k1_k2_linear_axes_reproduce_reported_displacements() {
    // d0 = 0, d1 = 228, d2 = 308, d3 = 140 mm.
    let g = FiveAxisGeometry::new(0.0, 0.0);
    let f = g.linear_frames(228.0 * MM, 308.0 * MM, 140.0 * MM);
    assert_homogeneous(
        &f[0],
        [
            [0.0, -1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        "T0^1",
    );
    assert_homogeneous(
        &f[1],
        [
            [0.0, 0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0, 228.0],
            [0.0, 1.0, 0.0, 0.0],
        ],
        "T0^2",
    );
    assert_homogeneous(
        &f[2],
        [
            [0.0, -1.0, 0.0, 308.0],
            [0.0, 0.0, 1.0, 228.0],
            [-1.0, 0.0, 0.0, 0.0],
        ],
        "T0^3",
    );
    assert_homogeneous(
        &f[3],
        [
            [0.0, -1.0, 0.0, 308.0],
            [0.0, 0.0, 1.0, 228.0],
            [-1.0, 0.0, 0.0, -140.0],
        ],
        "T0^4",
    );
    let pose = g
        .forward(&FiveAxisJoints {
            d1: 228.0 * MM,
            d2: 308.0 * MM,
            d3: 140.0 * MM,
            b: 0.0,
            c: 0.0,
        })
        .unwrap();
    assert!(
        (pose.tip / MM - Vector3::new(308.0, 228.0, -140.0)).norm() < 1e-9,
        "{:?}",
        pose.tip / MM
    );
    assert!((pose.axis - Vector3::z()).norm() < 1e-15);
}

fn machine() -> FiveAxisGeometry {
    let mut g = FiveAxisGeometry::new(400.0 * MM, 80.0 * MM);
    g.b_pivot = Vector3::new(500.0, 400.0, 150.0) * MM;
    g.c_offset = Vector3::new(3.0, -2.0, 60.0) * MM;
    g.workpiece_offset = Vector3::new(10.0, 20.0, 25.0) * MM;
    g
}

#[test]
fn inverse_returns_both_branches_and_each_round_trips_to_1e_9_m() {
    let g = machine();
    let truth = FiveAxisJoints {
        d1: 300.0 * MM,
        d2: 450.0 * MM,
        d3: 120.0 * MM,
        b: 0.6,
        c: -2.2,
    };
    let pose = g.forward(&truth).unwrap();
    let sols = g.inverse(&pose, 0.0).unwrap();
    assert_eq!(sols.len(), 2);
    let mut found_truth = false;
    for s in &sols {
        assert!(!s.singular);
        let back = g.forward(&s.joints).unwrap();
        assert!((back.tip - pose.tip).norm() < 1e-9);
        assert!((back.axis - pose.axis).norm() < 1e-12);
        let j = s.joints;
        if (j.b - truth.b).abs() < 1e-12 && (j.c - truth.c).abs() < 1e-12 {
            assert!(
                (j.d1 - truth.d1).abs() < 1e-9
                    && (j.d2 - truth.d2).abs() < 1e-9
                    && (j.d3 - truth.d3).abs() < 1e-9
            );
            found_truth = true;
        }
    }
    assert!(found_truth, "{sols:?}");
    assert!(
        (sols[0].joints.b + sols[1].joints.b).abs() < 1e-12,
        "branches have opposite B"
    );
}

#[test]
fn b_zero_is_singular_and_uses_the_c_hint() {
    let g = machine();
    let pose = g
        .forward(&FiveAxisJoints {
            d1: 0.3,
            d2: 0.4,
            d3: 0.1,
            b: 0.0,
            c: 0.7,
        })
        .unwrap();
    let sols = g.inverse(&pose, 0.7).unwrap();
    assert_eq!(sols.len(), 1);
    assert!(sols[0].singular);
    let back = g.forward(&sols[0].joints).unwrap();
    assert!((back.tip - pose.tip).norm() < 1e-9);
    assert!((sols[0].joints.c - 0.7).abs() < 1e-15);
}

#[test]
fn b_limits_drop_branches_and_bad_input_is_an_error() {
    let mut g = machine();
    g.b_limits = (0.0, std::f64::consts::FRAC_PI_2);
    let pose = g
        .forward(&FiveAxisJoints {
            d1: 0.3,
            d2: 0.4,
            d3: 0.1,
            b: 0.5,
            c: 1.0,
        })
        .unwrap();
    let sols = g.inverse(&pose, 0.0).unwrap();
    assert_eq!(sols.len(), 1);
    assert!((sols[0].joints.b - 0.5).abs() < 1e-12);
    let upside_down = ToolPose {
        tip: Vector3::zeros(),
        axis: -Vector3::z(),
    };
    assert!(matches!(
        g.inverse(&upside_down, 0.0),
        Err(KinematicsError::NoSolution { .. })
    ));
    assert!(g
        .inverse(
            &ToolPose {
                tip: Vector3::zeros(),
                axis: Vector3::zeros()
            },
            0.0
        )
        .is_err());
}
