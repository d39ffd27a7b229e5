//! The calibrate result as JSON (`--json`): what the summary says, as numbers (SI units).

use std::path::Path;

use metrocell_estimation::{rms, Fit, RecordSet};
use serde_json::{json, Value};

pub fn result(
    f: &Fit,
    records: &RecordSet,
    output: &Path,
    check: Option<&super::placements::CheckComparison>,
    alignment: Option<&super::accelerometer::AlignmentFinding>,
) -> Value {
    json!({
        "accelerometer_alignment": alignment.map(super::accelerometer::to_json),
        "check": check.map(super::placements::check_json),
        "model": output.display().to_string(),
        "records": f.used.len(),
        "rejected": records.rejected.iter().map(|r| json!({"at": r.at, "point_id": r.point_id, "reason": r.reason})).chain(f.skipped.iter().map(|s| json!({"at": format!("record {}", s.index), "point_id": s.point_id, "reason": s.reason}))).collect::<Vec<_>>(),
        "residual_rms_m": {"before": rms(&f.residuals_before), "after": rms(&f.residuals_after)},
        "chi2_per_dof": f.chi2_per_dof,
        "degrees_of_freedom": f.solution.degrees_of_freedom,
        "parameters": f.parameters.iter().filter(|p| p.free).map(|p| json!({"name": p.name, "value": p.value, "sigma": p.sigma, "unit": p.unit, "at_bound": p.at_bound.map(|b| b.name()), "usual": usual_or_null(p.usual), "outside_usual": !(p.value >= p.usual.0 && p.value <= p.usual.1)})).collect::<Vec<_>>(),
        "at_bound": f.parameters.iter().filter(|p| p.free && p.at_bound.is_some()).map(|p| json!({"name": p.name, "bound": p.at_bound.map(|b| b.name()), "value": p.value})).collect::<Vec<_>>(),
        "not_identifiable": f.held.iter().map(|h| json!({"name": h.name, "statement": h.combination})).collect::<Vec<_>>(),
        "outliers": f.outliers.iter().map(|o| json!({"point_id": o.point_id, "time": o.time, "reason": o.reason})).collect::<Vec<_>>(),
        "downweighted_components": f.downweighted,
        "rank": f.identifiability.rank,
        "condition_number": f.identifiability.condition_number,
    })
}

/// A range as `[lo, hi]` with null for an unbounded side (JSON has no infinity).
fn usual_or_null(r: (f64, f64)) -> Value {
    let side = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    json!([side(r.0), side(r.1)])
}
