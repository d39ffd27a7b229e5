//! `terms:` — the machine's error terms (physics catalog configs) validated against the
//! machine: the same rule for a cell the twin simulates (the truth) and a model file (the
//! declared model). Instrument terms are not written here but with their sensor ([`home_of`]).

use std::collections::BTreeSet;

use metrocell_model::{MachineGeometry, MachineKinematics};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, EffectKind, Frame, SignalKind, TermConfig, TermId};

use crate::error::CellError;

/// Instrument and camera terms live with their sensor; say where.
pub fn home_of(id: &str) -> Option<&'static str> {
    match id {
        "tracker_warmup" => Some("sensors.tracker.warmup"),
        "refraction" => Some("sensors.tracker.station and environment.air.beam_temperature_offset"),
        "turbulence" => Some("sensors.tracker.turbulence and sensors.tracker.range_noise"),
        "probe_pretravel" => Some("sensors.probe.pretravel"),
        "tracker_pose" => Some("sensors.tracker.pose"),
        "lens_distortion" => Some("sensors.camera.intrinsics (model plumb_bob, distortion)"),
        "camera_scale" => Some("the fiducial node's `marker_size` parameter (the twin's camera itself has no scale error)"),
        _ => None,
    }
}

/// Displacement terms that read no axis signal: the ones a serial arm takes.
const ARM_DISPLACEMENT_TERMS: &str = "joint_compliance, joint_backlash, column_bending, link_thermal_expansion, thermal_growth, tool_offset, frame_misalignment, workpiece_expansion";

/// Validate the `terms` list against the machine. `sensors` (the thermocouple names) and
/// `has_load` are checked when known (a cell to simulate); a model file leaves them to the
/// recording (None), which names a missing signal when records are built.
pub fn terms(
    configs: &[TermConfig],
    sensors: Option<&BTreeSet<String>>,
    has_load: Option<bool>,
    machine: &MachineGeometry,
) -> Result<TermModel, CellError> {
    let is_delta = matches!(machine.kinematics, MachineKinematics::Delta(_));
    let arm = match &machine.kinematics {
        MachineKinematics::SerialArm(a) => Some(a),
        _ => None,
    };
    let mut model = TermModel::default();
    for (i, c) in configs.iter().enumerate() {
        let path = format!("terms[{i}] (id `{}`)", c.id);
        if let Some(home) = home_of(&c.id) {
            return Err(CellError::invalid(
                path,
                format!("is a sensor term; give it in {home}"),
            ));
        }
        let t = configure(c).map_err(|e| CellError::term(&path, e))?;
        let is_delta_term = matches!(
            t.term.id(),
            TermId::DeltaRodLength
                | TermId::DeltaRadius
                | TermId::DeltaTowerAngle
                | TermId::DeltaEndstop
        );
        if is_delta_term && !is_delta {
            return Err(CellError::invalid(
                path,
                "is a delta term; it needs machine.family: delta",
            ));
        }
        // an arm's gravity physics: joint and URDF names are checked by the forward model
        if matches!(
            t.term.id(),
            TermId::JointCompliance
                | TermId::JointBacklash
                | TermId::ColumnBending
                | TermId::LinkThermalExpansion
        ) {
            if arm.is_none() {
                return Err(CellError::invalid(path, "is a serial-arm gravity term; it needs machine.family: serial_arm (a URDF with <inertial> masses)"));
            }
            model
                .push(t)
                .map_err(|e| CellError::term(format!("terms[{i}]"), e))?;
            continue;
        }
        let is_arm_term = matches!(t.term.id(), TermId::JointOffset | TermId::LinkLength);
        if is_arm_term {
            let Some(a) = arm else {
                return Err(CellError::invalid(
                    path,
                    "is a serial-arm term; it needs machine.family: serial_arm",
                ));
            };
            let (key, want) = if t.term.id() == TermId::JointOffset {
                ("joints", a.chain.dof())
            } else {
                ("links", a.link_count())
            };
            if t.params.len() != want {
                return Err(CellError::invalid(
                    format!("{path}.options.{key}"),
                    format!(
                        "is {}; this arm has {want} ({})",
                        t.params.len(),
                        if key == "joints" {
                            "movable joints"
                        } else {
                            "DH rows / URDF joints"
                        }
                    ),
                ));
            }
            if t.term.id() == TermId::LinkLength && a.dh.is_none() {
                // a URDF link length is the length of the joint's <origin xyz>; a zero one has no direction
                for (k, (j, p)) in a.chain.joints.iter().zip(&t.params).enumerate() {
                    if *p != 0.0 && j.pre.translation.vector.norm() == 0.0 {
                        return Err(CellError::invalid(format!("{path}.params.l{}", k + 1), format!("URDF joint `{}` has a zero-length <origin xyz>, so it has no link length to change; set l{} to 0", j.name, k + 1)));
                    }
                }
            }
            model
                .push(t)
                .map_err(|e| CellError::term(format!("terms[{i}]"), e))?;
            continue;
        }
        if arm.is_some()
            && t.term.signals().iter().any(|s| {
                matches!(
                    s,
                    SignalKind::AxisPosition(_)
                        | SignalKind::ApproachDirection(_)
                        | SignalKind::AxisVelocity(_)
                        | SignalKind::LoadForce
                )
            })
        {
            return Err(CellError::invalid(
                path,
                format!("reads linear-axis signals, which a serial_arm does not have; a serial_arm takes joint_offset, link_length and {ARM_DISPLACEMENT_TERMS}"),
            ));
        }
        if !matches!(
            t.term.effect(),
            EffectKind::Displacement(Frame::Machine | Frame::Tool | Frame::Workpiece)
        ) && !is_delta_term
        {
            return Err(CellError::invalid(
                path,
                format!("has effect {:?}; the twin's `terms` take machine-frame displacement terms (geometry, thermal_scale, thermal_growth, compliance, tool_offset, time_offset), workpiece-frame terms (frame_misalignment, workpiece_expansion), for a delta delta_rod_length, delta_radius, delta_tower_angle, delta_endstop, and for a serial_arm joint_offset, link_length, joint_compliance, joint_backlash, column_bending, link_thermal_expansion", t.term.effect()),
            ));
        }
        for s in t.term.signals() {
            let unknown = |name: &String| sensors.is_some_and(|known| !known.contains(name));
            match &s {
                SignalKind::Temperature(name) if unknown(name) => {
                    return Err(CellError::invalid(
                        format!("{path}.options"),
                        format!("refers to temperature sensor `{name}`, which is not a thermocouple; allowed: {}", sensors.into_iter().flatten().cloned().collect::<Vec<_>>().join(", ")),
                    ))
                }
                SignalKind::TemperatureHistory(name) if unknown(name) => {
                    return Err(CellError::invalid(
                        format!("{path}.options"),
                        format!("refers to temperature sensor `{name}`, which is not a thermocouple; allowed: {}", sensors.into_iter().flatten().cloned().collect::<Vec<_>>().join(", ")),
                    ))
                }
                SignalKind::LoadForce if has_load == Some(false) => return Err(CellError::invalid(path, "needs environment.load_force")),
                _ => {}
            }
        }
        model
            .push(t)
            .map_err(|e| CellError::term(format!("terms[{i}]"), e))?;
    }
    Ok(model)
}
