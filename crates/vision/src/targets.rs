//! One entry point for "find the configured kind of target in this image", shared by the
//! `metrocell-fiducial` node and `metrocell detect`: a [`TargetFamily`] parsed from a user string,
//! [`detect_targets`] returning [`Target`]s with corner covariances and, when the camera and the
//! target size are known, a pose with covariance.
//!
//! Pose convention (the ROS one, as geometry_msgs/PoseWithCovariance): the target frame expressed
//! in the camera frame (OpenCV camera: x right, y down, z forward); covariance 6×6 over
//! (x, y, z, rot_x, rot_y, rot_z) in m² / rad², rotations about the camera's axes applied on the left.
//! Target frames: markers use OpenCV's marker frame (centre, x right, y up, z out of the face);
//! a checkerboard's frame has its origin at inner corner (0, 0), x along the columns, y along the
//! rows, z = x × y, corners at (col·square, row·square, 0).

use crate::aruco::{detect_markers, DetectorParams, Dictionary};
use crate::camera::pose_from_isometry;
use crate::camera::CameraModel;
use crate::checkerboard::detect_checkerboard;
use crate::error::{invalid, Result, VisionError};
use crate::hole_grid::detect_hole_grid;
use crate::holes::HoleSearch;
use crate::marker_pose::estimate_marker_pose;
use image::GrayImage;
use nalgebra::{DMatrix, Matrix2, Point2, UnitQuaternion};

/// What to look for.
#[derive(Debug, Clone)]
pub enum TargetFamily {
    /// Square markers of an OpenCV predefined dictionary (ArUco and AprilTag dictionaries).
    Markers(Dictionary),
    /// Inner corners of a cols × rows checkerboard with squares of `square` metres.
    Checkerboard {
        cols: usize,
        rows: usize,
        square: f64,
    },
    /// Drilled-hole plate (seed 000, [`crate::hole_grid`]): a checkerboard with `cols` × `rows`
    /// inner corners, i.e. (cols + 1) × (rows + 1) squares, a hole at every square's centre.
    /// One target per measured hole: id = cell (row-major over squares), one point = the hole
    /// centre with its covariance, no pose; cells whose hole is rejected are left out.
    DrilledHoles { cols: usize, rows: usize },
}

impl TargetFamily {
    /// Parse a family name: an OpenCV dictionary name with or without `DICT_` (`DICT_4X4_50`,
    /// `4x4_50`, `aruco_4x4_50`, `apriltag_36h11`), or `checkerboard` (then `board` = (cols, rows)
    /// inner corners and `square` [m] are used), or `drilled_holes` (alias `holes`, `hole_plate`;
    /// `board` = the plate's inner corners). Case-insensitive.
    pub fn parse(name: &str, board: Option<(usize, usize)>, square: Option<f64>) -> Result<Self> {
        let lower = name.trim().to_ascii_lowercase();
        if ["drilled_holes", "holes", "hole_plate"].contains(&lower.as_str()) {
            let (cols, rows) = board.ok_or_else(|| {
                invalid(
                    "board",
                    "family drilled_holes needs the plate's inner-corner count COLSxROWS",
                )
            })?;
            return Ok(TargetFamily::DrilledHoles { cols, rows });
        }
        if lower == "checkerboard" || lower == "chessboard" {
            let (cols, rows) = board.ok_or_else(|| {
                invalid(
                    "board",
                    "family checkerboard needs the inner-corner count COLSxROWS",
                )
            })?;
            let square = square.unwrap_or(f64::NAN);
            if !(square.is_nan() || (square.is_finite() && square > 0.0)) {
                return Err(invalid("square", format!("must be > 0 m, got {square}")));
            }
            return Ok(TargetFamily::Checkerboard { cols, rows, square });
        }
        let stem = lower
            .strip_prefix("dict_")
            .or_else(|| lower.strip_prefix("aruco_"))
            .unwrap_or(&lower);
        let upper = format!("DICT_{}", stem.to_ascii_uppercase());
        let candidates = [
            upper.clone(),
            upper.replace("DICT_ORIGINAL", "DICT_ARUCO_ORIGINAL"),
        ];
        for c in &candidates {
            if let Ok(d) = Dictionary::predefined(c) {
                return Ok(TargetFamily::Markers(d));
            }
        }
        Err(VisionError::UnknownDictionary(format!(
            "{name} (families: an OpenCV dictionary such as DICT_4X4_50 or DICT_APRILTAG_36h11, checkerboard, or drilled_holes)"
        )))
    }

