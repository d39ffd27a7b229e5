//! Shared helpers for the integration tests: seeded synthetic checkerboard views and the OpenCV
//! reference script runner.
#![allow(dead_code)]

use metrocell_camera_model::{CameraModel, Distortion, Pose, View};
use nalgebra::{Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{json, Value};
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

pub fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

pub fn pinhole_truth() -> CameraModel {
    CameraModel::new(
        1280,
        960,
        1000.0,
        1003.0,
        642.3,
        477.8,
        Distortion::BrownConrady([-0.23, 0.09, 8e-4, -6e-4, -0.015]),
    )
    .unwrap()
}

pub fn fisheye_truth() -> CameraModel {
    CameraModel::new(
        1280,
        960,
        420.0,
        421.5,
        641.2,
        481.7,
        Distortion::Fisheye([0.04, -0.015, 0.006, -0.002]),
    )
    .unwrap()
}

/// 9×6 inner corners, 25 mm squares (metres), z = 0.
pub fn board() -> Vec<[f64; 3]> {
    let mut v = Vec::new();
    for j in 0..6 {
        for i in 0..9 {
            v.push([0.025 * i as f64, 0.025 * j as f64, 0.0]);
        }
    }
    v
}

/// `n` views with tilts up to ±35°, the whole board inside the image, noise σ px per coordinate.
pub fn synthetic_views(
    cam: &CameraModel,
    n: usize,
    sigma: f64,
    seed: u64,
    distance: (f64, f64),
) -> (Vec<View>, Vec<Pose>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let obj = board();
    let centre = Vector3::new(0.1, 0.0625, 0.0);
    let mut views = Vec::new();
    let mut poses = Vec::new();
    while views.len() < n {
        let rx = rng.random_range(-0.6..0.6);
        let ry = rng.random_range(-0.6..0.6);
        let rz = rng.random_range(-0.3..0.3);
        let r = Rotation3::from_euler_angles(rx, ry, rz);
        let z = rng.random_range(distance.0..distance.1);
        let ox = rng.random_range(-0.35..0.35) * z * cam.width as f64 / 2.0 / cam.fx;
        let oy = rng.random_range(-0.35..0.35) * z * cam.height as f64 / 2.0 / cam.fy;
        let t = Vector3::new(ox, oy, z) - r * centre;
        let pose = Pose {
            rotation: r,
            translation: t,
        };
        let px: Option<Vec<[f64; 2]>> = obj
            .iter()
            .map(|p| cam.project(&pose, &Vector3::from(*p)).ok())
            .collect();
        let Some(px) = px else { continue };
        let inside = px.iter().all(|p| {
            p[0] > 5.0
                && p[1] > 5.0
                && p[0] < cam.width as f64 - 6.0
                && p[1] < cam.height as f64 - 6.0
        });
        if !inside {
            continue;
        }
        let noisy = px
            .iter()
            .map(|p| {
                [
                    p[0] + sigma * gauss(&mut rng),
                    p[1] + sigma * gauss(&mut rng),
                ]
            })
            .collect();
        views.push(View {
            object_points: obj.clone(),
            image_points: noisy,
        });
        poses.push(pose);
    }
    (views, poses)
}

pub fn camera_json(cam: &CameraModel) -> Value {
    let (model, coeffs) = match cam.distortion {
        Distortion::BrownConrady(k) => ("plumb_bob", k.to_vec()),
        Distortion::Fisheye(k) => ("fisheye", k.to_vec()),
    };
    json!({"model": model, "fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy, "coeffs": coeffs})
}

/// The reference interpreter: METROCELL_PYTHON, else <workspace>/.venv/bin/python; never skip.
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let ws = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    if ws.exists() {
        return ws;
    }
    panic!("no Python reference interpreter: set METROCELL_PYTHON or run `tests/run` to create <workspace>/.venv (needs numpy, opencv-contrib-python-headless)");
}

/// Runs tests/py/opencv_reference.py on one request.
pub fn opencv(request: &Value) -> Value {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/py/opencv_reference.py");
    let mut child = Command::new(python())
        .arg(&script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the Python reference interpreter");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(request.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "opencv_reference.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON from opencv_reference.py")
}

pub fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

pub fn pairs(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| [f(&p[0]), f(&p[1])])
        .collect()
}

pub fn views_json(views: &[View]) -> Value {
    Value::Array(
        views
            .iter()
            .map(|v| json!({"object_points": v.object_points, "image_points": v.image_points}))
            .collect(),
    )
}
