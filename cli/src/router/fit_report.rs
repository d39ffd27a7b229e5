//! `router fit --report DIR`: the fit as one HTML page — the plate's errors before and the
//! held-out columns' residuals after, over the plate, the coefficients and Table 3's statistics.

use std::path::Path;

use anyhow::Context;
use metrocell_estimation::improvement::{improvement, ErrorStatistics};
use metrocell_gcode::planar_field_fit::{HeldOutHole, HoleError, PlanarFieldFit, COEFFICIENTS};
use metrocell_report::{Report, ScatterPlot, Table};

/// Writes `DIR/index.html` and its figures; returns the page's path.
pub fn write(
    dir: &Path,
    source: &Path,
    holes: &[HoleError],
    fit: &PlanarFieldFit,
    held: &[HeldOutHole],
) -> anyhow::Result<std::path::PathBuf> {
    let mut r = Report::new(&format!("Router calibration from {}", source.display()));
    let dof = fit.degrees_of_freedom;
    r.section("Summary").paragraph(&format!(
        "Seed 000's planar error field (eq. 7, nine coefficients A–I) fitted to {} holes: χ²/dof \
         {:.2} on {dof} degrees of freedom{}. After: each column of holes predicted by the field \
         fitted to the other columns (blocks of the plate, never random holes), so the residuals \
         are what compensation would leave on holes the fit did not see. e = reached − commanded.",
        holes.len(),
        fit.chi_square / dof as f64,
        if fit.covariance_scale > 1.0 {
            format!(
                "; the holes scatter more than their σ, so the σ below are widened by √{:.2}",
                fit.covariance_scale
            )
        } else {
            String::new()
        }
    ));
    let before: Vec<(f64, f64, f64)> = holes
        .iter()
        .map(|h| {
            (
                h.nominal_mm.0,
                h.nominal_mm.1,
                h.error_mm.0.hypot(h.error_mm.1),
            )
        })
        .collect();
    let after: Vec<(f64, f64, f64)> = held
        .iter()
        .map(|h| {
            (
                h.hole.nominal_mm.0,
                h.hole.nominal_mm.1,
                h.residual_mm.0.hypot(h.residual_mm.1) * 1e3,
            )
        })
        .collect();
    let plot = |title: &str, unit: &str, points: Vec<(f64, f64, f64)>| {
        ScatterPlot::new(title, "x [mm]", "y [mm]", unit, points).svg()
    };
    r.section("Over the plate")
        .figure(
            "errors_before",
            "|e| of each hole as drilled (mm)",
            plot("Error as drilled", "|e| [mm]", before)?,
        )
        .figure(
            "residuals_after",
            "|e| left on each hole when its column is predicted by the others' fit (µm)",
            plot("Held-out residual after compensation", "|e| [µm]", after)?,
        );
    let mut coefficients = Table::new(&["coefficient", "regressor", "value", "σ", "note"]);
    for (((name, regressor), value), sigma) in COEFFICIENTS
        .iter()
        .zip(fit.field.coefficients)
        .zip(fit.sigmas())
    {
        coefficients.push(vec![
            name.to_string(),
            regressor.to_string(),
            format!("{value:+.4e}"),
            format!("{sigma:.1e}"),
            if (value / sigma).abs() < 2.0 {
                "not significant: within 2σ of 0".into()
            } else {
                String::new()
            },
        ]);
    }
    r.section("Coefficients").table(coefficients);
    let magnitudes = |v: Vec<f64>| ErrorStatistics::of(&v).context("too few holes");
    let b = magnitudes(before_mm(holes))?;
    let a = magnitudes(
        held.iter()
            .map(|h| h.residual_mm.0.hypot(h.residual_mm.1))
            .collect(),
    )?;
    let (percent, average) = improvement(&b, &a);
    let mut stats = Table::new(&["|e| (mm)", "before", "after", "improved"]);
    for (((name, bv), (_, av)), (_, p)) in b.named().iter().zip(a.named()).zip(percent) {
        stats.push(vec![
            name.to_string(),
            format!("{bv:.4}"),
            format!("{av:.4}"),
            format!("{p:.2} %"),
        ]);
    }
    r.section("Seed 000's Table 3")
        .table(stats)
        .paragraph(&format!("Average improvement {average:.2} %."));
    let page = r
        .write_to(dir)
        .with_context(|| format!("writing the report to {}", dir.display()))?;
    Ok(page)
}

fn before_mm(holes: &[HoleError]) -> Vec<f64> {
    holes
        .iter()
        .map(|h| h.error_mm.0.hypot(h.error_mm.1))
        .collect()
}
