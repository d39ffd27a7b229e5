//! Pose estimation on synthetic data: exact recovery without noise, and the propagated 6×6
//! covariance against the empirical covariance of a Monte Carlo over corner noise.

use metrocell_camera_model::{estimate_planar_pose, estimate_pose, CameraModel, Distortion, Pose};
use nalgebra::{Matrix6, Vector3, Vector6};
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn camera() -> CameraModel {
    CameraModel::new(
        3840,
        2160,
        2900.0,
        2905.0,
        1921.5,
        1078.0,
        Distortion::BrownConrady([-0.12, 0.05, 4e-4, -3e-4, -0.01]),
    )
    .unwrap()
}

fn marker(side: f64) -> Vec<[f64; 3]> {
    let h = side / 2.0;
    vec![[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]]
}

fn project_all(cam: &CameraModel, pose: &Pose, obj: &[[f64; 3]]) -> Vec<[f64; 2]> {
    obj.iter()
        .map(|p| cam.project(pose, &Vector3::from(*p)).unwrap())
        .collect()
}

#[test]
fn exact_recovery_planar_and_nonplanar() {
    let cam = camera();
    let truth = Pose::from_rvec_tvec([0.4, -0.3, 0.2], [0.03, -0.02, 0.4]);
    let obj = marker(0.02);
    let img = project_all(&cam, &truth, &obj);
    let est = estimate_planar_pose(&cam, &obj, &img, 0.2).unwrap();
    assert!((est.pose.translation - truth.translation).norm() < 1e-10);
    assert!((est.pose.rotation.matrix() - truth.rotation.matrix()).norm() < 1e-10);
    // Non-planar cloud through the DLT path.
    let cloud: Vec<[f64; 3]> = (0..12)
        .map(|i| {
            let f = i as f64;
            [
                0.05 * (f * 1.3).sin(),
                0.04 * (f * 0.7).cos(),
                0.03 * (f * 2.1).sin(),
            ]
        })
        .collect();
    let img = project_all(&cam, &truth, &cloud);
    let est = estimate_pose(&cam, &cloud, &img, 0.2).unwrap();
    assert!(
        (est.pose.translation - truth.translation).norm() < 1e-10,
        "{:?}",
        est.pose.translation
    );
    assert!((est.pose.rotation.matrix() - truth.rotation.matrix()).norm() < 1e-10);
    // A tilted coplanar set (not on z = 0) goes through the plane-frame IPPE path.
    let tilt = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.5);
    let plane: Vec<[f64; 3]> = obj
        .iter()
        .chain(marker(0.01).iter())
        .map(|p| {
            let q = tilt * Vector3::from(*p) + Vector3::new(0.01, 0.02, 0.03);
            [q.x, q.y, q.z]
        })
        .collect();
    let img = project_all(&cam, &truth, &plane);
    let est = estimate_pose(&cam, &plane, &img, 0.2).unwrap();
    assert!((est.pose.translation - truth.translation).norm() < 1e-9);
    assert!((est.pose.rotation.matrix() - truth.rotation.matrix()).norm() < 1e-9);
}

#[test]
fn covariance_matches_monte_carlo() {
    let cam = camera();
    let truth = Pose::from_rvec_tvec([0.35, -0.25, 0.1], [0.02, -0.015, 0.35]);
    // 20 mm marker plus its inner 6×6 grid of corners (a checkerboard-like set), σ = 0.3 px.
    let mut obj = marker(0.02);
    for i in 0..6 {
        for j in 0..6 {
            obj.push([-0.0075 + 0.003 * i as f64, -0.0075 + 0.003 * j as f64, 0.0]);
        }
    }
    let sigma = 0.3;
    let clean = project_all(&cam, &truth, &obj);
    let predicted = estimate_planar_pose(&cam, &obj, &clean, sigma)
        .unwrap()
        .covariance;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let trials = 3000;
    let mut samples = Vec::with_capacity(trials);
    for _ in 0..trials {
        let noisy: Vec<[f64; 2]> = clean
            .iter()
            .map(|p| {
                [
                    p[0] + sigma * gauss(&mut rng),
                    p[1] + sigma * gauss(&mut rng),
                ]
            })
            .collect();
        let est = estimate_planar_pose(&cam, &obj, &noisy, sigma).unwrap();
        let dt = est.pose.translation - truth.translation;
        let dr = (est.pose.rotation * truth.rotation.inverse()).scaled_axis(); // left perturbation
        samples.push(Vector6::new(dt.x, dt.y, dt.z, dr.x, dr.y, dr.z));
    }
    let mean = samples.iter().fold(Vector6::zeros(), |a, s| a + s) / trials as f64;
    let mut emp = Matrix6::zeros();
    for s in &samples {
        let d = s - mean;
        emp += d * d.transpose();
    }
    emp /= (trials - 1) as f64;
    for i in 0..6 {
        let ratio = emp[(i, i)] / predicted[(i, i)];
        println!(
            "axis {i}: predicted σ {:.3e}, empirical σ {:.3e}, variance ratio {ratio:.3}",
            predicted[(i, i)].sqrt(),
            emp[(i, i)].sqrt()
        );
        assert!(
            (ratio - 1.0).abs() < 0.2,
            "axis {i}: empirical/predicted variance {ratio}"
        );
    }
    // Correlations too (the strong t–rotation couplings of a small planar target).
    for i in 0..6 {
        for j in 0..i {
            let rp = predicted[(i, j)] / (predicted[(i, i)] * predicted[(j, j)]).sqrt();
            let re = emp[(i, j)] / (emp[(i, i)] * emp[(j, j)]).sqrt();
            assert!(
                (rp - re).abs() < 0.1,
                "correlation ({i},{j}) predicted {rp:.3} empirical {re:.3}"
            );
        }
    }
}

