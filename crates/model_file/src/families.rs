//! Builds the five-axis and serial-arm machines from the cell file's `machine.five_axis` and
//! `machine.serial_arm` sections. The machine types, their true chains and the joint-vector
//! conventions live in [`metrocell_model::machine`].

use std::path::Path;

use metrocell_kinematics::dh::{DhConvention, DhRow, DhTable};
use metrocell_kinematics::five_axis::FiveAxisGeometry;
use metrocell_kinematics::serial::JointKind;
use metrocell_kinematics::urdf_chain::chain_from_urdf_file;
use metrocell_kinematics::urdf_link_placement::{link_placement, read_urdf_file, LinkPlacement};
use nalgebra::{Isometry3, Vector3};

use crate::cell_file::{
    AccelerometerSection, DhConventionName, FiveAxisSection, JointKindName, SerialArmSection,
    UrdfSection,
};
use crate::error::CellError;
use crate::quantity::{vector3, Quantity};
use metrocell_model::{ArmAccelerometer, InstrumentPose};
pub use metrocell_model::{FiveAxisMachine, SerialArm, FIVE_AXIS_JOINTS};

fn opt_vec(v: &Option<[Quantity; 3]>, path: &str) -> Result<Vector3<f64>, CellError> {
    v.as_ref()
        .map(|v| vector3(v, path, "m"))
        .transpose()
        .map(|v| v.unwrap_or_else(Vector3::zeros))
}

fn limits(
    v: &Option<[Quantity; 2]>,
    path: &str,
    unit: &str,
    default: [f64; 2],
) -> Result<[f64; 2], CellError> {
    let Some(v) = v else { return Ok(default) };
    let lo = v[0].to_si(&format!("{path}[0]"), unit)?;
    let hi = v[1].to_si(&format!("{path}[1]"), unit)?;
    if !(hi > lo) {
        return Err(CellError::invalid(
            path,
            format!("needs min < max, got [{lo}, {hi}] {unit}"),
        ));
    }
    Ok([lo, hi])
}

/// Validated five-axis geometry from `machine.five_axis`.
pub fn five_axis(s: &FiveAxisSection) -> Result<FiveAxisMachine, CellError> {
    let p = "machine.five_axis";
    let mut g = FiveAxisGeometry::new(
        s.d0.to_si(&format!("{p}.d0"), "m")?,
        s.tool_length
            .non_negative(&format!("{p}.tool_length"), "m")?,
    );
    g.b_pivot = opt_vec(&s.b_pivot, &format!("{p}.b_pivot"))?;
    g.c_offset = opt_vec(&s.c_offset, &format!("{p}.c_offset"))?;
    g.workpiece_offset = opt_vec(&s.workpiece_offset, &format!("{p}.workpiece_offset"))?;
    let half = std::f64::consts::FRAC_PI_2;
    let b = limits(&s.b_limits, &format!("{p}.b_limits"), "rad", [-half, half])?;
    g.b_limits = (b[0], b[1]);
    let c_limits = limits(
        &s.c_limits,
        &format!("{p}.c_limits"),
        "rad",
        [-4.0 * half, 4.0 * half],
    )?;
    Ok(FiveAxisMachine {
        geometry: g,
        c_limits,
    })
}

