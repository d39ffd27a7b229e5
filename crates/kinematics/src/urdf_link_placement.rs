//! Where one link of a URDF sits relative to another when nothing between them moves: the
//! placement of a sensor's link (an accelerometer's `base_imu`) in the frame of a chain's root
//! link (`base_link`). The two links may lie on different branches of the link tree: the path
//! goes up from each to their nearest common ancestor. Every joint on that path must be `fixed`;
//! a movable joint (revolute, continuous, prismatic, …) makes the placement depend on the robot's
//! pose, and is named instead. Frames and rpy as in [`crate::urdf_chain`].

use nalgebra::Isometry3;

use crate::error::KinematicsError;
use crate::transform::from_xyz_rpy;

/// How a link is attached to a reference link.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkPlacement {
    /// Rigidly: `t_reference_link`, the link's frame in the reference link's frame.
    Fixed(Isometry3<f64>),
    /// Through a joint that moves (its name): no constant placement.
    Moves { joint: String },
}

/// Reads a URDF file (for [`link_placement`] and [`crate::urdf_chain::chain_from_robot`]).
pub fn read_urdf_file(path: &std::path::Path) -> Result<urdf_rs::Robot, KinematicsError> {
    urdf_rs::read_file(path).map_err(|e| KinematicsError::Urdf {
        reason: format!("{}: {e}", path.display()),
    })
}

/// The placement of `link` in the frame of `reference` (see the module doc). An unknown link, or
/// two links in unconnected trees, is an error naming the robot's links.
pub fn link_placement(
    robot: &urdf_rs::Robot,
    reference: &str,
    link: &str,
) -> Result<LinkPlacement, KinematicsError> {
    let (up_from_reference, up_from_link) = path_between(robot, reference, link)?;
    if let Some(j) = up_from_reference
        .iter()
        .chain(&up_from_link)
        .find(|j| j.joint_type != urdf_rs::JointType::Fixed)
    {
        return Ok(LinkPlacement::Moves {
            joint: j.name.clone(),
        });
    }
    // common ancestor → each link, composed from the ancestor down
    let down = |path: &[&urdf_rs::Joint]| {
        path.iter().rev().fold(Isometry3::identity(), |t, j| {
            t * from_xyz_rpy(j.origin.xyz.0, j.origin.rpy.0)
        })
    };
    Ok(LinkPlacement::Fixed(
        down(&up_from_reference).inverse() * down(&up_from_link),
    ))
}

/// How a link is turned relative to a reference link.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkRotation {
    /// By a constant rotation, `r_reference_link`: every joint between is fixed or prismatic (a
    /// prismatic joint slides its child along its axis without turning it — a sensor on top of
    /// a lifting column keeps its orientation as the column extends).
    Fixed(nalgebra::Matrix3<f64>),
    /// Through a joint that turns (revolute, continuous, floating, planar, …): named.
    Turns { joint: String },
}

/// The rotation of `link`'s frame in `reference`'s (see [`LinkRotation`]); errors as
/// [`link_placement`]'s.
pub fn link_rotation(
    robot: &urdf_rs::Robot,
    reference: &str,
    link: &str,
) -> Result<LinkRotation, KinematicsError> {
    let (up_from_reference, up_from_link) = path_between(robot, reference, link)?;
    let turns = |j: &&&urdf_rs::Joint| {
        !matches!(
            j.joint_type,
            urdf_rs::JointType::Fixed | urdf_rs::JointType::Prismatic
        )
    };
    if let Some(j) = up_from_reference.iter().chain(&up_from_link).find(turns) {
        return Ok(LinkRotation::Turns {
            joint: j.name.clone(),
        });
    }
    let down = |path: &[&urdf_rs::Joint]| {
        path.iter()
            .rev()
            .fold(nalgebra::Matrix3::<f64>::identity(), |r, j| {
                r * from_xyz_rpy([0.0; 3], j.origin.rpy.0)
                    .rotation
                    .to_rotation_matrix()
                    .into_inner()
            })
    };
    Ok(LinkRotation::Fixed(
        down(&up_from_reference).transpose() * down(&up_from_link),
    ))
}

