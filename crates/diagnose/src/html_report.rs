//! The diagnosis as an HTML page with plots (crates/report): the answer in words, before/after
//! figures, the findings with their parameters, where they live and their evidence — the
//! residual against each term's signal — residuals over the workspace, over time with the
//! temperatures, before/after histograms, what is left unexplained, and how the selection went.
//! Plots show mm, µm and hours, as metrologists read them.

use metrocell_estimation::fit_summary::value_with_sigma;
use metrocell_report::{
    HistogramPlot, PlotError, Report, ScatterPlot, Section, Series, SeriesPlot, Table,
};

use crate::locate::p_value_text;
use crate::pipeline::{Diagnosis, PlotData};
use crate::report::{Finding, FitFigures, ParameterValue};

fn um(v: f64) -> String {
    format!("{:.2}", v * 1e6)
}

fn figures_row(name: &str, f: &FitFigures) -> Vec<String> {
    vec![
        name.into(),
        um(f.heldout_rms_m),
        um(f.heldout_max_m),
        format!("{:.2}", f.chi2_per_dof),
        um(f.rms_m),
    ]
}

/// A parameter as a metrologist reads it: µm or mm, µrad, µm/m/K, s, min or h, with its σ in the
/// same unit (the calibrate summary's formatting), never raw SI exponents.
fn parameter_text(p: &ParameterValue) -> String {
    match p.sigma {
        Some(_) => value_with_sigma(p.value, p.sigma, &p.unit),
        None => format!(
            "{} (not identifiable)",
            value_with_sigma(p.value, None, &p.unit)
        ),
    }
}

/// A p-value in a table cell: three decimals down to 0.001, then a mantissa and exponent, and
/// below f64's reach (an F statistic so large the tail underflows to 0) a floor, not "0.0e0".
fn p_text(p: f64) -> String {
    let text = p_value_text(p);
    text.strip_prefix("= ").map(str::to_string).unwrap_or(text)
}

/// The page for a diagnosis: the answer, each finding with its evidence, what catalog physics
/// does not explain, the residuals over the workspace and over time, the held-out histograms,
/// how the terms were chosen, and the records.
pub fn html_report(d: &Diagnosis, title: &str) -> Result<Report, PlotError> {
    let r = &d.report;
    let p = &d.plots;
    let mut page = Report::new(title);
    answer_section(&mut page, r);
    for (k, f) in r.findings.iter().enumerate() {
        finding_section(&mut page, k, f, p.evidence.get(k))?;
    }
    if !r.unexplained.is_empty() {
        let s = page.section("Not explained by catalog physics");
        for u in &r.unexplained {
            s.paragraph(&u.statement);
            s.paragraph(&format!("Where: {}", u.location.description));
        }
    }
    workspace_section(&mut page, p)?;
    if !p.time.is_empty() {
        time_section(&mut page, p)?;
    }
    // before/after histograms of held-out residuals
    if !p.heldout_before.is_empty() {
        let s = page.section("Held-out residuals before and after");
        let plot = HistogramPlot::new(
            "Held-out 3-D residual (blocks of time)",
            "|residual| (µm)",
            30,
        )
        .sample("before", p.heldout_before.iter().map(|v| v * 1e6).collect())
        .sample("after", p.heldout_after.iter().map(|v| v * 1e6).collect());
        s.figure(
            "histogram",
            "Each record predicted by a fit that did not see its block of time",
            plot.svg()?,
        );
    }
    selection_section(&mut page, r);
    if !r.messages.is_empty() || !r.records.rejected.is_empty() || !r.records.outliers.is_empty() {
        let s = page.section("The records");
        s.paragraph(&format!(
            "{} readings, {} records used ({} groups of repeated readings averaged), frame: {}.",
            r.records.readings, r.records.used, r.records.averaged_groups, r.records.frame
        ));
        for m in r
            .messages
            .iter()
            .chain(&r.records.rejected)
            .chain(&r.records.outliers)
        {
            s.paragraph(m);
        }
    }
    Ok(page)
}

/// The answer in words and the held-out figures before and after.
fn answer_section(page: &mut Report, r: &crate::report::Report) {
    let s = page.section("Answer");
    s.paragraph(&r.summary);
    s.paragraph(&r.noise.statement);
    s.table(
        Table::new(&["model", "held-out RMS (µm)", "held-out max (µm)", "χ²/dof", "RMS in fit (µm)"])
            .caption(&format!("Held out: every block of time and of workspace predicted by a fit to the others. Noise floor from the stated uncertainties: {} µm RMS per coordinate.", um(r.noise_rms_m)))
            .row(figures_row("declared model, refitted", &r.before))
            .row(figures_row("with what was found", &r.after)),
    );
}

