//! `delta fit --report DIR`: the fit as one HTML page — how far each measured feature was from
//! the firmware's geometry and from the fitted one, over the bed, the parameters and the new
//! settings.

use std::path::{Path, PathBuf};

use anyhow::Context;
use metrocell_estimation::delta_calibration::{name_of, DeltaFit, DeltaMeasurement};
use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::delta_firmware::MarlinDelta;
use metrocell_report::{Report, ScatterPlot, Table};

/// Writes `DIR/index.html` and its figures; returns the page's path.
pub fn write(
    dir: &Path,
    source: &Path,
    fit: &DeltaFit,
    firmware: &DeltaGeometry,
    measurements: &[DeltaMeasurement],
    new: &MarlinDelta,
) -> anyhow::Result<PathBuf> {
    let mut r = Report::new(&format!("Delta calibration from {}", source.display()));
    let dof = fit.degrees_of_freedom;
    r.section("Summary").paragraph(&format!(
        "The printer's physical geometry fitted to {} measurements by least squares over the full \
         delta kinematics: χ²/dof {:.2} on {dof} degrees of freedom{}. Plan residuals are \
         measured − predicted in the printed object's frame, the object placed as well as it fits.",
        measurements.len(),
        if dof > 0 {
            fit.chi_square / dof as f64
        } else {
            f64::NAN
        },
        if fit.covariance_scale > 1.0 {
            format!("; σ widened by √{:.2}", fit.covariance_scale)
        } else {
            String::new()
        }
    ));
    let plan = |residuals: &[f64], scale: f64| -> Vec<(f64, f64, f64)> {
        let mut out = Vec::new();
        let mut at = 0;
        for m in measurements {
            if let DeltaMeasurement::PlanPosition { commanded, .. } = m {
                out.push((
                    commanded.x * 1e3,
                    commanded.y * 1e3,
                    residuals[at].hypot(residuals[at + 1]) * scale,
                ));
            }
            at += m.rows();
        }
        out
    };
    let before = plan(&fit.residuals_before, 1e3);
    if !before.is_empty() {
        r.section("Over the bed")
            .figure(
                "plan_before",
                "how far each printed feature was from where the firmware's geometry puts it (mm)",
                ScatterPlot::new(
                    "Printed with the firmware's geometry",
                    "x [mm]",
                    "y [mm]",
                    "|residual| [mm]",
                    before,
                )
                .svg()?,
            )
            .figure(
                "plan_after",
                "what the fitted geometry leaves (µm): the measurement noise if the model holds",
                ScatterPlot::new(
                    "Fitted geometry",
                    "x [mm]",
                    "y [mm]",
                    "|residual| [µm]",
                    plan(&fit.residuals, 1e6),
                )
                .svg()?,
            );
    }
    let mut table = Table::new(&["parameter", "firmware", "physical", "σ", "note"]);
    let (was, now) = (firmware.to_vector(), fit.geometry.to_vector());
    for &k in &fit.estimated {
        let (unit, f) = if (2..=4).contains(&k) || name_of(k) == "object_rotation" {
            ("°", 180.0 / std::f64::consts::PI)
        } else {
            ("mm", 1e3)
        };
        let sigma = fit.sigma_of(k).unwrap_or(f64::NAN) * f;
        let (firmware_value, physical) = if k < was.len() {
            (format!("{:.4}", was[k] * f), now[k] * f)
        } else {
            (
                String::new(),
                fit.placement.unwrap_or_default()[k - was.len()] * f,
            )
        };
        let note = if k < was.len() && ((now[k] - was[k]) * f).abs() < 2.0 * sigma {
            "not significant: within 2σ of the firmware's value"
        } else {
            ""
        };
        table.push(vec![
            format!("{} ({unit})", name_of(k)),
            firmware_value,
            format!("{physical:.4}"),
            format!("{sigma:.4}"),
            note.into(),
        ]);
    }
    for (name, why) in &fit.held {
        table.push(vec![
            name.to_string(),
            String::new(),
            "held".into(),
            String::new(),
            why.to_string(),
        ]);
    }
    r.section("Parameters").table(table);
    r.section("New settings")
        .paragraph("Marlin (send, then M500 stores them):")
        .preformatted(&new.marlin_commands())
        .paragraph("Klipper printer.cfg:")
        .preformatted(&new.klipper_sections());
    r.write_to(dir)
        .with_context(|| format!("writing the report to {}", dir.display()))
}
