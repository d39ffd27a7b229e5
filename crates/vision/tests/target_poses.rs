//! `detect_targets` poses against the renderer's truth, in the ROS convention the module states:
//! marker pose = marker centre (OpenCV marker frame), board pose = inner corner (0, 0) with x along
//! the columns; covariance order (x, y, z, rot_x, rot_y, rot_z), errors within 4σ.
mod common;

use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, render_view, PoseInputs, RenderSettings, TargetFamily};
use nalgebra::{Point3, UnitQuaternion, Vector3};

fn check(p: &metrocell_vision::TargetPose, origin: Point3<f64>, x_axis: Vector3<f64>, what: &str) {
    for i in 0..3 {
        let s = p.covariance[7 * i].sqrt();
        let e = p.position[i] - origin[i];
        assert!(
            s > 0.0 && e.abs() < 4.0 * s + 2e-5,
            "{what}: position[{i}] error {e:.2e} m vs σ {s:.2e} m"
        );
    }
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        p.orientation[3],
        p.orientation[0],
        p.orientation[1],
        p.orientation[2],
    ));
    let ang = (q * Vector3::x()).angle(&x_axis);
    assert!(ang < 2e-3, "{what}: x axis off by {ang} rad");
}

#[test]
fn marker_and_board_poses_match_the_truth() {
    let cam = common::test_camera();
    let settings = RenderSettings {
        blur_sigma_px: 0.7,
        noise_sigma: 2.0,
        ..Default::default()
    };
    let params = DetectorParams::default();

    let pose = common::look_at_target([0.05, 0.05], 0.45, [0.3, -0.2, 0.4], [0.01, -0.01]);
    let view = render_view(&cam, &pose, &common::four_marker_target(), &settings).unwrap();
    let family = TargetFamily::parse("DICT_4X4_50", None, None).unwrap();
    let pi = PoseInputs {
        camera: &cam,
        marker_side: Some(0.04),
        fallback_sigma_px: 0.1,
        intrinsics_covariance: None,
    };
    let found = detect_targets(&view.image, &family, &params, Some(pi)).unwrap();
    assert_eq!(found.len(), 4);
    for t in &found {
        let k = [3, 7, 11, 42].iter().position(|&i| i == t.id).unwrap();
        // Target frame: y down as printed; marker frame: x right, y up → centre and +x of the target.
        let centre = pose
            * Point3::new(
                0.06 * (k % 2) as f64 + 0.02,
                0.06 * (k / 2) as f64 + 0.02,
                0.0,
            );
        check(
            t.pose.as_ref().unwrap(),
            centre,
            pose.rotation * Vector3::x(),
            &format!("marker {}", t.id),
        );
    }

    let pose = common::look_at_target([0.054, 0.042], 0.35, [-0.25, 0.3, 0.2], [0.0, 0.0]);
    let view = render_view(&cam, &pose, &common::checkerboard_target(), &settings).unwrap();
    let family = TargetFamily::parse("checkerboard", Some((8, 6)), Some(0.012)).unwrap();
    let found = detect_targets(&view.image, &family, &params, Some(pi)).unwrap();
    assert_eq!(found.len(), 1);
    let origin = pose * Point3::new(0.012, 0.012, 0.0);
    check(
        found[0].pose.as_ref().unwrap(),
        origin,
        pose.rotation * Vector3::x(),
        "board",
    );
}