/// Finding `k`: its statement, where it lives, its parameters, and its evidence (signal,
/// residual with the term put back, fitted term per record).
fn finding_section(
    page: &mut Report,
    k: usize,
    f: &Finding,
    evidence: Option<&(Vec<f64>, Vec<f64>, Vec<f64>)>,
) -> Result<(), PlotError> {
    let s = page.section(&format!("Finding {}: {}", k + 1, f.label));
    s.paragraph(&f.statement);
    s.paragraph(&format!(
        "Where: {} (channels: {}).",
        f.location.description,
        f.location.channels.join(", ")
    ));
    if !f.location.located.is_empty() {
        s.paragraph(&format!(
            "It accounts for: {}.",
            f.location.located.join("; ")
        ));
    }
    let mut t = Table::new(&["parameter", "value ± σ (k = 1)"]).caption(&format!(
        "catalog term `{}`, variant {}",
        f.term,
        if f.variant.is_empty() {
            "—"
        } else {
            &f.variant
        }
    ));
    for (name, v) in &f.parameters {
        t.push(vec![name.clone(), parameter_text(v)]);
    }
    s.table(t);
    if let Some((signal, residual, fitted)) = evidence {
        evidence_figure(s, k, f, signal, residual, fitted)?;
    }
    Ok(())
}

/// The residual with the term put back against the term's signal, the fitted term and the bin
/// means (no figure when no record has all three finite).
fn evidence_figure(
    s: &mut Section,
    k: usize,
    f: &Finding,
    signal: &[f64],
    residual: &[f64],
    fitted: &[f64],
) -> Result<(), PlotError> {
    let scale = if f.evidence.unit == "m" {
        1e3
    } else if f.evidence.unit == "s" {
        1.0 / 60.0
    } else {
        1.0
    };
    let unit = match f.evidence.unit.as_str() {
        "m" => "mm".to_string(),
        "s" => "min".to_string(),
        u => u.to_string(),
    };
    let keep: Vec<usize> = (0..signal.len())
        .filter(|&i| signal[i].is_finite() && residual[i].is_finite() && fitted[i].is_finite())
        .collect();
    let mut order = keep.clone();
    order.sort_by(|&a, &b| signal[a].total_cmp(&signal[b]));
    let measured = Series::new(
        "residual with the term put back",
        keep.iter()
            .map(|&i| (signal[i] * scale, residual[i] * 1e6))
            .collect(),
    )
    .markers();
    let model = Series::new(
        "fitted term",
        order
            .iter()
            .map(|&i| (signal[i] * scale, fitted[i] * 1e6))
            .collect(),
    );
    let bins = &f.evidence.bins;
    let binned = Series::new(
        "bin means ± standard error",
        bins.iter()
            .map(|b| (b.signal * scale, b.residual_m * 1e6))
            .collect(),
    )
    .band(
        bins.iter()
            .map(|b| {
                (
                    (b.residual_m - b.residual_sigma_m) * 1e6,
                    (b.residual_m + b.residual_sigma_m) * 1e6,
                )
            })
            .collect(),
    );
    if !keep.is_empty() {
        let plot = SeriesPlot::new(
            &format!("{} — evidence", f.label),
            &format!("{} ({unit})", f.evidence.signal),
            &format!("residual along {} (µm)", f.evidence.along),
        )
        .series(measured)
        .series(model)
        .series(binned);
        s.figure(
            &format!("evidence_{}", k + 1),
            &format!(
                "Residual against the term's signal (correlation {:.2})",
                f.evidence.correlation
            ),
            plot.svg()?,
        );
    }
    Ok(())
}

/// The residuals' size over the workspace (top view), before and after.
fn workspace_section(page: &mut Report, p: &PlotData) -> Result<(), PlotError> {
    let s = page.section("Residuals over the workspace");
    for (name, res) in [("before", &p.before), ("after", &p.after)] {
        if res.is_empty() {
            continue;
        }
        let pts: Vec<(f64, f64, f64)> = p
            .position
            .iter()
            .zip(res.iter())
            .map(|(q, e)| (q.x * 1e3, q.y * 1e3, e.norm() * 1e6))
            .collect();
        let plot = ScatterPlot::new(
            &format!("3-D residual {name} (top view)"),
            "x (mm)",
            "y (mm)",
            "|residual| (µm)",
            pts,
        );
        s.figure(
            &format!("workspace_{name}"),
            &format!("Residual size over the workspace, {name} adding what was found"),
            plot.svg()?,
        );
    }
    Ok(())
}