/// The joints from each of `reference` and `link` up to their nearest common ancestor, each
/// list starting at its link's own parent joint.
fn path_between<'a>(
    robot: &'a urdf_rs::Robot,
    reference: &str,
    link: &str,
) -> Result<(Vec<&'a urdf_rs::Joint>, Vec<&'a urdf_rs::Joint>), KinematicsError> {
    let known = || {
        robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    for name in [reference, link] {
        if !robot.links.iter().any(|l| l.name == name) {
            return Err(KinematicsError::Urdf {
                reason: format!(
                    "robot `{}` has no link `{name}`; its links: {}",
                    robot.name,
                    known()
                ),
            });
        }
    }
    let mut up_from_reference = joints_to_root(robot, reference)?;
    let mut up_from_link = joints_to_root(robot, link)?;
    // drop the joints the two paths share (from the tree's root down to the common ancestor)
    while let (Some(a), Some(b)) = (up_from_reference.last(), up_from_link.last()) {
        if a.name != b.name {
            break;
        }
        up_from_reference.pop();
        up_from_link.pop();
    }
    let top = |path: &[&urdf_rs::Joint], start: &str| {
        path.last()
            .map(|j| j.parent.link.clone())
            .unwrap_or_else(|| start.to_string())
    };
    if top(&up_from_reference, reference) != top(&up_from_link, link) {
        return Err(KinematicsError::Urdf { reason: format!("links `{reference}` and `{link}` of robot `{}` are in unconnected trees; its links: {}", robot.name, known()) });
    }
    Ok((up_from_reference, up_from_link))
}

/// The joints from `link` up to the tree's root, the link's own parent joint first.
fn joints_to_root<'a>(
    robot: &'a urdf_rs::Robot,
    link: &str,
) -> Result<Vec<&'a urdf_rs::Joint>, KinematicsError> {
    let mut path = Vec::new();
    let mut current = link.to_string();
    while let Some(j) = robot.joints.iter().find(|j| j.child.link == current) {
        path.push(j);
        if path.len() > robot.joints.len() {
            return Err(KinematicsError::Urdf {
                reason: format!(
                    "robot `{}`: the joint graph has a cycle through link `{link}`",
                    robot.name
                ),
            });
        }
        current = j.parent.link.clone();
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    // base_link ─fixed→ base_imu (turned 90° about z, 0.1 m up)
    //           ─fixed→ column (0.2 m forward) ─prismatic→ top ─fixed→ top_imu
    const URDF: &str = r#"<robot name="r">
      <link name="base_link"/><link name="base_imu"/><link name="column"/><link name="top"/><link name="top_imu"/><link name="elsewhere"/>
      <joint name="imu_mount" type="fixed"><parent link="base_link"/><child link="base_imu"/><origin xyz="0 0 0.1" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="column_foot" type="fixed"><parent link="base_link"/><child link="column"/><origin xyz="0.2 0 0" rpy="0 0 0"/></joint>
      <joint name="lift" type="prismatic"><parent link="column"/><child link="top"/><axis xyz="0 0 1"/><limit lower="0" upper="1" effort="1" velocity="1"/></joint>
      <joint name="top_mount" type="fixed"><parent link="top"/><child link="top_imu"/></joint>
    </robot>"#;

    fn robot() -> urdf_rs::Robot {
        urdf_rs::read_from_string(URDF).unwrap()
    }

    fn fixed(p: LinkPlacement) -> Isometry3<f64> {
        match p {
            LinkPlacement::Fixed(t) => t,
            other => panic!("expected a fixed placement, got {other:?}"),
        }
    }

    #[test]
    fn a_fixed_child_of_the_root_is_its_joint_origin() {
        let t = fixed(link_placement(&robot(), "base_link", "base_imu").unwrap());
        let rz90 = Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        assert!((t.rotation.to_rotation_matrix().matrix() - rz90.matrix()).norm() < 1e-12);
        assert!((t.translation.vector - Vector3::new(0.0, 0.0, 0.1)).norm() < 1e-12);
    }

    #[test]
    fn a_sibling_branch_goes_through_the_common_ancestor() {
        // base_imu in column's frame: back 0.2 m, up 0.1 m, turned 90° about z
        let t = fixed(link_placement(&robot(), "column", "base_imu").unwrap());
        assert!((t.translation.vector - Vector3::new(-0.2, 0.0, 0.1)).norm() < 1e-12);
        assert!((t.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // and the reverse is its inverse
        let back = fixed(link_placement(&robot(), "base_imu", "column").unwrap());
        assert!(((t * back).translation.vector).norm() < 1e-12);
        assert_eq!(
            fixed(link_placement(&robot(), "top", "top").unwrap()),
            Isometry3::identity()
        );
    }

    #[test]
    fn a_movable_joint_between_is_named() {
        assert_eq!(
            link_placement(&robot(), "base_link", "top_imu").unwrap(),
            LinkPlacement::Moves {
                joint: "lift".into()
            }
        );
        // also when the reference is the link below the joint
        assert_eq!(
            link_placement(&robot(), "top_imu", "base_imu").unwrap(),
            LinkPlacement::Moves {
                joint: "lift".into()
            }
        );
    }

    #[test]
    fn a_link_behind_a_prismatic_joint_keeps_its_rotation_a_revolute_one_is_named() {
        let r = match link_rotation(&robot(), "base_link", "top_imu").unwrap() {
            LinkRotation::Fixed(r) => r,
            other => panic!("{other:?}"),
        };
        assert!((r - nalgebra::Matrix3::identity()).norm() < 1e-12, "{r}");
        // base_imu seen from top_imu: turned +90° about z
        let r = match link_rotation(&robot(), "top_imu", "base_imu").unwrap() {
            LinkRotation::Fixed(r) => r,
            other => panic!("{other:?}"),
        };
        let rz90 = Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        assert!((r - rz90.matrix()).norm() < 1e-12, "{r}");
        let turning = URDF.replace(r#"type="prismatic""#, r#"type="revolute""#);
        let robot = urdf_rs::read_from_string(&turning).unwrap();
        assert_eq!(
            link_rotation(&robot, "base_link", "top_imu").unwrap(),
            LinkRotation::Turns {
                joint: "lift".into()
            }
        );
    }

    #[test]
    fn unknown_and_unconnected_links_name_the_robots_links() {
        let e = link_placement(&robot(), "base_link", "imu")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no link `imu`")
                && e.contains("base_link, base_imu, column, top, top_imu, elsewhere"),
            "{e}"
        );
        let e = link_placement(&robot(), "base_link", "elsewhere")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unconnected trees"), "{e}");
    }
}
