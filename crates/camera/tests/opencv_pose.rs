//! IPPE / planar pose against cv2.solvePnP(SOLVEPNP_IPPE) (+ solvePnPRefineLM) on the same corners.

mod common;
use common::*;
use metrocell_camera_model::{
    estimate_planar_pose, estimate_pose, ippe, undistort_to_normalized, CameraModel, Pose,
    UndistortCriteria,
};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

fn marker(side: f64) -> Vec<[f64; 3]> {
    let h = side / 2.0;
    vec![[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]]
}

fn pose_diff(a: &Pose, r: [f64; 3], t: [f64; 3]) -> (f64, f64) {
    let b = Pose::from_rvec_tvec(r, t);
    (
        (a.rotation.matrix() - b.rotation.matrix()).norm(),
        (a.translation - b.translation).norm(),
    )
}

#[test]
fn ippe_matches_opencv() {
    let cam: CameraModel = pinhole_truth();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let cases = [
        (
            Pose::from_rvec_tvec([0.5, -0.3, 0.2], [0.02, -0.01, 0.35]),
            marker(0.02),
        ),
        (
            Pose::from_rvec_tvec([-0.2, 0.6, -1.0], [-0.05, 0.03, 0.5]),
            marker(0.04),
        ),
        (
            Pose::from_rvec_tvec([0.1, 0.1, 2.5], [0.0, 0.0, 0.6]),
            board(),
        ),
    ];
    for (k, (truth, obj)) in cases.iter().enumerate() {
        let clean: Vec<[f64; 2]> = obj
            .iter()
            .map(|p| cam.project(truth, &Vector3::from(*p)).unwrap())
            .collect();
        // Noise-free: raw IPPE equals OpenCV's IPPE (and the truth).
        let normalized: Vec<[f64; 2]> = clean
            .iter()
            .map(|p| undistort_to_normalized(&cam, *p, UndistortCriteria::CONVERGED))
            .collect();
        let xy: Vec<[f64; 2]> = obj.iter().map(|p| [p[0], p[1]]).collect();
        let raw = ippe(&xy, &normalized).unwrap()[0];
        let cv = opencv(
            &json!({"op": "solvepnp_ippe", "camera": camera_json(&cam), "object_points": obj, "image_points": clean}),
        );
        let r = [f(&cv["rvec"][0]), f(&cv["rvec"][1]), f(&cv["rvec"][2])];
        let t = [f(&cv["tvec"][0]), f(&cv["tvec"][1]), f(&cv["tvec"][2])];
        let (dr, dt) = pose_diff(&raw, r, t);
        let (er, et) = pose_diff(&raw, truth.rvec(), truth.tvec());
        println!("case {k} noise-free: |ΔR|_F {dr:.2e}, |Δt| {dt:.2e} m vs OpenCV IPPE; vs truth {er:.2e}, {et:.2e}");
        assert!(
            er < 1e-10 && et < 1e-11,
            "raw IPPE misses the truth: {er} {et}"
        );
        // OpenCV undistorts inside solvePnP with its default 5 fixed-point iterations, which is not
        // converged near the corners of a strongly distorted image: agreement to 1e-7, not 1e-12.
        assert!(
            dr < 1e-7 && dt < 1e-8,
            "raw IPPE differs from OpenCV: {dr} {dt}"
        );
        // Noisy (σ = 0.3 px): our IPPE + LM equals OpenCV IPPE + solvePnPRefineLM.
        let noisy: Vec<[f64; 2]> = clean
            .iter()
            .map(|p| [p[0] + 0.3 * gauss(&mut rng), p[1] + 0.3 * gauss(&mut rng)])
            .collect();
        let est = estimate_planar_pose(&cam, obj, &noisy, 0.3).unwrap();
        let cv = opencv(
            &json!({"op": "solvepnp_ippe", "camera": camera_json(&cam), "object_points": obj, "image_points": noisy}),
        );
        let r = [
            f(&cv["rvec_lm"][0]),
            f(&cv["rvec_lm"][1]),
            f(&cv["rvec_lm"][2]),
        ];
        let t = [
            f(&cv["tvec_lm"][0]),
            f(&cv["tvec_lm"][1]),
            f(&cv["tvec_lm"][2]),
        ];
        let (dr, dt) = pose_diff(&est.pose, r, t);
        let sd = est.std_devs();
        println!("case {k} σ=0.3 px: |ΔR|_F {dr:.2e}, |Δt| {dt:.2e} m vs OpenCV IPPE+LM; predicted σ_t = ({:.2e}, {:.2e}, {:.2e}) m, σ_rot = ({:.2e}, {:.2e}, {:.2e}) rad",
            sd[0], sd[1], sd[2], sd[3], sd[4], sd[5]);
        // Far below the pose's own uncertainty.
        assert!(
            dt < 1e-3 * sd[2] && dr < 1e-3 * sd[3],
            "refined pose differs from OpenCV: {dr} {dt}"
        );
    }
}

#[test]
fn general_pnp_matches_opencv() {
    let cam: CameraModel = pinhole_truth();
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let truth = Pose::from_rvec_tvec([0.3, -0.5, 0.4], [0.03, 0.01, 0.7]);
    let cloud: Vec<[f64; 3]> = (0..30)
        .map(|i| {
            let a = i as f64;
            [
                0.12 * (a * 1.7).sin(),
                0.1 * (a * 0.9).cos(),
                0.08 * (a * 2.3).sin(),
            ]
        })
        .collect();
    let noisy: Vec<[f64; 2]> = cloud
        .iter()
        .map(|p| {
            let q = cam.project(&truth, &Vector3::from(*p)).unwrap();
            [q[0] + 0.3 * gauss(&mut rng), q[1] + 0.3 * gauss(&mut rng)]
        })
        .collect();
    let est = estimate_pose(&cam, &cloud, &noisy, 0.3).unwrap();
    let cv = opencv(
        &json!({"op": "solvepnp_sqpnp", "camera": camera_json(&cam), "object_points": cloud, "image_points": noisy}),
    );
    let r = [
        f(&cv["rvec_lm"][0]),
        f(&cv["rvec_lm"][1]),
        f(&cv["rvec_lm"][2]),
    ];
    let t = [
        f(&cv["tvec_lm"][0]),
        f(&cv["tvec_lm"][1]),
        f(&cv["tvec_lm"][2]),
    ];
    let (dr, dt) = pose_diff(&est.pose, r, t);
    let sd = est.std_devs();
    println!(
        "non-planar DLT+LM vs OpenCV SQPnP+LM: |ΔR|_F {dr:.2e}, |Δt| {dt:.2e} m; σ_t,z {:.2e} m",
        sd[2]
    );
    assert!(dt < 1e-3 * sd[2] && dr < 1e-3 * sd[3], "{dr} {dt}");
    // And the truth lies within the propagated uncertainty.
    for (a, s) in sd.iter().enumerate().take(3) {
        assert!((est.pose.translation[a] - truth.translation[a]).abs() < 4.0 * s);
    }
}
