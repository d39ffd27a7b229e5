//! Seed 003 (frame-alignment patent digest): fixtures P1–P11 that need no noise model.

use metrocell_kinematics::frame_alignment::*;
use metrocell_kinematics::KinematicsError;
use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};

fn rz(deg: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), deg.to_radians()).into_inner()
}
fn ry(deg: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::y_axis(), deg.to_radians()).into_inner()
}
fn rx(deg: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), deg.to_radians()).into_inner()
}
fn round_to(v: f64, digits: i32) -> f64 {
    let s = 10f64.powi(digits);
    (v * s).round() / s
}
fn assert_vec(got: Vector3<f64>, expected: [f64; 3], digits: i32, what: &str) {
    for i in 0..3 {
        assert_eq!(
            round_to(got[i], digits),
            expected[i],
            "{what}[{i}] = {}",
            got[i]
        );
    }
}

// Lengths in these tests are in mm: every formula here is linear-homogeneous in length, so the SI API
// returns mm for mm inputs; angles are converted to radians.

#[test]
fn p1_pure_yaw() {
    let r = rz(5.0);
    let (v1, v2) = (Vector3::new(100.0, 0.0, 0.0), Vector3::new(0.0, 100.0, 0.0));
    let (c1, c2) = (
        camera_reading_of_translation(&r, &v1),
        camera_reading_of_translation(&r, &v2),
    );
    assert_vec(c1, [99.61947, -8.71557, 0.0], 5, "c1");
    assert_vec(c2, [8.71557, 99.61947, 0.0], 5, "c2");
    let est = rotation_from_two_moves(&v1, &v2, &c1, &c2).unwrap();
    assert_eq!(round_to(yaw(&est).to_degrees(), 3), 5.000);
    assert_eq!(round_to((est * c1).norm(), 9), 100.0);
    assert_eq!(round_to((est * c2).norm(), 9), 100.0);
}

#[test]
fn p2_general_rotation_recovered_by_triad_and_kabsch() {
    let r = rz(5.0) * ry(2.0) * rx(-3.0);
    let (v1, v2) = (Vector3::new(100.0, 0.0, 0.0), Vector3::new(0.0, 100.0, 0.0));
    let (c1, c2) = (
        camera_reading_of_translation(&r, &v1),
        camera_reading_of_translation(&r, &v2),
    );
    assert_vec(c1, [99.5588, -8.8856, 3.0158], 4, "c1");
    assert_vec(c2, [8.7103, 99.4670, 5.5174], 4, "c2");
    for est in [
        rotation_from_two_moves(&v1, &v2, &c1, &c2).unwrap(),
        rotation_kabsch(&[v1, v2], &[c1, c2]).unwrap(),
    ] {
        let err = Rotation3::from_matrix(&(est * r.transpose()))
            .angle()
            .to_degrees();
        assert_eq!(round_to(err, 3), 0.0);
        assert!(err < 1e-9);
    }
}

fn xy_stage(
    r: Vector2<f64>,
    angle_deg: f64,
    desp: Vector2<f64>,
) -> Result<Vector2<f64>, KinematicsError> {
    Ok(simulate_xy_alignment(r, angle_deg.to_radians(), desp, 1.0, 1)?[0].estimate)
}

#[test]
fn p3_xy_ratio_first_pass_and_exact_solve() {
    let z = Vector3::z_axis();
    let cam = Vector3::new(30.0, 0.0, 0.0);
    let th = 10f64.to_radians();
    let d1 = camera_displacement_of_rotation(&z, th, &Vector3::zeros(), &cam);
    let d2 = camera_displacement_of_rotation(&z, th, &Vector3::new(50.0, 50.0, 0.0), &cam);
    assert_vec(d1, [-0.45577, 5.20945, 0.0], 5, "CΔ1");
    assert_vec(d2, [8.98625, -2.71335, 0.0], 5, "CΔ2");
    let des = xy_misalignment(Vector2::new(50.0, 50.0), d1.xy(), d2.xy()).unwrap();
    assert_eq!(
        (round_to(des.x, 4), round_to(des.y, 4)),
        (-32.8763, -2.4135)
    );
    let exact = offset_from_rotation_about_z(th, d1.xy()).unwrap();
    assert_eq!(
        (round_to(exact.x, 3), round_to(exact.y, 3)),
        (30.000, 0.000)
    );
}

#[test]
fn p4_separate_axis_pairs_show_the_tan_half_angle_bias() {
    let r = Vector2::new(30.0, -20.0);
    let th = 10f64.to_radians();
    let cam = Vector3::new(r.x, r.y, 0.0);
    let z = Vector3::z_axis();
    let d1 = camera_displacement_of_rotation(&z, th, &Vector3::zeros(), &cam);
    let dx2 = camera_displacement_of_rotation(&z, th, &Vector3::new(50.0, 0.0, 0.0), &cam);
    let dy2 = camera_displacement_of_rotation(&z, th, &Vector3::new(0.0, 50.0, 0.0), &cam);
    let des_x = ratio_misalignment(50.0, d1.y, dx2.y, "Des_x").unwrap();
    let des_y = ratio_misalignment(50.0, d1.x, dy2.x, "Des_y").unwrap();
    assert_eq!(round_to(des_x, 4), -31.7498);
    assert_eq!(round_to(des_y, 4), 17.3753);
    let t = 5f64.to_radians().tan();
    assert!(
        (des_x - (-30.0 - 20.0 * t)).abs() < 1e-9,
        "Des_x − Des_y·tan5°"
    );
    assert!(
        (des_y - (20.0 + (-30.0) * t)).abs() < 1e-9,
        "Des_y + Des_x·tan5°"
    );
}

