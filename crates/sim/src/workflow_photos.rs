//! The twin's photos of the camera workflows' objects, photographed from above by the twin's
//! workflow camera — so `metrocell router measure | fit` and `metrocell delta measure | fit` can
//! be run end to end on data whose truth is known, through the commands only:
//! - a drilled hole plate (seed 000) as a router with a known error field drilled it;
//! - a printed delta star (seed 002) as a printer with a known geometry printed it, beside a
//!   paper checkerboard card. The tops of its dots and tiles stand above the bed: a plane
//!   parallel to the bed, seen from the camera's centre C at height H, projects onto the bed as
//!   itself scaled by H / (H − h) about C's foot, so each top is drawn there on the bed plane —
//!   the parallax a real camera sees, exact for flat tops (their sides are not drawn).
//!
//! The workflow camera (stated once): 2048 × 1536 px, f = 3400 px, principal point
//! (1019.3, 771.8) px, Brown–Conrady (k1, k2, p1, p2, k3) = (−0.09, 0.11, 0.0002, −0.0005,
//! −0.02); 0.8 px optics blur, 1 grey level of sensor noise, edges supersampled 4 × 4 (the twin's
//! frame rendering, [`crate::FrameRendering`]). Each photo is taken from `distance` above the
//! object's centre, tilted up to 3° about a random horizontal axis and shifted up to 5 mm,
//! its seed derived from the run's seed and the photo's index.
//!
//! Board frame (the renderer's target frame): x right, y down as printed, the machine's back
//! (+Y) at the top — the orientation `router pattern` prints and `router measure` expects.

use metrocell_camera_model::{CameraModel, Distortion};
use metrocell_vision::render::{render_view, PlanarTarget, RenderSettings, TargetItem};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::camera_frame::frame_seed;
use crate::error::SimError;
use crate::FrameRendering;

/// The workflow camera of the module docs.
pub fn workflow_camera() -> CameraModel {
    CameraModel::new(
        2048,
        1536,
        3400.0,
        3400.0,
        1019.3,
        771.8,
        Distortion::BrownConrady([-0.09, 0.11, 0.0002, -0.0005, -0.02]),
    )
    .expect("valid workflow camera")
}

