//! `machine:` — the machine family and its geometry ([`MachineGeometry`]), and the pose
//! sections (`translation`, `euler_xyz`) every instrument and mount is written with.

use std::path::Path;

use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_model::{InstrumentPose, MachineGeometry, MachineKinematics};
use nalgebra::Vector3;

use crate::cell_file::{AccelerometerSection, MachineFamily, MachineSection, PoseSection};
use crate::error::CellError;
use crate::quantity::vector3;

/// The validated machine of a file's `machine:` section; `accelerometers` (a serial arm's,
/// each on a link of its URDF) are checked against the family; relative paths (a URDF) are
/// relative to `base_dir`.
pub fn machine(
    m: &MachineSection,
    accelerometers: &[AccelerometerSection],
    base_dir: &Path,
) -> Result<MachineGeometry, CellError> {
    check_family_sections(m)?;
    if !accelerometers.is_empty() && m.family != MachineFamily::SerialArm {
        return Err(CellError::invalid("sensors.accelerometers", format!("is for a serial arm's accelerometers (each on a link of its URDF); this machine is {}", family_name(m.family))));
    }
    let kinematics = match m.family {
        MachineFamily::Cartesian => {
            let stacking = m.stacking.as_deref().ok_or_else(|| {
                CellError::invalid(
                    "machine.stacking",
                    "is required for a cartesian machine (e.g. XFYZ, FXYZ, XYFZ)",
                )
            })?;
            MachineKinematics::Cartesian(stacking.parse().map_err(|e| {
                CellError::invalid(
                    "machine.stacking",
                    format!("{e}; allowed: the letters X, Y, Z and F once each, e.g. XFYZ"),
                )
            })?)
        }
        MachineFamily::Delta => {
            let d = m.delta.as_ref().ok_or_else(|| {
                CellError::invalid(
                    "machine.delta",
                    "is required for a delta machine: {rod_length, radius}",
                )
            })?;
            let rod = d.rod_length.positive("machine.delta.rod_length", "m")?;
            let radius = d.radius.positive("machine.delta.radius", "m")?;
            MachineKinematics::Delta(
                DeltaGeometry::new(rod, radius)
                    .map_err(|e| CellError::invalid("machine.delta", e.to_string()))?,
            )
        }
        MachineFamily::FiveAxis => {
            let s = m.five_axis.as_ref().ok_or_else(|| {
                CellError::invalid(
                    "machine.five_axis",
                    format!("is required for a five_axis machine: {}", FIVE_AXIS_KEYS),
                )
            })?;
            MachineKinematics::FiveAxis(crate::families::five_axis(s)?)
        }
        MachineFamily::SerialArm => {
            let s = m.serial_arm.as_ref().ok_or_else(|| {
                CellError::invalid(
                    "machine.serial_arm",
                    format!("is required for a serial_arm machine: {}", SERIAL_ARM_KEYS),
                )
            })?;
            let arm = crate::families::serial_arm(s, accelerometers, base_dir, pose)?;
            let inf = [f64::NEG_INFINITY, f64::INFINITY];
            return Ok(MachineGeometry {
                kinematics: MachineKinematics::SerialArm(arm),
                travel: [inf; 3],
                tool_offset: Vector3::zeros(),
            });
        }
    };
    let tr = m.travel.as_ref().ok_or_else(|| {
        CellError::invalid(
            "machine.travel",
            format!(
                "is required for a {} machine: {{x: [min, max], y: [min, max], z: [min, max]}} (m)",
                family_name(m.family)
            ),
        )
    })?;
    let mut travel = [[0.0; 2]; 3];
    for (i, (name, r)) in [("x", &tr.x), ("y", &tr.y), ("z", &tr.z)]
        .into_iter()
        .enumerate()
    {
        let lo = r[0].to_si(&format!("machine.travel.{name}[0]"), "m")?;
        let hi = r[1].to_si(&format!("machine.travel.{name}[1]"), "m")?;
        if !(hi > lo) {
            return Err(CellError::invalid(
                format!("machine.travel.{name}"),
                format!("needs min < max, got [{lo}, {hi}] m"),
            ));
        }
        travel[i] = [lo, hi];
    }
    let tool_offset = m
        .tool_offset
        .as_ref()
        .map(|v| vector3(v, "machine.tool_offset", "m"))
        .transpose()?
        .unwrap_or_else(Vector3::zeros);
    Ok(MachineGeometry {
        kinematics,
        travel,
        tool_offset,
    })
}

const FIVE_AXIS_KEYS: &str =
    "{d0, tool_length, b_pivot, c_offset, workpiece_offset, b_limits, c_limits}";
const SERIAL_ARM_KEYS: &str =
    "{dh: {convention, rows} | urdf: {path, root_link, tip_link}, base, tool, joint_limits}";

/// The `machine.*` keys that belong to some families only: a key given for another family is
/// an error naming who takes it and what this family takes instead.
fn check_family_sections(m: &MachineSection) -> Result<(), CellError> {
    use MachineFamily::*;
    let own = match m.family {
        Cartesian => "machine.stacking (e.g. XFYZ)".to_string(),
        Delta => "machine.delta {rod_length, radius}".to_string(),
        FiveAxis => format!("machine.five_axis {FIVE_AXIS_KEYS}"),
        SerialArm => {
            format!("machine.serial_arm {SERIAL_ARM_KEYS} with joint limits and tool frame in it")
        }
    };
    let rules: [(&str, bool, &[MachineFamily]); 6] = [
        ("stacking", m.stacking.is_some(), &[Cartesian]),
        ("delta", m.delta.is_some(), &[Delta]),
        ("five_axis", m.five_axis.is_some(), &[FiveAxis]),
        ("serial_arm", m.serial_arm.is_some(), &[SerialArm]),
        ("travel", m.travel.is_some(), &[Cartesian, Delta, FiveAxis]),
        ("tool_offset", m.tool_offset.is_some(), &[Cartesian, Delta]),
    ];
    for (key, present, families) in rules {
        if present && !families.contains(&m.family) {
            let owners = families
                .iter()
                .map(|f| family_name(*f))
                .collect::<Vec<_>>()
                .join(", ");
            return Err(CellError::invalid(
                format!("machine.{key}"),
                format!(
                    "is for family: {owners}; this cell's family is {}, a {} machine takes {own}",
                    family_name(m.family),
                    family_name(m.family)
                ),
            ));
        }
    }
    Ok(())
}

fn family_name(f: MachineFamily) -> &'static str {
    match f {
        MachineFamily::Cartesian => "cartesian",
        MachineFamily::Delta => "delta",
        MachineFamily::FiveAxis => "five_axis",
        MachineFamily::SerialArm => "serial_arm",
    }
}

/// A pose section (`translation`, `euler_xyz` = Rx·Ry·Rz angles, default 0) at `path`.
pub fn pose(p: &PoseSection, path: &str) -> Result<InstrumentPose, CellError> {
    let t = vector3(&p.translation, &format!("{path}.translation"), "m")?;
    let e = match &p.euler_xyz {
        Some(e) => vector3(e, &format!("{path}.euler_xyz"), "rad")?,
        None => Vector3::zeros(),
    };
    Ok(InstrumentPose::from_euler_xyz(t, [e.x, e.y, e.z]))
}
