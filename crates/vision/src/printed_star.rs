//! Seed 002's calibration object, as metrocell prints and measures it: a star of dots the delta
//! prints on its bed (the centre and 12 directions every 30° at 20, 30, … 80 mm), three ArUco
//! tiles (ids 1, 2, 3 of DICT_4X4_50) 15° counter-clockwise of the arms toward towers A, B and C,
//! and, laid flat on the bed beside it, a checkerboard card printed on paper (not by the
//! printer: its squares are the scale the printer's errors are measured against).
//!
//! A photo from above: the card's corners give the bed plane's pose and scale to the calibrated
//! camera ([`crate::hole_plate::board_pose`]); the tiles tell which arm is which (the star looks
//! the same turned by 30°); every dot is found where that places it
//! ([`crate::holes::measure_holes`]) and its top is carried back onto the plane at the dot's
//! height. Positions are in the card's frame turned right-handed with z toward the camera (m):
//! the star's placement on the bed is unknown and is estimated with the geometry by the fit
//! (`estimation::delta_calibration`).
//!
//! Commanded positions are the printer's (m, bed centre origin, z up; towers A, B, C at 210°,
//! 330°, 90°, Marlin's).

use crate::aruco::{detect_markers, DetectorParams, Dictionary};
use crate::error::{invalid, Result, VisionError};
use crate::hole_plate::{back_project, board_pose};
use crate::holes::{measure_holes, HoleRejection, HoleSearch};
use image::GrayImage;
use metrocell_camera_model::CameraModel;
use nalgebra::{Matrix2, Point2, Rotation2, Vector2, Vector3};

/// The printed star.
#[derive(Debug, Clone, PartialEq)]
pub struct DeltaStar {
    /// Commanded (x, y) of each dot (m).
    pub dots: Vec<[f64; 2]>,
    /// Dot diameter and height (m): the camera sees the dots' tops.
    pub dot_diameter: f64,
    pub dot_height: f64,
    /// (id, commanded centre, side) of each ArUco tile (m), DICT_4X4_50 with a white quiet
    /// zone one cell wide inside the side, printed `marker_height` tall.
    pub markers: Vec<(usize, [f64; 2], f64)>,
    pub marker_height: f64,
}

/// Marlin's tower angles A, B, C (degrees).
const TOWERS_DEG: [f64; 3] = [210.0, 330.0, 90.0];

impl DeltaStar {
    /// The standard star: dots of 3 mm, 1 mm tall; 14 mm tiles 0.6 mm tall at 62 mm.
    pub fn standard() -> Self {
        let mut dots = vec![[0.0, 0.0]];
        for k in 0..12 {
            let a = (90.0 + 30.0 * k as f64).to_radians();
            for r in 2..=8 {
                let r = r as f64 * 0.010;
                dots.push([r * a.cos(), r * a.sin()]);
            }
        }
        let markers = TOWERS_DEG
            .iter()
            .enumerate()
            .map(|(t, deg)| {
                let a = (deg + 15.0f64).to_radians();
                (t + 1, [0.062 * a.cos(), 0.062 * a.sin()], 0.014)
            })
            .collect();
        Self {
            dots,
            dot_diameter: 0.003,
            dot_height: 0.001,
            markers,
            marker_height: 0.0006,
        }
    }

    /// The dots as a CSV the printer's program and `delta measure` agree on (mm).
    pub fn dots_csv(&self) -> String {
        let mut s = String::from("dot,x_mm,y_mm,z_mm\n");
        for (k, d) in self.dots.iter().enumerate() {
            s.push_str(&format!(
                "{},{:.4},{:.4},{:.4}\n",
                k + 1,
                d[0] * 1e3,
                d[1] * 1e3,
                self.dot_height * 1e3
            ));
        }
        s
    }
}

/// The card the scale comes from: `cols` × `rows` inner corners, `square` metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleCard {
    pub cols: usize,
    pub rows: usize,
    pub square: f64,
}

/// One dot as measured.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredDot {
    /// Index into [`DeltaStar::dots`].
    pub dot: usize,
    /// Position of the dot's top in the card's frame (m), and its covariance (m²).
    pub position: [f64; 2],
    pub covariance: Matrix2<f64>,
}

/// What one photo gave.
#[derive(Debug, Clone, PartialEq)]
pub struct StarMeasurement {
    pub dots: Vec<MeasuredDot>,
    /// The camera's centre in the same right-handed frame as the dots (z up from the bed, m):
    /// a dot whose top is not at `dot_height` is seen displaced along the ray from here.
    pub viewpoint: Vector3<f64>,
    pub rejected: Vec<(usize, HoleRejection)>,
    /// Tile ids found.
    pub markers: Vec<usize>,
    pub card_rms_px: f64,
    pub mm_per_px: f64,
}

/// Why a photo could not be measured.
fn refuse(reason: String) -> VisionError {
    VisionError::NoSolution {
        what: "printed star",
        reason,
    }
}

