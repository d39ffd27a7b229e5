//! Projection, point undistortion and undistortion maps against OpenCV on identical inputs.

mod common;
use common::*;
use metrocell_camera_model::{
    undistort_points, undistort_rectify_map, CameraModel, Pose, UndistortCriteria,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

fn random_points(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            [
                rng.random_range(-0.35..0.35),
                rng.random_range(-0.28..0.28),
                rng.random_range(-0.05..0.05),
            ]
        })
        .collect()
}

fn check_projection(cam: &CameraModel) {
    let pose = Pose::from_rvec_tvec([0.12, -0.2, 0.05], [0.01, -0.02, 0.55]);
    let obj = random_points(3, 300);
    let ours: Vec<[f64; 2]> = obj
        .iter()
        .map(|p| cam.project(&pose, &Vector3::from(*p)).unwrap())
        .collect();
    let cv = opencv(
        &json!({"op": "project", "camera": camera_json(cam), "object_points": obj, "rvec": pose.rvec(), "tvec": pose.tvec()}),
    );
    let theirs = pairs(&cv["pixels"]);
    let worst = ours
        .iter()
        .zip(&theirs)
        .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
        .fold(0.0, f64::max);
    println!(
        "{:?} projection: max |Δ| = {worst:.2e} px (OpenCV {})",
        cam.distortion, cv["opencv_version"]
    );
    assert!(worst < 1e-6, "projection differs from OpenCV by {worst} px");
}

#[test]
fn projection_matches_opencv() {
    check_projection(&pinhole_truth());
    check_projection(&fisheye_truth());
}

fn check_undistort(cam: &CameraModel, criteria: UndistortCriteria, pixel_out: bool) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let px: Vec<[f64; 2]> = (0..400)
        .map(|_| {
            [
                rng.random_range(0.0..cam.width as f64),
                rng.random_range(0.0..cam.height as f64),
            ]
        })
        .collect();
    let rect = Rotation3::from_euler_angles(0.01, -0.02, 0.005).into_inner();
    let k = cam.k_matrix();
    let (r, p): (Option<&Matrix3<f64>>, Option<&Matrix3<f64>>) = if pixel_out {
        (Some(&rect), Some(&k))
    } else {
        (None, None)
    };
    let ours = undistort_points(cam, &px, r, p, criteria);
    let mut req = json!({"op": "undistort_points", "camera": camera_json(cam), "pixels": px,
        "criteria": {"max_iterations": criteria.max_iterations, "epsilon": criteria.epsilon}});
    if pixel_out {
        req["rectification"] = json!([
            [rect[(0, 0)], rect[(0, 1)], rect[(0, 2)]],
            [rect[(1, 0)], rect[(1, 1)], rect[(1, 2)]],
            [rect[(2, 0)], rect[(2, 1)], rect[(2, 2)]]
        ]);
        req["new_camera"] = json!([
            [k[(0, 0)], 0.0, k[(0, 2)]],
            [0.0, k[(1, 1)], k[(1, 2)]],
            [0.0, 0.0, 1.0]
        ]);
    }
    let theirs = pairs(&opencv(&req)["points"]);
    // Normalised outputs are compared in pixels (× fx).
    let scale = if pixel_out { 1.0 } else { cam.fx };
    let worst = ours
        .iter()
        .zip(&theirs)
        .map(|(a, b)| ((a[0] - b[0]).abs().max((a[1] - b[1]).abs())) * scale)
        .fold(0.0, f64::max);
    println!(
        "{:?} undistortPoints {criteria:?} pixel_out={pixel_out}: max |Δ| = {worst:.2e} px",
        cam.distortion
    );
    assert!(
        worst < 1e-6,
        "undistortPoints differs from OpenCV by {worst} px"
    );
}

#[test]
fn undistort_points_matches_opencv() {
    let pin = pinhole_truth();
    // OpenCV's own default (5 fixed-point iterations), replicated iteration for iteration.
    check_undistort(&pin, UndistortCriteria::OPENCV_PINHOLE, false);
    check_undistort(&pin, UndistortCriteria::CONVERGED, false);
    check_undistort(&pin, UndistortCriteria::CONVERGED, true);
    let fe = fisheye_truth();
    check_undistort(&fe, UndistortCriteria::OPENCV_FISHEYE, false);
    check_undistort(&fe, UndistortCriteria::OPENCV_FISHEYE, true);
}

#[test]
fn opencv_default_criteria_are_the_ones_replicated() {
    // cv2.undistortPoints / cv2.fisheye.undistortPoints called without criteria.
    for (cam, crit) in [
        (pinhole_truth(), UndistortCriteria::OPENCV_PINHOLE),
        (fisheye_truth(), UndistortCriteria::OPENCV_FISHEYE),
    ] {
        let px: Vec<[f64; 2]> = vec![[3.0, 4.0], [1270.0, 950.0], [640.0, 480.0], [100.0, 900.0]];
        let ours = undistort_points(&cam, &px, None, None, crit);
        let theirs = pairs(
            &opencv(&json!({"op": "undistort_points", "camera": camera_json(&cam), "pixels": px}))
                ["points"],
        );
        let conv = undistort_points(&cam, &px, None, None, UndistortCriteria::CONVERGED);
        let mut worst = 0.0f64;
        let mut gap = 0.0f64;
        for i in 0..px.len() {
            worst = worst.max(
                (ours[i][0] - theirs[i][0])
                    .abs()
                    .max((ours[i][1] - theirs[i][1]).abs())
                    * cam.fx,
            );
            gap = gap.max(
                (ours[i][0] - conv[i][0])
                    .abs()
                    .max((ours[i][1] - conv[i][1]).abs())
                    * cam.fx,
            );
        }
        println!("{:?}: default criteria max |Δ| vs OpenCV {worst:.2e} px; default vs converged {gap:.3} px", cam.distortion);
        assert!(worst < 1e-6);
    }
}

#[test]
fn undistort_maps_match_opencv() {
    for cam in [pinhole_truth(), fisheye_truth()] {
        // A reduced output image (new camera = K / 8) keeps the JSON small but covers the whole field.
        let mut p = cam.k_matrix() / 8.0;
        p[(2, 2)] = 1.0;
        let rect = Rotation3::from_euler_angles(0.02, 0.01, -0.01).into_inner();
        let size = (160u32, 120u32);
        let ours = undistort_rectify_map(&cam, Some(&rect), Some(&p), size).unwrap();
        let m = |x: &Matrix3<f64>| {
            json!([
                [x[(0, 0)], x[(0, 1)], x[(0, 2)]],
                [x[(1, 0)], x[(1, 1)], x[(1, 2)]],
                [x[(2, 0)], x[(2, 1)], x[(2, 2)]]
            ])
        };
        let cv = opencv(
            &json!({"op": "undistort_map", "camera": camera_json(&cam), "size": [size.0, size.1], "new_camera": m(&p), "rectification": m(&rect)}),
        );
        let (mx, my) = (
            cv["map_x"].as_array().unwrap(),
            cv["map_y"].as_array().unwrap(),
        );
        assert_eq!(mx.len(), ours.map_x.len());
        let mut worst = 0.0f64;
        for i in 0..mx.len() {
            worst = worst
                .max((ours.map_x[i] as f64 - f(&mx[i])).abs())
                .max((ours.map_y[i] as f64 - f(&my[i])).abs());
        }
        println!(
            "{:?} initUndistortRectifyMap: max |Δ| = {worst:.2e} px (f32 maps)",
            cam.distortion
        );
        assert!(worst < 5e-4, "map differs from OpenCV by {worst} px");
    }
}
