//! Shared helpers for the integration tests: locating the reference Python (OpenCV) and temp dirs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Python interpreter holding OpenCV: `METROCELL_PYTHON`, else `<workspace>/.venv/bin/python`.
/// Panics (fails the test) with instructions when neither exists: never skip silently.
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let ws = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let venv = ws.join(".venv/bin/python");
    if venv.exists() {
        return venv;
    }
    panic!(
        "no reference Python: set METROCELL_PYTHON or run `tests/run` to create {} \
         (needs opencv-contrib-python-headless, numpy)",
        venv.display()
    );
}

/// Run a script under `tests/py/` and parse its stdout as JSON.
pub fn run_py(script: &str, args: &[&str]) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/py")
        .join(script);
    let out = Command::new(python())
        .arg(&path)
        .args(args)
        .output()
        .expect("spawn python");
    assert!(
        out.status.success(),
        "{} {:?} failed: {}",
        script,
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "bad JSON from {script}: {e}: {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// A fresh, empty directory under the system temp dir for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-vision-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create temp dir");
    d
}

use metrocell_vision::aruco::Dictionary;
use metrocell_vision::{CameraModel, Distortion, PlanarTarget, TargetItem};
use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion, Vector2, Vector3};

/// 800×600 camera with moderate barrel distortion.
pub fn test_camera() -> CameraModel {
    // Brown–Conrady (k1, k2, p1, p2, k3).
    let d = Distortion::BrownConrady([-0.12, 0.05, 0.0008, -0.0006, 0.0]);
    CameraModel::new(800, 600, 900.0, 905.0, 401.3, 297.8, d).unwrap()
}

/// Pose of a target whose centre (cx, cy) (m) sits `dist` m in front of the camera, tilted by
/// roll/pitch/yaw (rad) about the target's own axes, shifted sideways by (dx, dy) m.
pub fn look_at_target(
    center: [f64; 2],
    dist: f64,
    rpy: [f64; 3],
    shift: [f64; 2],
) -> Isometry3<f64> {
    let rot = UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    let c = Vector3::new(center[0], center[1], 0.0);
    let t = Vector3::new(shift[0], shift[1], dist) - rot * c;
    Isometry3::from_parts(Translation3::from(t), rot)
}

/// 2×2 grid of 40 mm DICT_4X4_50 markers (ids 3, 7, 11, 42) with 20 mm gaps; centre (0.05, 0.05).
pub fn four_marker_target() -> PlanarTarget {
    let d = Dictionary::predefined("DICT_4X4_50").unwrap();
    let ids = [3, 7, 11, 42];
    let items = ids
        .iter()
        .enumerate()
        .map(|(k, &id)| TargetItem::Marker {
            dictionary: d,
            id,
            top_left: [0.06 * (k % 2) as f64, 0.06 * (k / 2) as f64],
            side: 0.04,
            border_bits: 1,
        })
        .collect();
    PlanarTarget { items }
}

/// Poses used by the accuracy tests: frontal, tilted, strongly tilted and rotated, off-axis.
pub fn test_poses() -> Vec<Isometry3<f64>> {
    vec![
        look_at_target([0.05, 0.05], 0.45, [0.0, 0.0, 0.05], [0.0, 0.0]),
        look_at_target([0.05, 0.05], 0.40, [0.35, -0.2, 0.6], [0.02, -0.01]),
        look_at_target([0.05, 0.05], 0.50, [-0.5, 0.3, -1.2], [-0.06, 0.04]),
        look_at_target([0.05, 0.05], 0.35, [0.15, 0.45, 2.5], [0.03, 0.03]),
    ]
}

pub fn save_png(img: &image::GrayImage, path: &Path) {
    img.save(path)
        .unwrap_or_else(|e| panic!("write {}: {e}", path.display()));
}

/// Parse the `detect` output of aruco_reference.py for one image: (id, corners).
pub fn parse_detections(v: &serde_json::Value) -> Vec<(usize, [Point2<f64>; 4])> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let c = m["corners"].as_array().unwrap();
            let p = |k: usize| Point2::new(c[k][0].as_f64().unwrap(), c[k][1].as_f64().unwrap());
            (m["id"].as_u64().unwrap() as usize, [p(0), p(1), p(2), p(3)])
        })
        .collect()
}

/// Squared corner errors of detections matched to truth by id (each truth id must be found once).
pub fn corner_sq_errors(
    truth: &[metrocell_vision::MarkerTruth],
    found: &[(usize, [Point2<f64>; 4])],
    what: &str,
) -> Vec<f64> {
    let mut out = Vec::new();
    for t in truth {
        let m: Vec<_> = found.iter().filter(|f| f.0 == t.id).collect();
        assert_eq!(
            m.len(),
            1,
            "{what}: marker id {} found {} times",
            t.id,
            m.len()
        );
        for k in 0..4 {
            out.push((m[0].1[k] - t.corners[k]).norm_squared());
        }
    }
    out
}

pub fn rms(sq: &[f64]) -> f64 {
    (sq.iter().sum::<f64>() / sq.len() as f64).sqrt()
}

/// Checkerboard of 9×7 squares of 12 mm (8×6 inner corners); centre (0.054, 0.042).
pub fn checkerboard_target() -> PlanarTarget {
    PlanarTarget {
        items: vec![TargetItem::Checkerboard {
            top_left: [0.0, 0.0],
            square: 0.012,
            squares_x: 9,
            squares_y: 7,
            top_left_black: true,
        }],
    }
}

/// RMS distance of each found point to its nearest truth point (orderings differ between tools).
pub fn nearest_rms(truth: &[Point2<f64>], found: &[Point2<f64>]) -> f64 {
    let sq: Vec<f64> = found
        .iter()
        .map(|f| {
            truth
                .iter()
                .map(|t| (f - t).norm_squared())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    rms(&sq)
}

pub fn parse_points(v: &serde_json::Value) -> Option<Vec<Point2<f64>>> {
    v.as_array().map(|a| {
        a.iter()
            .map(|p| Point2::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
            .collect()
    })
}

/// Mean component of the corner error along the direction from each true corner towards its
/// marker's centre (positive = found corners sit inside the marker).
pub fn mean_inward_bias(
    truth: &[metrocell_vision::MarkerTruth],
    found: &[(usize, [Point2<f64>; 4])],
) -> f64 {
    let mut acc = Vec::new();
    for t in truth {
        if let Some(f) = found.iter().find(|f| f.0 == t.id) {
            let c = t.corners.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / 4.0;
            for k in 0..4 {
                let dir = (c - t.corners[k].coords).normalize();
                acc.push((f.1[k] - t.corners[k]).dot(&dir));
            }
        }
    }
    acc.iter().sum::<f64>() / acc.len() as f64
}
