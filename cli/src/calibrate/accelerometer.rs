//! The base accelerometer's alignment against the levelled instrument, beside a fit that has the
//! base's tilt (crates/estimation `accelerometer_alignment`): said in words and in the JSON.

use metrocell_estimation::accelerometer_alignment::{
    base_accelerometer_alignment, prediction_effect, AccelerometerAlignment,
};
use metrocell_estimation::{Fit, RecordSet};
use metrocell_model::machine::MachineKinematics;
use metrocell_model::ForwardModel;
use nalgebra::{Matrix2, Vector2};
use serde_json::{json, Value};

/// The alignment and the largest change it makes to a fitted point's prediction (m).
pub struct AlignmentFinding {
    pub alignment: AccelerometerAlignment,
    pub effect_max_m: Option<f64>,
}

impl AlignmentFinding {
    /// Either component ≥ 3σ from zero.
    pub fn significant(&self) -> bool {
        self.alignment.significance().iter().any(|z| z.abs() >= 3.0)
    }
}

/// None unless the model is an arm with a base accelerometer, the fit has the base's tilt
/// (a levelled instrument) with its covariance, and the records hold the sensor's readings.
pub fn find(fm: &ForwardModel, f: &Fit, records: &RecordSet) -> Option<AlignmentFinding> {
    let MachineKinematics::SerialArm(arm) = &fm.machine.kinematics else {
        return None;
    };
    let names = fm.param_names();
    let at = |n: &str| names.iter().position(|p| p == n);
    let (r, p) = (at("base_tilt.roll")?, at("base_tilt.pitch")?);
    let cov = f.covariance.as_ref()?;
    let tilt = Vector2::new(f.x[r], f.x[p]);
    let tilt_cov = Matrix2::new(cov[(r, r)], cov[(r, p)], cov[(p, r)], cov[(p, p)]);
    if !(tilt_cov[(0, 0)] > 0.0 && tilt_cov[(1, 1)] > 0.0) {
        return None;
    }
    let used: Vec<_> = f.used.iter().map(|&i| records.records[i].clone()).collect();
    let alignment = base_accelerometer_alignment(arm, &used, tilt, tilt_cov)?;
    let effect_max_m = prediction_effect(fm, &f.x, &used, tilt);
    Some(AlignmentFinding {
        alignment,
        effect_max_m,
    })
}

pub fn lines(a: &AlignmentFinding) -> Vec<String> {
    let al = &a.alignment;
    let z = al.significance();
    let sig = |z: f64| {
        if z.abs() >= 3.0 {
            "significant"
        } else {
            "not significant (< 3σ)"
        }
    };
    let mut out = vec![format!(
        "accelerometer_alignment[{}]: the base accelerometer reads roll {:+.3} ± {:.3} mrad ({}), pitch {:+.3} ± {:.3} mrad ({}) off the levelled instrument's level, over {} readings (its mounting misalignment and bias/g together)",
        al.sensor,
        al.alignment.x * 1e3,
        al.covariance[(0, 0)].sqrt() * 1e3,
        sig(z.x),
        al.alignment.y * 1e3,
        al.covariance[(1, 1)].sqrt() * 1e3,
        sig(z.y),
        al.readings
    )];
    if let Some(e) = a.effect_max_m {
        out.push(format!("  gravity from the instrument's level instead of the accelerometer changes a fitted point's prediction by at most {:.1} µm", e * 1e6));
    }
    out
}

pub fn to_json(a: &AlignmentFinding) -> Value {
    let al = &a.alignment;
    json!({
        "significant": a.significant(),
        "sensor": al.sensor,
        "roll_rad": al.alignment.x,
        "pitch_rad": al.alignment.y,
        "sigma_roll_rad": al.covariance[(0, 0)].sqrt(),
        "sigma_pitch_rad": al.covariance[(1, 1)].sqrt(),
        "covariance_rad2": [[al.covariance[(0, 0)], al.covariance[(0, 1)]], [al.covariance[(1, 0)], al.covariance[(1, 1)]]],
        "accelerometer_tilt_rad": [al.accelerometer_tilt.x, al.accelerometer_tilt.y],
        "readings": al.readings,
        "significance_sigma": [al.significance().x, al.significance().y],
        "prediction_effect_max_m": a.effect_max_m,
    })
}
