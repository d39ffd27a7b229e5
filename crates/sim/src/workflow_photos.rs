//! The twin's photos of the camera workflows' objects: a drilled hole plate (seed 000) as a
//! router with a known error field drilled it, photographed from above by the twin's workflow
//! camera — so `metrocell router measure` and `fit` can be run end to end on data whose truth
//! is known, through the commands only.
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
            top_left_black: (self.squares.1 - 1) % 2 == 0,
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

#[cfg(test)]
mod tests {
    use super::*;

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