/// The residual components over time before and after, and the temperatures.
fn time_section(page: &mut Report, p: &PlotData) -> Result<(), PlotError> {
    let t0 = p.time.iter().cloned().fold(f64::INFINITY, f64::min);
    let hours: Vec<f64> = p.time.iter().map(|t| (t - t0) / 3600.0).collect();
    let s = page.section("Residuals over time, with the temperatures");
    let mut plot = SeriesPlot::new(
        "Residuals over time",
        "time from the first record (h)",
        "residual (µm)",
    );
    for (when, res) in [("before", &p.before), ("after", &p.after)] {
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            plot = plot.series(
                Series::new(
                    &format!("{name} {when}"),
                    hours
                        .iter()
                        .zip(res)
                        .map(|(h, e)| (*h, e[axis] * 1e6))
                        .collect(),
                )
                .markers(),
            );
        }
    }
    s.figure(
        "residuals_time",
        "Workpiece-frame residual components before and after",
        plot.svg()?,
    );
    if !p.temperatures.is_empty() {
        let mut tplot = SeriesPlot::new("Temperatures", "time from the first record (h)", "°C");
        for (name, values) in &p.temperatures {
            let mut pts: Vec<(f64, f64)> =
                hours.iter().zip(values).map(|(h, v)| (*h, *v)).collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            tplot = tplot.series(Series::new(name, pts));
        }
        s.figure(
            "temperatures",
            "The recorded temperatures at the records' times",
            tplot.svg()?,
        );
    }
    Ok(())
}

/// How the terms were chosen: each step's best candidates, and the terms not tried.
fn selection_section(page: &mut Report, r: &crate::report::Report) {
    let s = page.section("How the terms were chosen");
    s.paragraph("Each step tries every candidate term (catalog terms the model lacks, with their variants) and every empirical correction, refits the declared parameters with it, and accepts the best one only if it lowers the held-out error by 2 % or more, is significant (F test, Bonferroni over the candidates tried), lies in its documented range and lowers the BIC.");
    for (k, step) in r.selection.iter().enumerate() {
        let mut t = Table::new(&[
            "candidate",
            "variant",
            "held-out gain",
            "p (adjusted)",
            "ΔBIC",
            "plausible",
            "separable",
            "accepted",
        ])
        .caption(&format!(
            "step {}: {}",
            k + 1,
            step.chosen
                .clone()
                .unwrap_or_else(|| "nothing accepted".into())
        ));
        for c in &step.top {
            t.push(vec![
                c.label.clone(),
                c.variant.clone(),
                format!("{:.3}", c.heldout_gain),
                p_text(c.p_adjusted),
                format!("{:.1}", c.delta_bic),
                c.plausible.to_string(),
                c.separable.to_string(),
                c.accepted.to_string(),
            ]);
        }
        s.table(t);
    }
    if !r.not_tried.is_empty() {
        let mut t = Table::new(&["term", "why not tried"]);
        for n in &r.not_tried {
            t.push(vec![n.term.clone(), n.reason.clone()]);
        }
        s.table(t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 32: the report's tables read in µm, µm/m/K, minutes, and p-values with a floor.
    #[test]
    fn parameters_and_p_values_read_as_a_metrologist_reads_them() {
        let v = |value: f64, sigma: Option<f64>, unit: &str| ParameterValue {
            value,
            sigma,
            unit: unit.into(),
            at_bound: None,
        };
        assert_eq!(
            parameter_text(&v(1.985e-5, Some(1.6e-7), "m")),
            "19.85 ± 0.16 µm"
        );
        assert_eq!(
            parameter_text(&v(1800.0, Some(420.0), "s")),
            "30.0 ± 7.0 min"
        );
        assert_eq!(
            parameter_text(&v(11.5e-6, None, "1/K")),
            "11.5000 µm/m/K (not identifiable)"
        );
        assert_eq!(p_text(0.0), "< 1e-300");
        assert_eq!(p_text(3.2e-5), "3.2e-5");
        assert_eq!(p_text(0.0421), "0.042");
    }
}
