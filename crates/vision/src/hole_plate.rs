//! A drilled plate (seed 000 §3) measured in its own plane: the checkerboard's inner corners
//! give the board's pose to a calibrated camera, each hole is found where the pose predicts its
//! square's centre ([`crate::holes::measure_holes`]) and its centre is carried back through the
//! lens model onto the board plane.
//!
//! Board frame (metres): origin at the outer corner of the first square the detector orders
//! ([`crate::checkerboard`]: a frontal board top-left first), x along the columns, y along the
//! rows, so square (c, r) spans [c·s, (c+1)·s] × [r·s, (r+1)·s]. Each hole's covariance is its
//! centre's (px², [`crate::holes::CENTRE_FLOOR_PX`] included) with the corners' reprojection
//! RMS added in quadrature, carried through the back-projection; the board pose's own
//! uncertainty is common to all holes (a rigid shift, turn or tilt of the whole
//! plate), which the planar error field's constant and linear terms take up, and is reported as
//! the corners' reprojection RMS.

use crate::checkerboard::detect_checkerboard;
use crate::error::{invalid, Result, VisionError};
use crate::holes::{measure_holes, HoleRejection, HoleSearch};
use image::GrayImage;
use metrocell_camera_model::{estimate_planar_pose, CameraModel, Pose};
use nalgebra::{Matrix2, Point2, Vector3};

/// One hole on the board plane.
#[derive(Debug, Clone, PartialEq)]
pub struct PlateHole {
    /// Square (column, row) in the detector's order.
    pub column: usize,
    pub row: usize,
    /// The square's centre and the hole's measured centre (m, board frame).
    pub nominal: [f64; 2],
    pub measured: [f64; 2],
    /// Covariance of `measured` (m²).
    pub covariance: Matrix2<f64>,
    /// Whether the hole is darker than its surroundings (a hole through a white square over a
    /// black backing).
    pub dark: bool,
}

/// What one photo gave.
#[derive(Debug, Clone, PartialEq)]
pub struct PlateMeasurement {
    pub holes: Vec<PlateHole>,
    /// Squares without a usable hole, and why.
    pub rejected: Vec<((usize, usize), HoleRejection)>,
    /// RMS distance of the inner corners from where the fitted pose puts them (px).
    pub corner_rms_px: f64,
    /// Board millimetres per pixel at the board's centre.
    pub mm_per_px: f64,
}

/// Measures the plate of `squares_x` × `squares_y` squares of `square` metres in `img`.
/// `Ok(None)` when no board of that size is in the picture. `search.window_half_px` = 0 sizes
/// each window to 0.3 × the square's side in the image.
pub fn measure_plate(
    img: &GrayImage,
    cam: &CameraModel,
    squares_x: usize,
    squares_y: usize,
    square: f64,
    search: &HoleSearch,
) -> Result<Option<PlateMeasurement>> {
    if squares_x < 3 || squares_y < 3 {
        return Err(invalid(
            "squares",
            format!("a hole plate needs at least 3×3 squares, got {squares_x}×{squares_y}"),
        ));
    }
    if !(square > 0.0 && square.is_finite()) {
        return Err(invalid(
            "square",
            format!("{square} m is not a positive size"),
        ));
    }
    let Some((pose, rms_px)) = board_pose(img, cam, squares_x - 1, squares_y - 1, square)? else {
        return Ok(None);
    };
    let project = |x: f64, y: f64| -> Result<Point2<f64>> {
        let c = pose.rotation * Vector3::new(x, y, 0.0) + pose.translation;
        let [u, v] = cam
            .project_camera_point(&c)
            .map_err(|e| VisionError::NoSolution {
                what: "hole prediction",
                reason: e.to_string(),
            })?;
        Ok(Point2::new(u, v))
    };
    let centre = project(
        0.5 * squares_x as f64 * square,
        0.5 * squares_y as f64 * square,
    )?;
    let step = project(
        (0.5 * squares_x as f64 + 1.0) * square,
        0.5 * squares_y as f64 * square,
    )?;
    let side_px = (step - centre).norm();
    let mut predicted = Vec::new();
    let mut cells = Vec::new();
    for row in 0..squares_y {
        for column in 0..squares_x {
            let nominal = [(column as f64 + 0.5) * square, (row as f64 + 0.5) * square];
            predicted.push(project(nominal[0], nominal[1])?);
            cells.push((column, row, nominal));
        }
    }
    let window = if search.window_half_px == 0 {
        ((0.3 * side_px).floor() as u32).max(3)
    } else {
        search.window_half_px
    };
    let s = HoleSearch {
        window_half_px: window,
        ..*search
    };
    let found = measure_holes(img, &predicted, &s)?;
    let mut out = PlateMeasurement {
        holes: Vec::new(),
        rejected: Vec::new(),
        corner_rms_px: rms_px,
        mm_per_px: square * 1e3 / side_px,
    };
    for ((column, row, nominal), result) in cells.into_iter().zip(found) {
        match result {
            Ok(h) => {
                let (measured, jacobian) = back_project(cam, &pose, &h.centre, 0.0)?;
                // the board frame is no better than its corners fit
                let px = h.covariance + Matrix2::identity() * rms_px.powi(2);
                out.holes.push(PlateHole {
                    column,
                    row,
                    nominal,
                    measured,
                    covariance: jacobian * px * jacobian.transpose(),
                    dark: h.contrast < 0.0,
                });
            }
            Err(why) => out.rejected.push(((column, row), why)),
        }
    }
    Ok(Some(out))
}

