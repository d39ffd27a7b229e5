//! A fitted machine model as the compensator's error field: e(C) = true − nominal tool point
//! of the shared forward model (crates/model) at the commanded axis position C, for the
//! approach direction of each axis — the sum of the model's machine terms (geometric, thermal,
//! load), nothing of the instruments.
//!
//! The program's X Y Z are the commanded axis coordinates q of a cartesian or delta machine
//! (crates/model `machine`: tool point = q + tool offset, so e is the same for the tool tip and
//! for q). Five-axis and serial-arm programs are not X Y Z programs and are refused.
//! Terms that read signals besides the axes need them as conditions of the compensation: the
//! temperatures (°C) the part will be cut at, a load. The region is the machine's travel.

use std::cell::RefCell;

use metrocell_model::{ForwardModel, KinematicTruth, MachineKinematics};
use metrocell_physics::Signals;
use nalgebra::Vector3;

use crate::error_field::{ErrorField, FieldError, Region};

/// Why a model cannot be a G-code error field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ModelFieldError(pub String);

/// The error field of a forward model at fixed parameters and conditions.
pub struct ModelErrorField<'m, 'a> {
    model: &'m ForwardModel<'a>,
    params: Vec<f64>,
    kin: KinematicTruth,
    conditions: Signals,
    region: Region,
    scratch: RefCell<Signals>,
}

impl<'m, 'a> ModelErrorField<'m, 'a> {
    /// `params`: the stacked parameter vector (the model's configured one for a fitted model
    /// file); `conditions`: temperatures, load and other signals the terms read (the axis signals
    /// are set per point). The field is evaluated once here at the travel's centre so a missing
    /// signal is reported now, not halfway through a program.
    pub fn new(
        model: &'m ForwardModel<'a>,
        params: Vec<f64>,
        conditions: Signals,
    ) -> Result<Self, ModelFieldError> {
        match model.machine.kinematics {
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_) => {}
            _ => return Err(ModelFieldError("G-code compensation needs a machine whose program coordinates are X Y Z (family cartesian or delta); five_axis and serial_arm programs are joint or pose programs".into())),
        }
        let kin = model
            .kinematic_truth(&params)
            .map_err(|e| ModelFieldError(e.to_string()))?;
        let t = model.machine.travel;
        let region = Region {
            min: Vector3::new(t[0][0], t[1][0], t[2][0]),
            max: Vector3::new(t[0][1], t[1][1], t[2][1]),
        };
        let field = Self {
            model,
            params,
            kin,
            scratch: RefCell::new(conditions.clone()),
            conditions,
            region,
        };
        let centre = (region.min + region.max) / 2.0;
        field
            .error(&centre, &[1.0; 3])
            .map_err(|e| ModelFieldError(format!("the model cannot be evaluated: {}", e.0)))?;
        Ok(field)
    }
}

impl ErrorField for ModelErrorField<'_, '_> {
    fn error(
        &self,
        commanded: &Vector3<f64>,
        approach: &[f64; 3],
    ) -> Result<Vector3<f64>, FieldError> {
        let mut s = self.scratch.borrow_mut();
        s.clone_from(&self.conditions);
        let q = [commanded.x, commanded.y, commanded.z];
        self.model.set_motion(&mut s, &q, &[0.0; 3], approach);
        let tool = self
            .model
            .tool_state(&self.params, &self.kin, &q, &mut s, None)
            .map_err(|e| FieldError(e.to_string()))?;
        Ok(tool.d)
    }

    fn calibrated_region(&self) -> Option<Region> {
        Some(self.region)
    }
}
