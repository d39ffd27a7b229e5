//! The alignment's result in the forms a cell uses: a `/tf_static` transform (tool link →
//! camera link), a fixed URDF joint, and the `mount` line of a cell file's camera
//! (`p_tool = R·p_cam + t`, Euler XYZ, R = Rx·Ry·Rz — the cell file's convention).

use metrocell_kinematics::frame_alignment_procedure::Alignment;
use metrocell_kinematics::instrument_pose::InstrumentPose;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::{Quaternion, Transform, TransformStamped, Vector3};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use nalgebra::{Rotation3, UnitQuaternion};

/// The camera's frame in the tool's as `/tf_static` carries it.
pub fn tf_static(a: &Alignment, tool_link: &str, camera_link: &str, stamp: Time) -> TFMessage {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(a.rotation));
    TFMessage {
        transforms: vec![TransformStamped {
            header: Header {
                stamp,
                frame_id: tool_link.to_string(),
            },
            child_frame_id: camera_link.to_string(),
            transform: Transform {
                translation: Vector3 {
                    x: a.offset.x,
                    y: a.offset.y,
                    z: a.offset.z,
                },
                rotation: Quaternion {
                    x: q.i,
                    y: q.j,
                    z: q.k,
                    w: q.w,
                },
            },
        }],
    }
}

/// The result's standard uncertainties in words (mm, degrees).
pub fn uncertainty(a: &Alignment) -> String {
    let c = &a.offset_covariance;
    format!(
        "σ offset x {:.4} y {:.4} z {:.4} mm, rotation {:.4}° about each axis",
        c[(0, 0)].sqrt() * 1e3,
        c[(1, 1)].sqrt() * 1e3,
        c[(2, 2)].sqrt() * 1e3,
        a.rotation_sigma.to_degrees()
    )
}

/// The `mount:` line of a cell file's `sensors.camera` (mm and degrees), its uncertainty as a
/// comment above it.
pub fn cell_mount(a: &Alignment) -> String {
    let pose = InstrumentPose::from_rotation(a.offset, &a.rotation);
    let t = a.offset * 1e3;
    let e = pose.euler_xyz.map(f64::to_degrees);
    format!(
        "# metrocell align: {}\nmount: {{translation: [{:.4} mm, {:.4} mm, {:.4} mm], euler_xyz: [{:.5} deg, {:.5} deg, {:.5} deg]}}\n",
        uncertainty(a),
        t.x, t.y, t.z, e[0], e[1], e[2]
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3 as V3};

    fn alignment() -> Alignment {
        Alignment {
            rotation: Rotation3::from_euler_angles(3.0, 0.1, -0.2).into_inner(),
            offset: V3::new(0.06, -0.01, 0.02),
            rotation_sigma: 1e-4,
            offset_covariance: Matrix3::identity() * 1e-10,
            passes: Default::default(),
        }
    }

    #[test]
    fn the_cell_mount_reads_back_as_the_same_frame() {
        let a = alignment();
        let text = cell_mount(&a);
        assert!(
            text.starts_with("# metrocell align: σ offset x 0.0100"),
            "{text}"
        );
        let line = text.lines().nth(1).unwrap();
        // parse the numbers back and rebuild R = Rx·Ry·Rz
        let nums: Vec<f64> = line
            .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
            .filter_map(|w| w.parse().ok())
            .collect();
        let [x, y, z, al, be, de] = nums[..] else {
            panic!("{line}")
        };
        let r = metrocell_kinematics::transform::euler_xyz(
            al.to_radians(),
            be.to_radians(),
            de.to_radians(),
        );
        assert!((r - a.rotation).abs().max() < 1e-6, "{line}");
        assert!((V3::new(x, y, z) * 1e-3 - a.offset).norm() < 1e-7);
    }

    #[test]
    fn tf_static_carries_the_rotation_and_offset() {
        let a = alignment();
        let m = tf_static(&a, "tool0", "camera", Time::default());
        let t = &m.transforms[0];
        assert_eq!(
            (t.header.frame_id.as_str(), t.child_frame_id.as_str()),
            ("tool0", "camera")
        );
        let q = t.transform.rotation.clone();
        let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z));
        let diff: Matrix3<f64> = r.to_rotation_matrix().into_inner() - a.rotation;
        assert!(diff.abs().max() < 1e-12);
        assert_eq!(t.transform.translation.x, 0.06);
    }
}
