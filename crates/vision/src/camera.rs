//! The camera model of this crate is `metrocell_camera_model::CameraModel` (pinhole K + Brown–Conrady or
//! Kannala–Brandt fisheye distortion, OpenCV formulas); there is no second copy here. This module
//! only adapts it to the nalgebra isometry/point types the renderer and detectors use.
//!
//! Frames: camera x right, y down, z forward (OpenCV). An `Isometry3` pose maps target → camera:
//! X_cam = R·X_target + t.

pub use metrocell_camera_model::{CameraModel, Distortion};
use nalgebra::{Isometry3, Point2, Point3};

/// The camera crate's pose type for a nalgebra isometry (same meaning: target → camera).
pub fn pose_from_isometry(iso: &Isometry3<f64>) -> metrocell_camera_model::Pose {
    metrocell_camera_model::Pose {
        rotation: iso.rotation.to_rotation_matrix(),
        translation: iso.translation.vector,
    }
}

/// Project a target-frame point seen with `pose` (target → camera), distortion included.
/// None if the point is not in front of the camera.
pub fn project(
    camera: &CameraModel,
    pose: &Isometry3<f64>,
    p: &Point3<f64>,
) -> Option<Point2<f64>> {
    camera
        .project_camera_point(&(pose * p).coords)
        .ok()
        .map(|[u, v]| Point2::new(u, v))
}

/// Pixel → ideal normalised coordinates (x, y) = (X/Z, Y/Z); None outside the invertible region.
pub fn pixel_to_normalized(camera: &CameraModel, u: f64, v: f64) -> Option<(f64, f64)> {
    camera.pixel_to_normalized(u, v).map(|[x, y]| (x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_uses_opencv_pixel_convention() {
        let cam =
            CameraModel::new(640, 480, 1000.0, 1000.0, 319.5, 239.5, Distortion::none()).unwrap();
        let id = Isometry3::identity();
        let p = project(&cam, &id, &Point3::new(0.0, 0.0, 1.0)).unwrap();
        assert_eq!((p.x, p.y), (319.5, 239.5));
        let q = project(&cam, &id, &Point3::new(0.01, -0.02, 2.0)).unwrap();
        assert!((q.x - 324.5).abs() < 1e-12 && (q.y - 229.5).abs() < 1e-12);
        assert!(project(&cam, &id, &Point3::new(0.0, 0.0, -1.0)).is_none());
        let (x, y) = pixel_to_normalized(&cam, 324.5, 229.5).unwrap();
        assert!((x - 0.005).abs() < 1e-15 && (y + 0.01).abs() < 1e-15);
    }
}
