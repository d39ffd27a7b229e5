//! The instrument's placements (a recording's `setup` column) in a calibration: one pose per
//! setup, setups with too few fit points named and set aside, the stationing step (`--refit
//! poses`: only the poses fitted, the physics kept) and the check points predicted by the model
//! before and after.

use metrocell_estimation::check_points::check_report_of;
use metrocell_estimation::check_points::is_placement_parameter;
use metrocell_estimation::{fit, CheckReport, Fit, FitOptions, RecordSet};
use metrocell_model::{ForwardModel, ParameterSetup};

/// `setup` with only the placements' parameters free (the poses, the base's tilt).
pub fn poses_only(setup: &ParameterSetup) -> ParameterSetup {
    let mut out = setup.clone();
    for (k, name) in setup.names.iter().enumerate() {
        out.free[k] = setup.free[k] && is_placement_parameter(name);
    }
    out
}

/// The check points as predicted by three models, each with its placements fitted to the fit
/// points: `nominal` (every term at its catalog default: the kinematics alone), `declared` (the
/// model file's values) and `fitted` (this calibration's result).
pub struct CheckComparison {
    pub nominal: CheckReport,
    pub declared: CheckReport,
    pub fitted: CheckReport,
}

/// Predict the check points of `records` (module doc). `fitted` is the calibration's fit.
pub fn compare_on_check_points(
    fm: &ForwardModel,
    setup: &ParameterSetup,
    records: &RecordSet,
    fitted: &Fit,
    options: &FitOptions,
) -> anyhow::Result<CheckComparison> {
    let stationed = |start: Vec<f64>| -> anyhow::Result<CheckReport> {
        let only = poses_only(setup);
        let mut x = metrocell_estimation::start_vector(fm, &only, records)?;
        // the physics at `start`, the placements registered from the fit points
        for (k, name) in setup.names.iter().enumerate() {
            if !is_placement_parameter(name) {
                x[k] = start[k];
            }
        }
        let f = fit(fm, &only, records, Some(x), options)?;
        Ok(check_report_of(fm, &f.x, &records.check))
    };
    let declared = stationed(fm.params())?;
    let nominal = stationed(nominal_values(fm))?;
    Ok(CheckComparison {
        nominal,
        declared,
        fitted: check_report_of(fm, &fitted.x, &records.check),
    })
}

/// Every machine term's parameters at their catalog defaults (the instrument's as declared).
fn nominal_values(fm: &ForwardModel) -> Vec<f64> {
    let mut x = fm.params();
    let mut k = 0;
    for t in &fm.machine_terms.terms {
        for spec in t.term.params() {
            x[k] = spec.default;
            k += 1;
        }
    }
    x
}

/// The comparison in words, mm.
pub fn check_lines(c: &CheckComparison) -> Vec<String> {
    let mm = |v: f64| v * 1e3;
    let row = |what: &str, r: &CheckReport| {
        format!(
            "  {what:<9} p50 xy {:.2} mm, p95 xy {:.2} mm, p95 z {:.2} mm, max {:.2} mm",
            mm(r.overall.p50_xy_m),
            mm(r.overall.p95_xy_m),
            mm(r.overall.p95_z_m),
            mm(r.overall.max_m)
        )
    };
    let mut out = vec![format!("check points ({} predicted, kept out of the fit; each model with its placements fitted to the fit points; xy horizontal in the instrument's frame):", c.fitted.overall.n)];
    out.push(row("nominal", &c.nominal));
    out.push(row("declared", &c.declared));
    out.push(row("fitted", &c.fitted));
    for (name, s) in &c.fitted.setups {
        out.push(format!(
            "    setup {name}: {} points, fitted p95 xy {:.2} mm, p95 z {:.2} mm",
            s.n,
            mm(s.p95_xy_m),
            mm(s.p95_z_m)
        ));
    }
    if !c.fitted.unpredicted.is_empty() {
        let first = &c.fitted.unpredicted[0];
        out.push(format!(
            "  {} check point(s) unpredicted, e.g. {}: {}",
            c.fitted.unpredicted.len(),
            first.point_id,
            first.reason
        ));
    }
    out
}

/// The comparison as JSON: `{nominal|declared|fitted: {overall, setups: {NAME: …}, unpredicted}}`
/// (the statistics as crates/estimation serialises them, NaN as null).
pub fn check_json(c: &CheckComparison) -> serde_json::Value {
    use serde_json::json;
    let report = |r: &CheckReport| {
        json!({
            "overall": r.overall,
            "setups": r.setups,
            "unpredicted": r.unpredicted.iter().map(|u| json!({"point_id": u.point_id, "setup": u.setup, "reason": u.reason})).collect::<Vec<_>>(),
        })
    };
    json!({"nominal": report(&c.nominal), "declared": report(&c.declared), "fitted": report(&c.fitted)})
}