    /// The name written into FiducialDetection.family: `aruco_4x4_50`, `aruco_original`,
    /// `apriltag_36h11`, `checkerboard`.
    pub fn message_name(&self) -> String {
        match self {
            TargetFamily::Markers(d) => {
                let s = d.name.trim_start_matches("DICT_").to_ascii_lowercase();
                if s.starts_with("apriltag_") || s.starts_with("aruco_") {
                    s
                } else {
                    format!("aruco_{s}")
                }
            }
            TargetFamily::Checkerboard { .. } => "checkerboard".into(),
            TargetFamily::DrilledHoles { .. } => "drilled_holes".into(),
        }
    }
}

/// A pose with covariance in the ROS convention of the module doc.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetPose {
    /// Target origin in the camera frame [m].
    pub position: [f64; 3],
    /// Target → camera rotation as a quaternion (x, y, z, w).
    pub orientation: [f64; 4],
    /// Row-major 6×6 over (x, y, z, rot_x, rot_y, rot_z).
    pub covariance: [f64; 36],
    /// RMS reprojection error of the target's points [px].
    pub reprojection_rms_px: f64,
}

/// One detected target.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    /// Marker id; -1 for a checkerboard.
    pub id: i64,
    /// Sub-pixel points [px]: marker corners clockwise from top-left, or board corners row-major.
    pub corners: Vec<Point2<f64>>,
    /// Covariance of each corner [px²]; NaN where it could not be estimated.
    pub corner_covariance: Vec<Matrix2<f64>>,
    /// Markers: correction capacity left (max correctable bits − bits corrected); boards: 1.
    pub decision_margin: f64,
    pub pose: Option<TargetPose>,
}

/// Pose inputs: the calibrated camera and the target size (marker side [m]; boards use their
/// own square size).
#[derive(Debug, Clone, Copy)]
pub struct PoseInputs<'a> {
    pub camera: &'a CameraModel,
    pub marker_side: Option<f64>,
    /// Corner σ [px] used where a corner has no covariance.
    pub fallback_sigma_px: f64,
    /// The calibration's covariance of the camera's parameters ((fx, fy, cx, cy, coefficients…),
    /// as its camera_info YAML states it); when given, each pose's covariance includes what it
    /// adds (crates/camera `intrinsics_uncertainty`), else the intrinsics count as exact.
    pub intrinsics_covariance: Option<&'a DMatrix<f64>>,
}

/// What [`detect_targets_explained`] found, and why a board was not found.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    pub targets: Vec<Target>,
    /// Why no target of a single-target family (checkerboard, drilled holes) was found.
    pub not_found: Option<String>,
}

/// Detect `family` in `img`. An image without targets gives an empty list, not an error.
/// Pose failures leave `pose = None` (the corners are still reported).
pub fn detect_targets(
    img: &GrayImage,
    family: &TargetFamily,
    params: &DetectorParams,
    pose_inputs: Option<PoseInputs<'_>>,
) -> Result<Vec<Target>> {
    Ok(detect_targets_explained(img, family, params, pose_inputs)?.targets)
}