#[test]
fn bad_pose_input_is_an_error_naming_the_problem() {
    use metrocell_camera_model::CameraError;
    let cam = camera();
    let obj = marker(0.02);
    let truth = Pose::from_rvec_tvec([0.1, 0.2, 0.0], [0.0, 0.0, 0.3]);
    let img = project_all(&cam, &truth, &obj);
    assert!(matches!(
        estimate_planar_pose(&cam, &obj, &img, 0.0),
        Err(CameraError::InvalidParameter { .. })
    ));
    assert!(matches!(
        estimate_planar_pose(&cam, &obj[..3], &img[..3], 0.2),
        Err(CameraError::TooFewPoints { got: 3, .. })
    ));
    assert!(matches!(
        estimate_planar_pose(&cam, &obj, &img[..3], 0.2),
        Err(CameraError::InvalidParameter { .. })
    ));
    let mut nan = img.clone();
    nan[2][1] = f64::NAN;
    assert!(matches!(
        estimate_planar_pose(&cam, &obj, &nan, 0.2),
        Err(CameraError::BadPoint { index: 2, .. })
    ));
    let mut lifted = obj.clone();
    lifted[1][2] = 0.005;
    assert!(matches!(
        estimate_planar_pose(&cam, &lifted, &img, 0.2),
        Err(CameraError::BadPoint { index: 1, .. })
    ));
    // Five non-coplanar points are too few for the DLT.
    let cloud: Vec<[f64; 3]> = vec![
        [0.0, 0.0, 0.0],
        [0.01, 0.0, 0.0],
        [0.0, 0.01, 0.0],
        [0.0, 0.0, 0.01],
        [0.01, 0.01, 0.01],
    ];
    let img5 = project_all(&cam, &truth, &cloud);
    assert!(matches!(
        estimate_pose(&cam, &cloud, &img5, 0.2),
        Err(CameraError::TooFewPoints { needed: 6, .. })
    ));
}

#[test]
fn ros_pose_with_covariance_layout() {
    let cam = camera();
    let truth = Pose::from_rvec_tvec([0.0, 0.0, std::f64::consts::FRAC_PI_2], [0.01, 0.02, 0.3]);
    let obj = marker(0.02);
    let img = project_all(&cam, &truth, &obj);
    let ros = estimate_planar_pose(&cam, &obj, &img, 0.25)
        .unwrap()
        .to_ros();
    assert!((ros.position[0] - 0.01).abs() < 1e-12 && (ros.position[2] - 0.3).abs() < 1e-12);
    // 90° about z: quaternion (0, 0, sin 45°, cos 45°), ROS (x, y, z, w) order.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert!((ros.orientation[2] - s).abs() < 1e-12 && (ros.orientation[3] - s).abs() < 1e-12);
    // Row-major, symmetric, positive diagonal; depth (z, index 14) is the worst-determined translation.
    for i in 0..6 {
        assert!(ros.covariance[7 * i] > 0.0);
        for j in 0..6 {
            assert!(
                (ros.covariance[6 * i + j] - ros.covariance[6 * j + i]).abs()
                    <= 1e-12 * ros.covariance[7 * i].max(ros.covariance[7 * j])
            );
        }
    }
    assert!(ros.covariance[14] > ros.covariance[0] && ros.covariance[14] > ros.covariance[7]);
}