/// Measures the star in one photo. Errors name what is missing (the card, the tiles).
pub fn measure_star(
    img: &GrayImage,
    cam: &CameraModel,
    star: &DeltaStar,
    card: &ScaleCard,
) -> Result<StarMeasurement> {
    if !(card.square > 0.0 && card.square.is_finite()) {
        return Err(invalid("card square", format!("{} m", card.square)));
    }
    let Some((pose, card_rms_px)) = board_pose(img, cam, card.cols, card.rows, card.square)? else {
        return Err(refuse(format!(
            "no {}×{}-corner checkerboard card in the picture: lay the card flat on the bed \
             beside the star, wholly in view",
            card.cols, card.rows
        )));
    };
    // the card's frame has z away from the camera (x right, y down the image): seen from the
    // camera it is mirrored, so y is turned over to give positions in a right-handed frame with
    // z toward the camera, as the printer's own (a turn and a shift from it, never a mirror)
    let mirror = if (-(pose.rotation.transpose() * pose.translation)).z < 0.0 {
        Matrix2::new(1.0, 0.0, 0.0, -1.0)
    } else {
        Matrix2::identity()
    };
    // the tiles: which arm is which
    let dict = Dictionary::predefined("DICT_4X4_50")?;
    let found = detect_markers(img, &dict, &DetectorParams::default())?;
    let mut pairs = Vec::new();
    let mut ids = Vec::new();
    for (id, centre, _) in &star.markers {
        let seen: Vec<_> = found.iter().filter(|m| m.id == *id).collect();
        if seen.len() > 1 {
            return Err(refuse(format!(
                "tile {id} is seen {} times: only one star (and no spare tiles) may be in view",
                seen.len()
            )));
        }
        if let Some(m) = seen.first() {
            let c = m.corners.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / 4.0;
            let (p, _) = back_project(cam, &pose, &Point2::from(c), star.marker_height)?;
            pairs.push((Vector2::from(*centre), mirror * Vector2::from(p)));
            ids.push(*id);
        }
    }
    if pairs.len() < 2 {
        return Err(refuse(format!(
            "{} of the star's 3 tiles (ids 1, 2, 3 of DICT_4X4_50) found: at least 2 are needed \
             to tell its arms apart; light the tiles evenly and keep them in view",
            pairs.len()
        )));
    }
    let (rotation, shift) = rigid_2d(&pairs);
    let project = |p: Vector2<f64>, h: f64| -> Result<Point2<f64>> {
        let up = (-(pose.rotation.transpose() * pose.translation)).z.signum();
        let c = pose.rotation * Vector3::new(p.x, p.y, up * h) + pose.translation;
        let [u, v] = cam
            .project_camera_point(&c)
            .map_err(|e| refuse(e.to_string()))?;
        Ok(Point2::new(u, v))
    };
    // commanded → the card's own frame, where `project` works
    let place = |d: &[f64; 2]| mirror * (rotation * Vector2::from(*d) + shift);
    let predicted: Vec<Point2<f64>> = star
        .dots
        .iter()
        .map(|d| project(place(d), star.dot_height))
        .collect::<Result<_>>()?;
    // px per m on the bed at the star's centre
    let c0 = project(place(&[0.0, 0.0]), 0.0)?;
    let c1 = project(place(&[0.01, 0.0]), 0.0)?;
    let px_per_m = (c1 - c0).norm() / 0.01;
    // dots 10 mm apart along an arm, 10.4 mm between arms on the inner ring: a window of ±4 mm
    // holds a 3 mm dot misplaced by up to 2.5 mm and no neighbour
    let search = HoleSearch {
        window_half_px: ((0.004 * px_per_m).floor() as u32).max(3),
        ..HoleSearch::default()
    };
    let results = measure_holes(img, &predicted, &search)?;
    let centre = -(pose.rotation.transpose() * pose.translation);
    let mut out = StarMeasurement {
        dots: Vec::new(),
        viewpoint: Vector3::new(centre.x, (mirror * centre.xy()).y, centre.z.abs()),
        rejected: Vec::new(),
        markers: ids,
        card_rms_px,
        mm_per_px: 1e3 / px_per_m,
    };
    for (dot, r) in results.into_iter().enumerate() {
        match r {
            Ok(h) => {
                let (position, j) = back_project(cam, &pose, &h.centre, star.dot_height)?;
                let position = [position[0], (mirror * Vector2::from(position)).y];
                let j = mirror * j;
                let px = h.covariance + Matrix2::identity() * card_rms_px.powi(2);
                out.dots.push(MeasuredDot {
                    dot,
                    position,
                    covariance: j * px * j.transpose(),
                });
            }
            Err(why) => out.rejected.push((dot, why)),
        }
    }
    Ok(out)
}

/// The rotation and shift taking the first points of `pairs` onto the second (least squares).
fn rigid_2d(pairs: &[(Vector2<f64>, Vector2<f64>)]) -> (Rotation2<f64>, Vector2<f64>) {
    let n = pairs.len() as f64;
    let ca = pairs.iter().map(|p| p.0).sum::<Vector2<f64>>() / n;
    let cb = pairs.iter().map(|p| p.1).sum::<Vector2<f64>>() / n;
    let (mut s, mut c) = (0.0, 0.0);
    for (a, b) in pairs {
        let (a, b) = (a - ca, b - cb);
        s += a.x * b.y - a.y * b.x;
        c += a.dot(&b);
    }
    let r = Rotation2::new(s.atan2(c));
    (r, cb - r * ca)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_star_has_85_dots_and_its_tiles_between_the_arms() {
        let s = DeltaStar::standard();
        assert_eq!(s.dots.len(), 85);
        assert_eq!(s.markers.len(), 3);
        // no tile (whatever its turn) overlaps a dot
        for (_, c, side) in &s.markers {
            for d in &s.dots {
                let far = (d[0] - c[0]).hypot(d[1] - c[1]);
                assert!(
                    far > side / 2f64.sqrt() + s.dot_diameter / 2.0,
                    "{d:?} under tile at {c:?}"
                );
            }
        }
        assert!(s.dots_csv().lines().nth(1).unwrap() == "1,0.0000,0.0000,1.0000");
        let (r, t) = rigid_2d(&[
            (Vector2::new(1.0, 0.0), Vector2::new(2.0, 1.0)),
            (Vector2::new(0.0, 1.0), Vector2::new(1.0, 0.0)),
        ]);
        assert!((r.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((t - Vector2::new(2.0, 0.0)).norm() < 1e-12);
    }
}