/// The pose (board → camera) of a checkerboard of `cols` × `rows` inner corners, `square`
/// metres apart, in the board frame of the module docs, and the corners' reprojection RMS (px).
/// `Ok(None)` when no such board is in the picture.
pub fn board_pose(
    img: &GrayImage,
    cam: &CameraModel,
    cols: usize,
    rows: usize,
    square: f64,
) -> Result<Option<(Pose, f64)>> {
    let board = match detect_checkerboard(img, cols, rows) {
        Ok(b) => b,
        Err(VisionError::NoSolution { .. }) => return Ok(None),
        Err(e) => return Err(e),
    };
    let object: Vec<[f64; 3]> = (0..cols * rows)
        .map(|k| {
            [
                ((k % cols) + 1) as f64 * square,
                ((k / cols) + 1) as f64 * square,
                0.0,
            ]
        })
        .collect();
    let pixels: Vec<[f64; 2]> = board
        .corners
        .iter()
        .map(|c| [c.position.x, c.position.y])
        .collect();
    let pose =
        estimate_planar_pose(cam, &object, &pixels, 0.1).map_err(|e| VisionError::NoSolution {
            what: "board pose",
            reason: e.to_string(),
        })?;
    Ok(Some((pose.pose, pose.rms_px)))
}

/// The point (x, y) on the plane `height` metres above the board (toward the camera) that a
/// pixel sees, in board coordinates (m), and its 2×2 Jacobian with respect to the pixel (central
/// differences of ±0.01 px). A feature standing proud of the board — a printed dot's top — is
/// seen displaced outward by height × (its distance from the view's axis) / (the camera's
/// distance): back-projecting onto its own plane takes that parallax out.
pub fn back_project(
    cam: &CameraModel,
    pose: &Pose,
    px: &Point2<f64>,
    height: f64,
) -> Result<([f64; 2], Matrix2<f64>)> {
    let rt = pose.rotation.transpose();
    let origin = -(rt * pose.translation);
    // "up" is the side of the board the camera is on
    let plane_z = height * origin.z.signum();
    let at = |u: f64, v: f64| -> Result<[f64; 2]> {
        let [x, y] = cam
            .pixel_to_normalized(u, v)
            .ok_or_else(|| VisionError::NoSolution {
                what: "hole back-projection",
                reason: format!("pixel ({u:.1}, {v:.1}) cannot be undistorted"),
            })?;
        let dir = rt * Vector3::new(x, y, 1.0);
        if dir.z.abs() < 1e-12 {
            return Err(VisionError::NoSolution {
                what: "hole back-projection",
                reason: "the ray runs parallel to the board".into(),
            });
        }
        let l = (plane_z - origin.z) / dir.z;
        Ok([origin.x + l * dir.x, origin.y + l * dir.y])
    };
    let p = at(px.x, px.y)?;
    let h = 0.01;
    let (xp, xm) = (at(px.x + h, px.y)?, at(px.x - h, px.y)?);
    let (yp, ym) = (at(px.x, px.y + h)?, at(px.x, px.y - h)?);
    let j = Matrix2::new(
        (xp[0] - xm[0]) / (2.0 * h),
        (yp[0] - ym[0]) / (2.0 * h),
        (xp[1] - xm[1]) / (2.0 * h),
        (yp[1] - ym[1]) / (2.0 * h),
    );
    Ok((p, j))
}
