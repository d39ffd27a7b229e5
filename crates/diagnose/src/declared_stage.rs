//! Stages 1–2 of the diagnosis: the records made ready, and the declared model fitted to them.
//!
//! The declared model carries the instrument pose its readings need (the model-file loader's:
//! free when the records are in an instrument frame, the identity otherwise); unusable records
//! are set aside with the reason, repeats of a stationary point averaged; the declared free parameters are fitted (so a mis-set
//! declared parameter is not taken for missing physics); gross outliers are set aside and the fit
//! repeated; a model that leaves millimetres after its own fit is refused with what to check.

use metrocell_estimation::{estimate_nests, fit, is_reference, Fit, MeasurementRecord, RecordSet};
use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::model::TermModel;
use metrocell_physics::PhysicsError;
use nalgebra::Vector3;

use crate::outliers::{outliers, robust_scale};
use crate::pipeline::{DeclaredModel, DiagnoseError, DiagnoseOptions, Progress};
use crate::record_preparation::prepare;
use crate::residual_view::ResidualView;

/// The declared model with its instrument pose, fitted.
pub(crate) struct DeclaredStage {
    /// The declared instrument terms (with the loader's `tracker_pose`).
    pub instruments: TermModel,
    pub setup: ParameterSetup,
    /// The records the diagnosis uses (prepared, outliers set aside).
    pub set: RecordSet,
    pub readings: usize,
    pub groups: usize,
    /// √(pooled χ²/dof) of repeated readings and its degrees of freedom.
    pub repeatability: Option<(f64, usize)>,
    pub rejected: Vec<String>,
    pub outlier_notes: Vec<String>,
    pub fit: Fit,
}

/// The declared instrument terms as the model-file loader made them (its one rule gives every
/// model a `tracker_pose`, crates/model_file `instrument_terms`: free if the records are in an
/// instrument frame, the identity otherwise), and the declared setup over them.
pub(crate) fn declared_instruments(
    declared: &DeclaredModel,
) -> Result<(TermModel, ParameterSetup), PhysicsError> {
    let instruments = declared.instrument_terms.clone();
    let model = ForwardModel::new(declared.machine, declared.machine_terms, &instruments)?;
    let setup = setup_by_name(&model, declared.setup, &|_| true);
    Ok((instruments, setup))
}

/// A setup for `model` taking free/fixed and priors from `old` by name; parameters `old` does
/// not know are free when `new_free(name)`.
pub(crate) fn setup_by_name(
    model: &ForwardModel,
    old: &ParameterSetup,
    new_free: &dyn Fn(&str) -> bool,
) -> ParameterSetup {
    let mut setup = ParameterSetup::all_free(model);
    for (k, name) in setup.names.clone().iter().enumerate() {
        match old.names.iter().position(|n| n == name) {
            Some(j) => {
                setup.free[k] = old.free[j];
                setup.priors[k] = old.priors[j];
            }
            None => setup.free[k] = new_free(name),
        }
    }
    setup
}

/// Records made ready and the declared model fitted (stages 1 and 2).
pub(crate) fn declared_stage(
    declared: &DeclaredModel,
    records: &RecordSet,
    options: &DiagnoseOptions,
    progress: &Progress,
) -> Result<DeclaredStage, DiagnoseError> {
    let (instruments, setup) = declared_instruments(declared)?;
    let model = ForwardModel::new(declared.machine, declared.machine_terms, &instruments)?;
    let prep = prepare(
        &records.records,
        options.average_repeats,
        options.repeat_gap_s,
    );
    let rejected: Vec<String> = records
        .rejected
        .iter()
        .chain(&prep.rejected)
        .map(|r| format!("{} ({}): {}", r.at, r.point_id, r.reason))
        .collect();
    if prep.records.is_empty() {
        return Err(DiagnoseError::NoRecords(if rejected.is_empty() {
            "the recording holds no measured points".into()
        } else {
            format!(
                "every record was set aside: {}",
                rejected
                    .iter()
                    .take(5)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join("; ")
            )
        }));
    }
    // reference nests only inform the instrument's terms: the declared model is fitted to the
    // machine's points, the nests placed from their own readings at that fit
    let (mut references, points): (Vec<MeasurementRecord>, Vec<MeasurementRecord>) =
        prep.records.iter().cloned().partition(is_reference);
    check_records(declared, &setup, &points)?;
    let mut set = RecordSet {
        check: records.check.clone(),
        frame: records.frame.clone(),
        records: points,
        rejected: vec![],
        sources: records.sources.clone(),
    };
    progress.say(&format!("{} readings → {} records ({} groups of repeats averaged, {} readings of reference nests); fitting the declared model", prep.readings, prep.records.len(), prep.groups, references.len()));
    let mut declared_fit =
        fit(&model, &setup, &set, None, &options.fit).map_err(DiagnoseError::DeclaredFit)?;
    let outlier_notes =
        set_outliers_aside(&model, &declared_fit, &mut set, options.outlier_threshold)?;
    if !outlier_notes.is_empty() {
        declared_fit =
            fit(&model, &setup, &set, None, &options.fit).map_err(DiagnoseError::DeclaredFit)?;
    }
    check_mismatch(&declared_fit, &set)?;
    if !references.is_empty() {
        estimate_nests(&model, &declared_fit.x, &mut references, &set.frame, true)?;
        set.records.extend(references);
    }
    Ok(DeclaredStage {
        instruments,
        setup,
        set,
        readings: prep.readings,
        groups: prep.groups,
        repeatability: prep.repeatability_scale,
        rejected,
        outlier_notes,
        fit: declared_fit,
    })
}