/// A uniform number in [−1, 1) from `seed` and a draw index.
fn uniform(seed: u64, draw: u64) -> f64 {
    (frame_seed(seed, draw) >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Target → camera pose of photo `k`: the camera `distance` (m) above `centre` (target frame,
/// m), looking down the target's +z (the target's x right and y down are the image's), tilted
/// and shifted as the module docs say.
pub fn photo_pose(centre: [f64; 2], distance: f64, seed: u64, k: u64) -> Isometry3<f64> {
    let s = frame_seed(seed, k);
    let axis_angle = std::f64::consts::PI * uniform(s, 0);
    let tilt = 3f64.to_radians() * (0.5 + 0.5 * uniform(s, 1));
    let axis = Unit::new_normalize(Vector3::new(axis_angle.cos(), axis_angle.sin(), 0.0));
    let rotation = UnitQuaternion::from_axis_angle(&axis, tilt);
    let shift = Vector3::new(0.005 * uniform(s, 2), 0.005 * uniform(s, 3), 0.0);
    // p_c = R·(p − centre − shift) + (0, 0, distance)
    let c = Vector3::new(centre[0], centre[1], 0.0) + shift;
    Isometry3::from_parts(
        Translation3::from(Vector3::new(0.0, 0.0, distance) - rotation * c),
        rotation,
    )
}

/// The twin's frame rendering with the photo's own noise seed.
fn settings(seed: u64, k: u64) -> RenderSettings {
    RenderSettings {
        seed: frame_seed(seed ^ 0x5EED, k),
        ..FrameRendering::default().settings
    }
}

/// A drilled plate: `squares` (x, y) squares of `square` m, the front-left square black,
/// one hole of `hole` m per square at `holes[row·squares.0 + column]` (board frame, m; rows from
/// the top), lying over its inverse-coloured backing.
#[derive(Debug, Clone, PartialEq)]
pub struct DrilledPlate {
    pub squares: (u32, u32),
    pub square: f64,
    pub hole: f64,
    pub holes: Vec<[f64; 2]>,
}

impl DrilledPlate {
    fn target(&self) -> PlanarTarget {
        let mut items = vec![TargetItem::Checkerboard {
            top_left: [0.0, 0.0],
            square: self.square,
            squares_x: self.squares.0,
            squares_y: self.squares.1,
            // the front-left (bottom-left) square is black
            top_left_black: (self.squares.1 - 1).is_multiple_of(2),
        }];
        items.extend(self.holes.iter().map(|&centre| TargetItem::Hole {
            centre,
            diameter: self.hole,
        }));
        PlanarTarget { items }
    }
}

/// Photo `k` of `plate` by `camera` from `distance` m above its centre.
pub fn photograph_plate(
    plate: &DrilledPlate,
    camera: &CameraModel,
    distance: f64,
    seed: u64,
    k: u64,
) -> Result<image::GrayImage, SimError> {
    let centre = [
        0.5 * plate.squares.0 as f64 * plate.square,
        0.5 * plate.squares.1 as f64 * plate.square,
    ];
    let pose = photo_pose(centre, distance, seed, k);
    let view = render_view(camera, &pose, &plate.target(), &settings(seed, k))
        .map_err(|e| SimError::invalid("drilled plate photo", e.to_string()))?;
    Ok(view.image)
}

/// A printed delta star (printer frame: bed centre origin, x right, y toward the back, z up; m)
/// and the checkerboard card beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct PrintedStar {
    /// Each dot's top centre, where the printer put it.
    pub dots: Vec<Vector3<f64>>,
    pub dot_diameter: f64,
    /// (ArUco id of DICT_4X4_50, top centre as printed, side with its one-cell quiet zone).
    pub tiles: Vec<(usize, Vector3<f64>, f64)>,
    /// The card: squares (x, y), square side, and the (x, y) of its squares' back-left corner.
    pub card_squares: (u32, u32),
    pub card_square: f64,
    pub card_corner: [f64; 2],
}

impl PrintedStar {
    /// The scene's extent in the target frame (x right, y down = −printer y): (min, max).
    fn extent(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let card = [
            self.card_corner,
            [
                self.card_corner[0] + self.card_squares.0 as f64 * self.card_square,
                self.card_corner[1] - self.card_squares.1 as f64 * self.card_square,
            ],
        ];
        for p in self.dots.iter().map(|d| [d.x, d.y]).chain(card) {
            let t = [p[0], -p[1]];
            for a in 0..2 {
                lo[a] = lo[a].min(t[a]);
                hi[a] = hi[a].max(t[a]);
            }
        }
        (lo, hi)
    }

    /// The scene as drawn on the bed plane for a camera centred at `eye` (target frame, m;
    /// z < 0 above the bed): dark bed, white card with its board, tiles and dot tops carried
    /// to where the camera sees them (module docs).
    fn target(&self, eye: &Vector3<f64>) -> Result<PlanarTarget, SimError> {
        let height = -eye.z;
        let seen = |p: &Vector3<f64>| -> ([f64; 2], f64) {
            let scale = height / (height - p.z);
            (
                [
                    eye.x + (p.x - eye.x) * scale,
                    eye.y + (-p.y - eye.y) * scale,
                ],
                scale,
            )
        };
        let (lo, hi) = self.extent();
        let margin = 0.03;
        let mut items = vec![TargetItem::Rectangle {
            top_left: [lo[0] - margin, lo[1] - margin],
            size: [hi[0] - lo[0] + 2.0 * margin, hi[1] - lo[1] + 2.0 * margin],
            white: false,
        }];
        let (cx, cy) = (self.card_corner[0], -self.card_corner[1]);
        let (w, h) = (
            self.card_squares.0 as f64 * self.card_square,
            self.card_squares.1 as f64 * self.card_square,
        );
        let paper = 0.5 * self.card_square;
        items.push(TargetItem::Rectangle {
            top_left: [cx - paper, cy - paper],
            size: [w + 2.0 * paper, h + 2.0 * paper],
            white: true,
        });
        items.push(TargetItem::Checkerboard {
            top_left: [cx, cy],
            square: self.card_square,
            squares_x: self.card_squares.0,
            squares_y: self.card_squares.1,
            top_left_black: true,
        });
        let dictionary = metrocell_vision::aruco::Dictionary::predefined("DICT_4X4_50")
            .map_err(|e| SimError::invalid("star tiles", e.to_string()))?;
        for (id, top, side) in &self.tiles {
            let (c, scale) = seen(top);
            let side = side * scale;
            items.push(TargetItem::Rectangle {
                top_left: [c[0] - side / 2.0, c[1] - side / 2.0],
                size: [side, side],
                white: true,
            });
            // 4 × 4 bits, a one-cell black border, a one-cell quiet zone: 8 cells
            let marker = side * 6.0 / 8.0;
            items.push(TargetItem::Marker {
                dictionary,
                id: *id,
                top_left: [c[0] - marker / 2.0, c[1] - marker / 2.0],
                side: marker,
                border_bits: 1,
            });
        }
        for d in &self.dots {
            let (centre, scale) = seen(d);
            items.push(TargetItem::Disc {
                centre,
                diameter: self.dot_diameter * scale,
                white: true,
            });
        }
        Ok(PlanarTarget { items })
    }
}

/// Photo `k` of `star` by `camera` from `distance` m above the scene's centre.
pub fn photograph_star(
    star: &PrintedStar,
    camera: &CameraModel,
    distance: f64,
    seed: u64,
    k: u64,
) -> Result<image::GrayImage, SimError> {
    let (lo, hi) = star.extent();
    let pose = photo_pose(
        [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
        distance,
        seed,
        k,
    );
    let eye = pose.inverse() * nalgebra::Point3::origin();
    let target = star.target(&eye.coords)?;
    let view = render_view(camera, &pose, &target, &settings(seed, k))
        .map_err(|e| SimError::invalid("printed star photo", e.to_string()))?;
    Ok(view.image)
}

/// The distance (m) from which `camera` sees a scene `extent` m across over 80 % of its
/// shorter side.
pub fn distance_for(camera: &CameraModel, extent: f64) -> f64 {
    camera.fx * extent / (0.8 * camera.height.min(camera.width) as f64)
}

/// The star's scene extent (m): its larger side, card included.
pub fn star_extent(star: &PrintedStar) -> f64 {
    let (lo, hi) = star.extent();
    (hi[0] - lo[0]).max(hi[1] - lo[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_top_above_the_bed_is_drawn_where_the_camera_sees_it() {
        let star = PrintedStar {
            dots: vec![Vector3::new(0.08, 0.0, 0.001)],
            dot_diameter: 0.003,
            tiles: vec![],
            card_squares: (4, 3),
            card_square: 0.01,
            card_corner: [0.1, 0.0],
        };
        // camera 0.33 m above the bed's centre: a top 1 mm up, 80 mm out, is seen 0.24 mm
        // further out, and 0.3 % larger
        let target = star.target(&Vector3::new(0.0, 0.0, -0.33)).unwrap();
        let Some(TargetItem::Disc {
            centre, diameter, ..
        }) = target.items.last()
        else {
            panic!("the dot is drawn last");
        };
        let scale = 0.33 / 0.329;
        assert!((centre[0] - 0.08 * scale).abs() < 1e-12 && centre[1].abs() < 1e-15);
        assert!((centre[0] - 0.08 - 0.000_243).abs() < 1e-6);
        assert!((diameter - 0.003 * scale).abs() < 1e-15);
    }

    /// The standard star printed true, for the bad-input cases below.
    fn true_star(tiles: Vec<(usize, [f64; 2])>) -> PrintedStar {
        let design = metrocell_vision::printed_star::DeltaStar::standard();
        PrintedStar {
            dots: design
                .dots
                .iter()
                .map(|d| Vector3::new(d[0], d[1], design.dot_height))
                .collect(),
            dot_diameter: design.dot_diameter,
            tiles: tiles
                .into_iter()
                .map(|(id, c)| (id, Vector3::new(c[0], c[1], design.marker_height), 0.014))
                .collect(),
            card_squares: (10, 7),
            card_square: 0.010,
            card_corner: [0.090, 0.035],
        }
    }

    #[test]
    fn a_tile_seen_twice_or_tiles_missing_are_refused_with_what_to_do() {
        use metrocell_vision::printed_star::{measure_star, DeltaStar, ScaleCard};
        let design = DeltaStar::standard();
        let tiles: Vec<(usize, [f64; 2])> =
            design.markers.iter().map(|(id, c, _)| (*id, *c)).collect();
        let card = ScaleCard {
            cols: 9,
            rows: 6,
            square: 0.010,
        };
        let camera = workflow_camera();
        let photo = |star: &PrintedStar| {
            let image = photograph_star(
                star,
                &camera,
                distance_for(&camera, star_extent(star)),
                1,
                0,
            )
            .unwrap();
            measure_star(&image, &camera, &design, &card)
        };
        // the true star is measured: every dot, the three tiles
        let m = photo(&true_star(tiles.clone())).unwrap();
        assert_eq!((m.dots.len(), m.markers.clone()), (85, vec![1, 2, 3]));
        // a spare tile 2 left on the bed beside the star
        let mut spare = tiles.clone();
        spare.push((2, [0.0, -0.095]));
        let e = photo(&true_star(spare)).unwrap_err().to_string();
        assert!(
            e.contains("tile 2 is seen 2 times") && e.contains("only one star"),
            "{e}"
        );
        // two tiles covered
        let e = photo(&true_star(tiles[..1].to_vec()))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("1 of the star's 3 tiles") && e.contains("keep them in view"),
            "{e}"
        );
    }

    #[test]
    fn photo_poses_look_down_from_the_distance_and_differ_per_photo() {
        let (a, b) = (
            photo_pose([0.075, 0.075], 0.4, 7, 0),
            photo_pose([0.075, 0.075], 0.4, 7, 1),
        );
        for p in [a, b] {
            // the board's centre lies ahead of the camera, within the shift and tilt
            let c = p * nalgebra::Point3::new(0.075, 0.075, 0.0);
            assert!(
                (c.z - 0.4).abs() < 0.002 && c.x.abs() < 0.01 && c.y.abs() < 0.01,
                "{c}"
            );
            let tilt = p.rotation.angle().to_degrees();
            assert!((1.5..=3.0).contains(&tilt), "{tilt}");
        }
        assert_ne!(a, b);
        assert_eq!(a, photo_pose([0.075, 0.075], 0.4, 7, 0));
    }
}
