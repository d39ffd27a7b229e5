//! The fiducial plate a simulated camera sees at each dwell, and where its markers are: the twin
//! places it, crates/sim renders it, and measurement records take its features' nominal
//! positions from it.
//!
//! The cell file says where the camera is mounted on the tool, not what it looks at, so the twin
//! places one plate per dwell point: a 2 × 2 board of ArUco markers (ids 0–3, `DICT_4X4_50`,
//! side [`FiducialPlate::marker_side`] including the border, gap [`FiducialPlate::gap`]) square
//! to the *nominal* camera's optical axis at [`FiducialPlate::standoff`] in front of it, its
//! centre on that axis, its x/y axes along the nominal camera's x/y. So a perfect machine sees
//! the board centred, and the machine's displacement moves the markers by ≈ f·d/standoff pixels.
//!
//! Frames (stated once): plate frame p (plane z = 0, x right, y down as printed, origin at the
//! board's centre); workpiece frame wp. With the nominal camera pose (c_nom, R_nom),
//! `p_wp = R_nom·p_p + c_nom + R_nom·(0, 0, standoff)`. The plate belongs to the part, so the
//! workpiece terms move it (the forward model's d_w at each corner, crates/model `camera`).
//! Corner order per marker: OpenCV's, clockwise from the marker's top-left corner.

use nalgebra::{Isometry3, Translation3, Vector3};

/// Layout of the plate (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiducialPlate {
    /// Distance from the nominal camera centre to the plate along the optical axis.
    pub standoff: f64,
    /// Outer side of each marker, border included.
    pub marker_side: f64,
    /// Gap between neighbouring markers.
    pub gap: f64,
}

/// Markers on the plate.
pub const PLATE_MARKERS: usize = 4;

impl Default for FiducialPlate {
    /// 150 mm standoff, 20 mm markers, 10 mm gap.
    fn default() -> Self {
        FiducialPlate {
            standoff: 0.150,
            marker_side: 0.020,
            gap: 0.010,
        }
    }
}

impl FiducialPlate {
    /// Top-left corner (plate frame, m) of marker `k`: 0, 1 on the top row left to right, 2, 3.
    pub fn marker_top_left(&self, k: usize) -> [f64; 2] {
        let half = self.marker_side + self.gap / 2.0;
        let pitch = self.marker_side + self.gap;
        [
            -half + (k % 2) as f64 * pitch,
            -half + (k / 2) as f64 * pitch,
        ]
    }

    /// Centre of marker `k` in the plate frame (the origin of a detector's marker pose).
    pub fn marker_centre(&self, k: usize) -> Vector3<f64> {
        let [x, y] = self.marker_top_left(k);
        let h = self.marker_side / 2.0;
        Vector3::new(x + h, y + h, 0.0)
    }

    /// The four corners of marker `k` in the plate frame, OpenCV order.
    pub fn marker_corners(&self, k: usize) -> [Vector3<f64>; 4] {
        let [x, y] = self.marker_top_left(k);
        let s = self.marker_side;
        [
            Vector3::new(x, y, 0.0),
            Vector3::new(x + s, y, 0.0),
            Vector3::new(x + s, y + s, 0.0),
            Vector3::new(x, y + s, 0.0),
        ]
    }

    /// Plate frame → workpiece frame for the nominal camera pose `nominal_camera`.
    pub fn pose(&self, nominal_camera: &Isometry3<f64>) -> Isometry3<f64> {
        nominal_camera * Translation3::new(0.0, 0.0, self.standoff)
    }

    /// Every marker corner in the workpiece frame (markers 0–3, OpenCV order each): the nominal
    /// feature positions a camera reading is predicted for.
    pub fn corners_in_workpiece(&self, nominal_camera: &Isometry3<f64>) -> Vec<Vector3<f64>> {
        let pose = self.pose(nominal_camera);
        (0..PLATE_MARKERS)
            .flat_map(|k| self.marker_corners(k))
            .map(|c| pose.transform_point(&c.into()).coords)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_lie_on_the_plate_at_the_standoff() {
        let plate = FiducialPlate::default();
        // camera at (1, 2, 3) looking down −z: its x along wp x, y along −wp y
        let cam = Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 3.0),
            nalgebra::UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0),
        );
        let c = plate.corners_in_workpiece(&cam);
        assert_eq!(c.len(), 16);
        for p in &c {
            assert!((p.z - (3.0 - 0.150)).abs() < 1e-12, "{p}");
        }
        // marker 0's top-left corner: plate (−0.025, −0.025) → wp (1 − 0.025, 2 + 0.025)
        assert!(
            (c[0] - Vector3::new(0.975, 2.025, 2.85)).norm() < 1e-12,
            "{}",
            c[0]
        );
        // marker 3's bottom-right corner: plate (0.025, 0.025)
        assert!(
            (c[14] - Vector3::new(1.025, 1.975, 2.85)).norm() < 1e-12,
            "{}",
            c[14]
        );
    }
}
