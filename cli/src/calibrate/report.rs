//! The calibrate report: residuals before/after (histograms, over time, over the workspace),
//! the fitted error functions with their uncertainty bands, the parameters, the
//! identifiability table and the uncertainty budget — one HTML page with SVG figures
//! (crates/report).

use std::path::{Path, PathBuf};

use metrocell_estimation::error_functions::axis_error_functions;
use metrocell_estimation::fit_summary::value_with_sigma;
use metrocell_estimation::uncertainty_budget::Budget;
use metrocell_estimation::{rms, Fit, RecordSet};
use metrocell_model::ForwardModel;
use metrocell_model_file::CellModel;
use metrocell_report::{HistogramPlot, Report, ScatterPlot, Series, SeriesPlot, Table};

use super::CalibrateArgs;

const AXES: [&str; 3] = ["x", "y", "z"];

pub fn write(
    dir: &Path,
    a: &CalibrateArgs,
    model: &CellModel,
    fm: &ForwardModel,
    f: &Fit,
    records: &RecordSet,
    summary: &[String],
) -> anyhow::Result<PathBuf> {
    let mut r = Report::new(&format!("Calibration of {}", model.raw.name));
    let command = format!(
        "metrocell calibrate --model {} {} -o {}",
        a.model.display(),
        a.bags
            .iter()
            .map(|b| b.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        a.output.display()
    );
    r.section("Summary")
        .preformatted(&command)
        .preformatted(&summary.join("\n"));

    // residuals
    let used: Vec<&metrocell_estimation::MeasurementRecord> =
        f.used.iter().map(|&i| &records.records[i]).collect();
    let comps = |v: &[nalgebra::Vector3<f64>]| {
        v.iter()
            .flat_map(|r| r.iter().map(|c| c * 1e6).collect::<Vec<_>>())
            .collect::<Vec<f64>>()
    };
    let hist = HistogramPlot::new("Residual components, measured − model", "residual [µm]", 40)
        .sample("before the fit", comps(&f.residuals_before))
        .sample("after the fit", comps(&f.residuals_after))
        .svg()?;
    let t0 = used.first().map(|r| r.time).unwrap_or(0.0);
    let over_time = |v: &[nalgebra::Vector3<f64>]| {
        used.iter()
            .zip(v)
            .map(|(rec, e)| ((rec.time - t0) / 60.0, e.norm() * 1e6))
            .collect::<Vec<_>>()
    };
    let time = SeriesPlot::new(
        "Residual length over time",
        "time since the first record [min]",
        "|residual| [µm]",
    )
    .series(Series::new("before", over_time(&f.residuals_before)).markers())
    .series(Series::new("after", over_time(&f.residuals_after)).markers())
    .svg()?;
    let kin = fm.kinematic_truth(&f.x)?;
    let mut workspace = vec![];
    for (rec, e) in used.iter().zip(&f.residuals_after) {
        let mut s = rec.signals.clone();
        if let Ok(tool) = fm.tool_state(&f.x, &kin, &rec.q, &mut s, None) {
            let p = tool.nominal.translation.vector;
            workspace.push((p.x * 1e3, p.y * 1e3, e.norm() * 1e6));
        }
    }
    let sec = r.section("Residuals");
    sec.paragraph(&format!(
        "Residual RMS per coordinate {:.2} µm before and {:.2} µm after the fit over {} measured points; χ²/dof = {:.3}.",
        rms(&f.residuals_before) * 1e6,
        rms(&f.residuals_after) * 1e6,
        used.len(),
        f.chi2_per_dof
    ));
    sec.figure(
        "residual_histogram",
        "Residual components before and after the fit",
        hist,
    )
    .figure("residual_time", "Residual length over time", time);
    if !workspace.is_empty() {
        sec.figure(
            "residual_workspace",
            "Residual length after the fit over the workspace (commanded tool point, top view)",
            ScatterPlot::new(
                "Residual after the fit over the workspace",
                "x [mm]",
                "y [mm]",
                "|residual| [µm]",
                workspace,
            )
            .svg()?,
        );
    }

    // error functions ± 2u
    let conditions = used.first().map(|r| r.signals.clone()).unwrap_or_default();
    let functions = axis_error_functions(fm, &f.x, f.covariance.as_ref(), &conditions, 41)?;
    let sec = r.section("Error functions");
    if functions.is_empty() {
        sec.paragraph("This machine family's errors are not per-axis functions (five-axis or serial arm); see the parameters.");
    } else {
        sec.paragraph("The fitted machine error e (true − commanded tool point, machine terms only) along each axis, the other axes at the middle of their travel and the signals (temperatures, time) of the first record; bands are ± 2u (k = 2) from the fit's covariance.");
    }
    let mut u_sq = 0.0;
    let mut n_u = 0;
    for func in &functions {
        for u in &func.sigmas {
            u_sq += u.norm_squared() / 3.0;
            n_u += 1;
        }
        sec.figure(
            &format!("error_{}", AXES[func.axis]),
            &format!("Error functions along {} with ± 2u", AXES[func.axis]),
            error_function_plot(func)?,
        );
    }

    // parameters and identifiability
    let mut t = Table::new(&["parameter", "value ± u (k = 1)", "status"]);
    for p in &f.parameters {
        let status = if let Some(side) = p.at_bound {
            format!("fitted, ended on the {} bound of its possible range: the data want a value beyond it (no interior uncertainty)", side.name())
        } else if p.free && !(p.value >= p.usual.0 && p.value <= p.usual.1) {
            format!(
                "fitted, outside the usual range {} … {}",
                value_with_sigma(p.usual.0, None, p.unit),
                value_with_sigma(p.usual.1, None, p.unit)
            )
        } else if p.free {
            "fitted".to_string()
        } else if let Some(h) = f.held.iter().find(|h| h.name == p.name) {
            format!("held at its start: {}", h.combination)
        } else {
            "fixed by the model file".to_string()
        };
        t.push(vec![
            p.name.clone(),
            value_with_sigma(p.value, p.sigma, p.unit),
            status,
        ]);
    }
    r.section("Parameters").table(t.caption("Every parameter of the model; uncertainties are standard (k = 1), scaled by the a-posteriori variance factor"));
    let mut id = Table::new(&["quantity", "value"]);
    id.push(vec![
        "parameters declared free".into(),
        (f.parameters.iter().filter(|p| p.free).count() + f.held.len()).to_string(),
    ]);
    id.push(vec![
        "rank of the declared model at the start".into(),
        f.declared_identifiability.rank.to_string(),
    ]);
    id.push(vec![
        "held (not identifiable from these measurements)".into(),
        f.held.len().to_string(),
    ]);
    id.push(vec![
        "condition number of the fitted set (column-scaled)".into(),
        format!("{:.3e}", f.identifiability.condition_number),
    ]);
    let sec = r.section("Identifiability");
    sec.table(id);
    for h in &f.held {
        sec.paragraph(&h.combination);
    }

    // budget
    let u_model = if n_u > 0 {
        (u_sq / n_u as f64).sqrt()
    } else {
        0.0
    };
    let u_residual = rms(&f.residuals_after);
    let budget = Budget::new(2.0)
        .with(
            "fitted model (RMS of u_e over the error functions)",
            u_model,
        )
        .with(
            "residual the model leaves (RMS per coordinate after the fit)",
            u_residual,
        );
    let bt = budget_table(&budget);
    r.section("Uncertainty budget").paragraph("Uncertainty of the compensated machine's error per coordinate, GUM root-sum-of-squares: the fitted model's own uncertainty and what it leaves unexplained (noise and misfit).").table(bt);
    Ok(r.write_to(dir)?)
}

/// A fitted error function along its axis: the three components with their ± 2u bands (also
/// `verify report`'s).
pub(crate) fn error_function_plot(
    func: &metrocell_estimation::error_functions::AxisErrorFunction,
) -> anyhow::Result<String> {
    let mut plot = SeriesPlot::new(
        &format!("Error along {}", AXES[func.axis]),
        &format!("{} [mm]", AXES[func.axis]),
        "error [µm]",
    );
    for c in 0..3 {
        let pts: Vec<(f64, f64)> = func
            .positions
            .iter()
            .zip(&func.errors)
            .map(|(q, e)| (q * 1e3, e[c] * 1e6))
            .collect();
        let band: Vec<(f64, f64)> = func
            .errors
            .iter()
            .zip(&func.sigmas)
            .map(|(e, u)| ((e[c] - 2.0 * u[c]) * 1e6, (e[c] + 2.0 * u[c]) * 1e6))
            .collect();
        plot = plot.series(Series::new(&format!("e_{}", AXES[c]), pts).band(band));
    }
    Ok(plot.svg()?)
}

/// An uncertainty budget as a table: each contribution (µm) with its share of u², then u_c and
/// U (also `verify report`'s).
pub(crate) fn budget_table(budget: &Budget) -> Table {
    let mut t = Table::new(&["contribution", "u [µm]", "share of u²"]);
    for ((c, share), contribution) in budget.shares().iter().zip(&budget.contributions) {
        t.push(vec![
            c.clone(),
            format!("{:.3}", contribution.standard_uncertainty * 1e6),
            format!("{:.1} %", share * 100.0),
        ]);
    }
    t.push(vec![
        "combined u_c".into(),
        format!("{:.3}", budget.combined() * 1e6),
        String::new(),
    ]);
    t.push(vec![
        format!("expanded U (k = {})", budget.coverage_factor),
        format!("{:.3}", budget.expanded() * 1e6),
        String::new(),
    ]);
    t
}