/// [`detect_targets`], with the reason a checkerboard or hole plate was not found (what to
/// tell a user who sees none).
pub fn detect_targets_explained(
    img: &GrayImage,
    family: &TargetFamily,
    params: &DetectorParams,
    pose_inputs: Option<PoseInputs<'_>>,
) -> Result<Detection> {
    let found = |targets: Vec<Target>| Detection {
        targets,
        not_found: None,
    };
    Ok(match family {
        TargetFamily::Markers(dict) => {
            let markers = detect_markers(img, dict, params)?;
            found(
                markers
                    .into_iter()
                    .map(|m| {
                        let pose = pose_inputs.and_then(|pi| {
                            let side = pi.marker_side?;
                            let p = estimate_marker_pose(
                                pi.camera,
                                &m.corners,
                                &m.corner_covariance,
                                side,
                                pi.fallback_sigma_px,
                            )
                            .ok()?;
                            let mut pose = to_ros_pose(
                                &p.camera_from_marker,
                                &p.covariance,
                                p.reprojection_rms_px,
                            );
                            let object: Vec<[f64; 3]> =
                                crate::marker_pose::marker_object_points(side)
                                    .iter()
                                    .map(|q| [q.x, q.y, q.z])
                                    .collect();
                            add_intrinsics_covariance(
                                &mut pose,
                                &pi,
                                &pose_from_isometry(&p.camera_from_marker),
                                &object,
                            )?;
                            Some(pose)
                        });
                        Target {
                            id: m.id as i64,
                            corners: m.corners.to_vec(),
                            corner_covariance: m.corner_covariance.to_vec(),
                            decision_margin: dict.max_correction_bits as f64 - m.bit_errors as f64,
                            pose,
                        }
                    })
                    .collect(),
            )
        }
        TargetFamily::Checkerboard { cols, rows, square } => {
            let board = match detect_checkerboard(img, *cols, *rows) {
                Ok(b) => b,
                Err(VisionError::NoSolution { reason, .. }) => {
                    return Ok(Detection {
                        targets: Vec::new(),
                        not_found: Some(reason),
                    });
                }
                Err(e) => return Err(e),
            };
            let corners: Vec<Point2<f64>> = board.corners.iter().map(|c| c.position).collect();
            let cov: Vec<Matrix2<f64>> = board.corners.iter().map(|c| c.covariance).collect();
            let pose = pose_inputs.and_then(|pi| board_pose(pi, &corners, &cov, *cols, *square));
            found(vec![Target {
                id: -1,
                corners,
                corner_covariance: cov,
                decision_margin: 1.0,
                pose,
            }])
        }
        TargetFamily::DrilledHoles { cols, rows } => {
            let Some(holes) = detect_hole_grid(
                img,
                cols + 1,
                rows + 1,
                &HoleSearch {
                    window_half_px: 0,
                    ..Default::default()
                },
            )?
            else {
                return Ok(Detection {
                    targets: Vec::new(),
                    not_found: Some(format!(
                        "no {}×{} grid of squares with holes found",
                        cols + 1,
                        rows + 1
                    )),
                });
            };
            found(
                holes
                    .into_iter()
                    .filter_map(|h| {
                        let m = h.result.ok()?;
                        Some(Target {
                            id: h.cell as i64,
                            corners: vec![m.centre],
                            corner_covariance: vec![m.covariance],
                            // FiducialDetection: 0..1 contrast for circles.
                            decision_margin: (m.contrast.abs() / 255.0).min(1.0),
                            pose: None,
                        })
                    })
                    .collect(),
            )
        }
    })
}

/// Add what the calibration's uncertainty adds to `pose`'s covariance (the workspace's order
/// (t, rot), crates/camera's pose perturbation), when `pi` states it. None when it cannot
/// be computed (the pose is then not reported rather than reported too sure).
fn add_intrinsics_covariance(
    pose: &mut TargetPose,
    pi: &PoseInputs<'_>,
    fitted: &metrocell_camera_model::Pose,
    object: &[[f64; 3]],
) -> Option<()> {
    let Some(sigma_k) = pi.intrinsics_covariance else {
        return Some(());
    };
    let extra =
        metrocell_camera_model::pose_covariance_from_intrinsics(pi.camera, fitted, object, sigma_k)
            .ok()?;
    for i in 0..6 {
        for j in 0..6 {
            pose.covariance[6 * i + j] += extra[(i, j)];
        }
    }
    Some(())
}