fn p5_aligned_offset() -> Vector2<f64> {
    let r = rz(5.0) * ry(2.0) * rx(-3.0);
    (r.transpose() * Vector3::new(40.0, -25.0, 60.0)).xy()
}

#[test]
fn p5_iteration_converges_as_the_digest_lists() {
    let r_tool = Vector3::new(40.0, -25.0, 60.0);
    // Camera readings are R_rcᵀ·v, so an offset given in the tool frame appears as R_rcᵀ·r_tool.
    let aligned = (rz(5.0) * ry(2.0) * rx(-3.0)).transpose() * r_tool;
    assert_vec(aligned, [35.5520, -31.5592, 59.7082], 4, "aligned r");
    let passes = simulate_xy_alignment(
        aligned.xy(),
        10f64.to_radians(),
        Vector2::new(50.0, 50.0),
        1.0,
        4,
    )
    .unwrap();
    assert_eq!(
        (
            round_to(passes[0].estimate.x, 5),
            round_to(passes[0].estimate.y, 5)
        ),
        (-41.98639, 26.16013)
    );
    let expected = [
        (-6.4344, -5.3991, 4),
        (0.09926, 0.08329, 5),
        (-0.001531, -0.001285, 6),
    ];
    for (k, (ex, ey, d)) in expected.iter().enumerate() {
        assert_eq!(
            (
                round_to(passes[k].residual.x, *d),
                round_to(passes[k].residual.y, *d)
            ),
            (*ex, *ey),
            "pass {k}"
        );
    }
    assert_eq!(
        (
            round_to(passes[3].residual.x, 6),
            round_to(passes[3].residual.y, 6)
        ),
        (2.4e-5, 2.0e-5)
    );
}

#[test]
fn p6_ratio_form_is_scale_invariant() {
    let a = simulate_xy_alignment(
        p5_aligned_offset(),
        10f64.to_radians(),
        Vector2::new(50.0, 50.0),
        1.05,
        1,
    )
    .unwrap()[0]
        .estimate;
    assert_eq!((round_to(a.x, 5), round_to(a.y, 5)), (-41.98639, 26.16013));
}

#[test]
fn p7_small_angle_first_pass() {
    let des = xy_stage(p5_aligned_offset(), 1.0, Vector2::new(50.0, 50.0)).unwrap();
    assert_eq!(
        (round_to(des.x, 4), round_to(des.y, 4)),
        (-36.1428, 30.9786)
    );
}

#[test]
fn p8_zero_offset_component_is_rejected_not_silently_zero() {
    let err = xy_stage(p5_aligned_offset(), 10.0, Vector2::new(50.0, 0.0)).unwrap_err();
    assert!(matches!(err, KinematicsError::Degenerate { .. }), "{err}");
    assert!(err.to_string().contains("Des_y"));
}

#[test]
fn p9_p10_z_offset_from_two_x_or_two_y_axes_is_exact() {
    let cam = Vector3::new(0.0, 0.0, 60.0);
    let th = 10f64.to_radians();
    let a2 = Vector3::new(0.0, 0.0, 50.0);
    let d1 = camera_displacement_of_rotation(&Vector3::x_axis(), th, &Vector3::zeros(), &cam);
    let d2 = camera_displacement_of_rotation(&Vector3::x_axis(), th, &a2, &cam);
    assert_vec(d1, [0.0, -10.41889, -0.91153], 5, "CΔ1 (x axes)");
    assert_vec(d2, [0.0, -1.73648, -0.15192], 5, "CΔ2 (x axes)");
    let dz = z_misalignment_from_x_axes(50.0, d1.y, d2.y).unwrap();
    assert_eq!(round_to(dz, 3), -60.000);
    assert!((dz + 60.0).abs() < 1e-9);
    let e1 = camera_displacement_of_rotation(&Vector3::y_axis(), th, &Vector3::zeros(), &cam);
    let e2 = camera_displacement_of_rotation(&Vector3::y_axis(), th, &a2, &cam);
    assert_eq!((round_to(e1.x, 5), round_to(e2.x, 5)), (10.41889, 1.73648));
    let dz = z_misalignment_from_y_axes(50.0, e1.x, e2.x).unwrap();
    assert!((dz + 60.0).abs() < 1e-9, "{dz}");
}

#[test]
fn p11_residual_xy_offset_biases_the_z_step() {
    let cam = Vector3::new(3.0, 2.0, 59.7082);
    let th = 10f64.to_radians();
    let d1 = camera_displacement_of_rotation(&Vector3::x_axis(), th, &Vector3::zeros(), &cam);
    let d2 = camera_displacement_of_rotation(
        &Vector3::x_axis(),
        th,
        &Vector3::new(0.0, 0.0, 50.0),
        &cam,
    );
    let dz = z_misalignment_from_x_axes(50.0, d1.y, d2.y).unwrap();
    assert_eq!(round_to(dz, 4), -59.8832);
    assert_eq!(round_to(dz + 59.7082, 3), -0.175);
}

#[test]
fn degenerate_rotation_inputs_are_errors() {
    let v = Vector3::new(1.0, 0.0, 0.0);
    assert!(rotation_from_two_moves(&v, &(v * 2.0), &v, &(v * 2.0)).is_err());
    assert!(rotation_kabsch(&[v, v * 3.0], &[v, v * 3.0]).is_err());
    assert!(rotation_kabsch(&[v], &[v, v]).is_err());
    assert!(offset_from_rotation_about_z(0.0, Vector2::new(1.0, 1.0)).is_err());
}