/// Enough records for the free parameters, and of this machine (its joint count).
fn check_records(
    declared: &DeclaredModel,
    setup: &ParameterSetup,
    records: &[MeasurementRecord],
) -> Result<(), DiagnoseError> {
    let n_free = setup.free.iter().filter(|f| **f).count();
    let needed = (n_free + 10).div_ceil(3).max(12);
    if records.len() < needed {
        return Err(DiagnoseError::TooFew(format!(
            "{} usable measured points for {} free declared parameters; needs at least {} points spread over the workspace (and over time) to fit the declared model and still hold some back to judge candidates",
            records.len(),
            n_free,
            needed
        )));
    }
    let joints = declared.machine.joint_names();
    if let Some(r) = records.iter().find(|r| r.q.len() != joints.len()) {
        return Err(DiagnoseError::Mismatch(format!(
            "the records carry {} joint values per point (point `{}` at t = {:.3} s), the model's machine has {} ({}): the recording is of another machine, or the model file is the wrong one",
            r.q.len(),
            r.point_id,
            r.time,
            joints.len(),
            joints.join(" ")
        )));
    }
    Ok(())
}

/// Gross outliers of the declared fit (far outside the robust scatter and unlike their
/// neighbours in time and in the workspace) taken out of `set`, each said in words.
fn set_outliers_aside(
    model: &ForwardModel,
    declared_fit: &Fit,
    set: &mut RecordSet,
    threshold: f64,
) -> Result<Vec<String>, DiagnoseError> {
    let view = ResidualView::new(model, &declared_fit.x, &set.records, &set.frame)?;
    let z: Vec<Vector3<f64>> = (0..view.len())
        .map(|i| view.whitening[i] * view.residual[i])
        .collect();
    let out = outliers(&z, &view.time, &view.position, threshold);
    if out.is_empty() {
        return Ok(Vec::new());
    }
    let scatter =
        robust_scale(&z.iter().flat_map(|v| v.iter().copied()).collect::<Vec<_>>()).max(1e-12);
    let notes = out
        .iter()
        .map(|&i| {
            let r = &set.records[i];
            format!(
                "t = {:.1} s, point `{}` ({}): residual {:.1} µm, {:.0}× the robust scatter",
                r.time,
                r.point_id,
                r.channel,
                view.residual[i].norm() * 1e6,
                z[i].amax() / scatter
            )
        })
        .collect();
    set.records = set
        .records
        .iter()
        .enumerate()
        .filter(|(i, _)| !out.contains(i))
        .map(|(_, r)| r.clone())
        .collect();
    Ok(notes)
}

/// A model of another machine leaves millimetres after its own fit: refused with what to check.
fn check_mismatch(declared_fit: &Fit, set: &RecordSet) -> Result<(), DiagnoseError> {
    let n = set.records.len();
    let rms = metrocell_estimation::rms(&declared_fit.residuals_after);
    let noise = (set
        .records
        .iter()
        .map(|r| r.covariance.trace())
        .sum::<f64>()
        / (3 * n) as f64)
        .sqrt();
    if rms > 5e-4 && rms > 100.0 * noise {
        return Err(DiagnoseError::Mismatch(format!(
            "after fitting its own parameters the model still misses the measured points by {:.2} mm RMS ({:.0}× the stated noise of {:.1} µm): check the machine family and geometry, the tool offset, the instrument frame of the points, and the units of the recording",
            rms * 1e3,
            rms / noise,
            noise * 1e6
        )));
    }
    Ok(())
}
