//! metrocell-camera-model (`crates/camera`): camera models, calibration and planar pose estimation on point
//! correspondences (no image decoding here; detection lives in `metrocell-vision`), and raw frame
//! capture from V4L2 devices.
//!
//! | module | what it holds |
//! |---|---|
//! | [`distortion`] | Brown–Conrady (plumb_bob) and Kannala–Brandt fisheye (equidistant), OpenCV formulas, analytic derivatives |
//! | [`model`] | [`CameraModel`] = K + distortion; projection with Jacobians w.r.t. intrinsics, distortion, pose, point |
//! | [`pose`] | [`Pose`] (target → camera) and its 6-parameter perturbation |
//! | [`undistort`] | `undistortPoints` (OpenCV iterations) and `initUndistortRectifyMap` |
//! | [`homography`] | normalised DLT |
//! | [`zhang`] | closed-form intrinsics and per-view extrinsics from homographies |
//! | [`mod@calibrate`] | Zhang + Levenberg–Marquardt calibration with covariance and view rejection |
//! | [`pose_estimation`] | IPPE, DLT, LM refinement, 6×6 pose covariance (ROS PoseWithCovariance) |
//! | [`intrinsics_uncertainty`] | what the calibration's covariance adds to a pose's |
//! | [`camera_info`] | ROS camera_info YAML load/save |
//! | [`scale`] | object-plane mm/px scale from a known length (seed 002 eq. 4) |
//! | [`resolution`] | a calibration used at another resolution of the same field of view |
//! | [`v4l2`] | V4L2 streaming capture (raw ioctls, mmap) and GREY/YUYV → mono8/rgb8 |
//!
//! Conventions, stated once:
//! * Pixels: the centre of the top-left pixel is (0, 0), u right, v down (OpenCV).
//! * Camera frame: x right, y down, z forward (OpenCV). Poses map target → camera, see [`pose`].
//! * Pose perturbations and covariances: (x, y, z, rot_x, rot_y, rot_z) in the camera (parent)
//!   frame, rotation applied on the left: R ← exp(\[δθ\]×)·R — see [`pose`].
//! * Distortion coefficient order is OpenCV's, see [`distortion`].
//! * Units: whatever length unit the target points are given in (use metres in messages); pixels
//!   for image quantities.

// `!(x > 0.0)` is used on purpose: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod calibrate;
pub mod camera_info;
pub mod camera_info_msg;
pub mod distortion;
pub mod error;
pub mod homography;
pub mod intrinsics_uncertainty;
pub mod model;
pub mod pose;
pub mod pose_estimation;
pub mod resolution;
pub mod scale;
pub(crate) mod solver_bridge;
pub mod undistort;
pub mod v4l2;
pub mod zhang;

pub use calibrate::{
    calibrate, CalibratedView, Calibration, CalibrationFlags, LensModel, RejectedView,
    RejectionReason, View,
};
pub use camera_info::CameraInfo;
pub use camera_info_msg::camera_model_from_msg;
pub use distortion::Distortion;
pub use error::{CameraError, Result};
pub use intrinsics_uncertainty::pose_covariance_from_intrinsics;
pub use model::{CameraModel, Projection};
pub use pose::Pose;
pub use pose_estimation::{
    estimate_planar_pose, estimate_pose, ippe, refine_pose, PoseEstimate, RosPoseWithCovariance,
};
pub use scale::{mean_square_side_px, plane_scale, PlaneScale};
pub use undistort::{
    undistort_points, undistort_rectify_map, undistort_to_normalized, UndistortCriteria,
    UndistortMap,
};