fn board_pose(
    pi: PoseInputs<'_>,
    corners: &[Point2<f64>],
    cov: &[Matrix2<f64>],
    cols: usize,
    square: f64,
) -> Option<TargetPose> {
    if !(square.is_finite() && square > 0.0) {
        return None;
    }
    let object: Vec<[f64; 3]> = (0..corners.len())
        .map(|k| [(k % cols) as f64 * square, (k / cols) as f64 * square, 0.0])
        .collect();
    let image: Vec<[f64; 2]> = corners.iter().map(|p| [p.x, p.y]).collect();
    // One σ for all corners: the RMS of the per-corner standard deviations.
    let vars: Vec<f64> = cov
        .iter()
        .map(|c| c.trace() / 2.0)
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let sigma = if vars.is_empty() {
        pi.fallback_sigma_px
    } else {
        (vars.iter().sum::<f64>() / vars.len() as f64).sqrt()
    };
    let est =
        metrocell_camera_model::estimate_planar_pose(pi.camera, &object, &image, sigma).ok()?;
    let ros = est.to_ros();
    let mut pose = TargetPose {
        position: ros.position,
        orientation: ros.orientation,
        covariance: ros.covariance,
        reprojection_rms_px: est.rms_px,
    };
    add_intrinsics_covariance(&mut pose, &pi, &est.pose, &object)?;
    Some(pose)
}

/// A marker pose as the ROS pose of the module doc (its covariance is already translation first).
fn to_ros_pose(
    iso: &nalgebra::Isometry3<f64>,
    covariance: &nalgebra::SMatrix<f64, 6, 6>,
    rms: f64,
) -> TargetPose {
    let mut c = [0.0; 36];
    for i in 0..6 {
        for j in 0..6 {
            c[6 * i + j] = covariance[(i, j)];
        }
    }
    let q: UnitQuaternion<f64> = iso.rotation;
    let t = iso.translation.vector;
    TargetPose {
        position: [t.x, t.y, t.z],
        orientation: [q.i, q.j, q.k, q.w],
        covariance: c,
        reprojection_rms_px: rms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn family_names_parse_in_opencv_and_message_spellings() {
        for (input, msg) in [
            ("DICT_4X4_50", "aruco_4x4_50"),
            ("4x4_50", "aruco_4x4_50"),
            ("aruco_6x6_1000", "aruco_6x6_1000"),
            ("DICT_ARUCO_ORIGINAL", "aruco_original"),
            ("aruco_original", "aruco_original"),
            ("DICT_APRILTAG_36h11", "apriltag_36h11"),
            ("apriltag_36h11", "apriltag_36h11"),
        ] {
            let f = TargetFamily::parse(input, None, None).unwrap();
            assert_eq!(f.message_name(), msg, "{input}");
        }
        let b = TargetFamily::parse("checkerboard", Some((9, 6)), Some(0.01)).unwrap();
        assert!(
            matches!(b, TargetFamily::Checkerboard { cols: 9, rows: 6, square } if square == 0.01)
        );
        assert!(TargetFamily::parse("checkerboard", None, None).is_err());
        let h = TargetFamily::parse("Drilled_Holes", Some((5, 5)), None).unwrap();
        assert!(matches!(h, TargetFamily::DrilledHoles { cols: 5, rows: 5 }));
        assert_eq!(h.message_name(), "drilled_holes");
        assert!(TargetFamily::parse("holes", None, None).is_err());
        let e = TargetFamily::parse("DICT_9X9_50", None, None).unwrap_err();
        assert!(e.to_string().contains("DICT_9X9_50"), "{e}");
    }
}