/// Validated serial arm from `machine.serial_arm` and its `sensors.accelerometers`; a URDF
/// `path` is relative to `base_dir`.
pub fn serial_arm(
    s: &SerialArmSection,
    accelerometers: &[AccelerometerSection],
    base_dir: &Path,
    pose: impl Fn(&crate::cell_file::PoseSection, &str) -> Result<InstrumentPose, CellError>,
) -> Result<SerialArm, CellError> {
    let p = "machine.serial_arm";
    let (mut chain, dh) = match (&s.dh, &s.urdf) {
        (Some(_), Some(_)) | (None, None) => return Err(CellError::invalid(p, "needs exactly one of `dh` (a DH table: {convention: standard | modified, rows}) and `urdf` ({path, root_link, tip_link})")),
        (Some(d), None) => {
            if d.rows.is_empty() {
                return Err(CellError::invalid(format!("{p}.dh.rows"), "needs at least one row {theta, d, a, alpha, joint: revolute | prismatic | fixed}"));
            }
            let mut rows = Vec::new();
            for (i, r) in d.rows.iter().enumerate() {
                let rp = format!("{p}.dh.rows[{i}]");
                let v = |q: &Option<Quantity>, name: &str, unit: &str| q.as_ref().map(|q| q.to_si(&format!("{rp}.{name}"), unit)).transpose().map(|v| v.unwrap_or(0.0));
                let (theta, dd, a, alpha) = (v(&r.theta, "theta", "rad")?, v(&r.d, "d", "m")?, v(&r.a, "a", "m")?, v(&r.alpha, "alpha", "rad")?);
                check_dh_lengths(&rp, dd, a)?;
                rows.push(match r.joint {
                    JointKindName::Revolute => DhRow::revolute(theta, dd, a, alpha),
                    JointKindName::Prismatic => DhRow::prismatic(theta, dd, a, alpha),
                    JointKindName::Fixed => DhRow::fixed(theta, dd, a, alpha),
                });
            }
            let convention = match d.convention {
                DhConventionName::Standard => DhConvention::Standard,
                DhConventionName::Modified => DhConvention::Modified,
            };
            let table = DhTable::new(convention, rows).map_err(|e| CellError::invalid(format!("{p}.dh"), e.to_string()))?;
            (table.to_chain(), Some(table))
        }
        (None, Some(u)) => {
            let path = base_dir.join(&u.path);
            let chain = chain_from_urdf_file(&path, &u.root_link, &u.tip_link).map_err(|e| CellError::invalid(format!("{p}.urdf"), format!("{e} (path resolved relative to the cell file: {})", path.display())))?;
            (chain, None)
        }
    };
    if chain.dof() == 0 {
        return Err(CellError::invalid(p, "the chain has no movable joint"));
    }
    if let Some(b) = &s.base {
        chain.base = pose(b, &format!("{p}.base"))?.isometry();
    }
    if let Some(t) = &s.tool {
        chain.tool = pose(t, &format!("{p}.tool"))?.isometry();
    }
    let revolute: Vec<bool> = chain
        .joints
        .iter()
        .filter(|j| j.is_variable())
        .map(|j| j.kind == JointKind::Revolute)
        .collect();
    let joint_limits = if s.joint_limits.is_empty() {
        None
    } else {
        if s.joint_limits.len() != chain.dof() {
            return Err(CellError::invalid(
                format!("{p}.joint_limits"),
                format!(
                    "has {} entries; the arm has {} movable joints ({})",
                    s.joint_limits.len(),
                    chain.dof(),
                    chain.variable_names().join(", ")
                ),
            ));
        }
        let mut v = Vec::new();
        for (i, l) in s.joint_limits.iter().enumerate() {
            v.push(limits(
                &Some(l.clone()),
                &format!("{p}.joint_limits[{i}]"),
                if revolute[i] { "rad" } else { "m" },
                [0.0, 0.0],
            )?);
        }
        Some(v)
    };
    let accelerometers =
        arm_accelerometers(accelerometers, s.urdf.as_ref(), base_dir, &chain.base)?;
    Ok(SerialArm {
        chain,
        dh,
        joint_limits,
        revolute,
        accelerometers,
    })
}

/// The arm's accelerometers from `sensors.accelerometers`: each link looked up in the arm's
/// URDF. A sensor on a link fixed to the chain's root (fixed joints only, on any branch) gets
/// its rotation in the arm's base frame — the frame the chain's positions and its gravity are in,
/// `machine.serial_arm.base` included — and gives the ground's tilt; one behind a movable joint
/// (an IMU on a column's top) is kept by name without it.
fn arm_accelerometers(
    sensors: &[AccelerometerSection],
    urdf: Option<&UrdfSection>,
    base_dir: &Path,
    base: &Isometry3<f64>,
) -> Result<Vec<ArmAccelerometer>, CellError> {
    if sensors.is_empty() {
        return Ok(Vec::new());
    }
    let Some(u) = urdf else {
        return Err(CellError::invalid("sensors.accelerometers", "needs an arm from a URDF (`machine.serial_arm.urdf`): each accelerometer names the URDF link it sits on; a DH table has no links to name"));
    };
    let path = base_dir.join(&u.path);
    let robot = read_urdf_file(&path)
        .map_err(|e| CellError::invalid("machine.serial_arm.urdf", e.to_string()))?;
    let mut out: Vec<ArmAccelerometer> = Vec::new();
    for (i, a) in sensors.iter().enumerate() {
        let p = format!("sensors.accelerometers[{i}]");
        if a.name.is_empty() || out.iter().any(|o| o.name == a.name) {
            return Err(CellError::invalid(format!("{p}.name"), format!("`{}` must be a non-empty name no other accelerometer has (the `accel.<name>` columns and `/imu/<name>`)", a.name)));
        }
        let placement = link_placement(&robot, &u.root_link, &a.link).map_err(|e| {
            CellError::invalid(
                format!("{p}.link"),
                format!("{e} (URDF {})", path.display()),
            )
        })?;
        let base_from_sensor = match placement {
            LinkPlacement::Fixed(t) => Some(
                (base.rotation * t.rotation)
                    .to_rotation_matrix()
                    .into_inner(),
            ),
            LinkPlacement::Moves { .. } => None,
        };
        out.push(ArmAccelerometer {
            name: a.name.clone(),
            link: a.link.clone(),
            base_from_sensor,
        });
    }
    Ok(out)
}

/// A DH row's lengths as a machine has them: under 10 m. A bare number is metres, so an angle
/// written in a length column — seed 004's printed table has a₂ = 90, the α column's 90° — reads
/// as a 90 m link; that is refused with what it probably is, rather than built.
fn check_dh_lengths(row: &str, d: f64, a: f64) -> Result<(), CellError> {
    const LONGEST_LINK_M: f64 = 10.0;
    for (name, value) in [("d", d), ("a", a)] {
        if value.abs() > LONGEST_LINK_M {
            return Err(CellError::OutOfRange {
                path: format!("{row}.{name}"),
                value,
                reason: format!(
                    "is {value} m: `{name}` is a length (bare numbers are metres), longer than any \
                     machine's link; an angle belongs in theta or alpha (write `90 deg` there), \
                     a length in mm needs its unit (`90 mm`)"
                ),
            });
        }
    }
    Ok(())
}
