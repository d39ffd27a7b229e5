//! A fit said in words, for a terminal and a report: what was fitted with ± σ in the units
//! metrology users read, what could not be identified and why, residuals before/after in µm,
//! whether what remains is consistent with the stated noise, and which measurements were left
//! out or down-weighted.

use crate::fit::{rms, Fit};
use crate::records::RecordSet;

/// A parameter's value and σ in display units: lengths µm (mm from 1 cm), angles µrad (degrees
/// from 10 mrad), 1/K as µm/m/K, times s (min from 2 min, h from 2 h), others as they are.
/// Returns (value, σ, unit text).
pub fn display(value: f64, sigma: Option<f64>, unit: &str) -> (f64, Option<f64>, String) {
    let (scale, shown) = match unit {
        // a time constant of half an hour reads in minutes, a drift over a shift in hours
        "s" if value.abs() >= 7200.0 => (1.0 / 3600.0, "h".to_string()),
        "s" if value.abs() >= 120.0 => (1.0 / 60.0, "min".to_string()),
        // an instrument's position (metres away) reads in mm, its orientation in degrees
        "m" if value.abs() >= 0.01 => (1e3, "mm".to_string()),
        "rad" if value.abs() >= 0.01 => (180.0 / std::f64::consts::PI, "°".to_string()),
        "m" => (1e6, "µm".to_string()),
        "rad" => (1e6, "µrad".to_string()),
        "1/K" => (1e6, "µm/m/K".to_string()),
        "m/K" => (1e6, "µm/K".to_string()),
        "1" => (1e6, "µm/m".to_string()),
        other => (1.0, other.to_string()),
    };
    (value * scale, sigma.map(|s| s * scale), shown)
}

/// `v ± σ unit` with σ to two significant digits and v to the same decimal.
pub fn value_with_sigma(value: f64, sigma: Option<f64>, unit: &str) -> String {
    let (v, s, u) = display(value, sigma, unit);
    match s {
        Some(s) if s > 0.0 => {
            let decimals = (1.0 - s.log10().floor()).max(0.0) as usize;
            format!("{v:.decimals$} ± {s:.decimals$} {u}")
        }
        _ => format!("{v:.4} {u}"),
    }
}

/// Does χ²/dof agree with 1 for this many degrees of freedom (within 3 standard deviations of
/// the χ² distribution, √(2/dof))?
pub fn consistent_with_noise(chi2_per_dof: f64, dof: usize) -> bool {
    (chi2_per_dof - 1.0).abs() <= 3.0 * (2.0 / dof.max(1) as f64).sqrt()
}

/// The summary, one statement per line.
pub fn summary_lines(fit: &Fit, records: &RecordSet) -> Vec<String> {
    let mut lines = vec![];
    let free: Vec<_> = fit.parameters.iter().filter(|p| p.free).collect();
    let frame = match &records.frame {
        crate::records::RecordFrame::Machine => "the machine frame".to_string(),
        crate::records::RecordFrame::Instrument(f) => {
            format!("the instrument frame `{f}` (its pose fitted with the model)")
        }
    };
    lines.push(format!(
        "Fitted {} parameters to {} measured points in {frame}.",
        free.len(),
        fit.used.len()
    ));
    let dof = fit.solution.degrees_of_freedom;
    let verdict = if consistent_with_noise(fit.chi2_per_dof, dof) {
        "consistent with the stated measurement noise: the model explains the data".to_string()
    } else if fit.chi2_per_dof > 1.0 {
        "larger than the stated noise explains: the model misses something (try `metrocell diagnose`) or the stated uncertainties are too small".to_string()
    } else {
        "smaller than the stated noise predicts: the stated uncertainties are too large".to_string()
    };
    lines.push(format!(
        "Residual RMS per coordinate: {:.2} µm before, {:.2} µm after; χ²/dof = {:.3} with {dof} degrees of freedom, {verdict}.",
        rms(&fit.residuals_before) * 1e6,
        rms(&fit.residuals_after) * 1e6,
        fit.chi2_per_dof
    ));
    for p in &free {
        lines.push(format!("  {}", p.describe()));
    }
    let bounded: Vec<&str> = free
        .iter()
        .filter(|p| p.at_bound.is_some())
        .map(|p| p.name.as_str())
        .collect();
    if fit.held.is_empty() && bounded.is_empty() {
        lines.push(format!("Every declared parameter is identifiable from these measurements (condition number {:.3e}).", fit.identifiability.condition_number));
    } else if fit.held.is_empty() {
        lines.push(format!(
            "Every declared parameter is identifiable from these measurements (condition number {:.3e}), but {} ended on a bound of its possible range ({}): the data want a value the model calls impossible — check the term's sign convention and the recording, or free the bound if the physics allows it.",
            fit.identifiability.condition_number,
            if bounded.len() == 1 { "one" } else { "some" },
            bounded.join(", ")
        ));
    } else {
        lines.push(format!("{} declared parameters cannot be identified from these measurements and were held at their start values:", fit.held.len()));
        for h in &fit.held {
            lines.push(format!("  {}", h.combination));
        }
        if !bounded.is_empty() {
            lines.push(format!(
                "At a bound of the possible range (no interior σ): {}.",
                bounded.join(", ")
            ));
        }
    }
    let t0 = records
        .records
        .iter()
        .map(|r| r.time)
        .fold(f64::INFINITY, f64::min);
    let who = |id: &str, index: usize| {
        if id.is_empty() {
            format!("record {index}")
        } else {
            format!("`{id}` (record {index})")
        }
    };
    if fit.outliers.is_empty() {
        lines.push("No measurement was down-weighted as an outlier.".into());
    } else {
        let list: Vec<String> = fit
            .outliers
            .iter()
            .take(10)
            .map(|o| {
                format!(
                    "{} at {:.1} s ({})",
                    who(&o.point_id, o.index),
                    o.time - t0,
                    o.reason
                )
            })
            .collect();
        let more = if fit.outliers.len() > 10 {
            format!(", and {} more", fit.outliers.len() - 10)
        } else {
            String::new()
        };
        // how many an honest Gaussian sample puts beyond the threshold anyway
        let expected = match fit.options_threshold {
            Some(c) => format!(
                "; Gaussian noise alone puts about {:.1} of {} components beyond {c}σ",
                3.0 * fit.used.len() as f64
                    * statrs::function::erf::erfc(c / std::f64::consts::SQRT_2),
                3 * fit.used.len()
            ),
            None => String::new(),
        };
        lines.push(format!("{} measurements were down-weighted as outliers by the robust loss ({} residual components{expected}; times from the first record): {}{more}.", fit.outliers.len(), fit.downweighted, list.join(", ")));
    }
    if !fit.skipped.is_empty() || !records.rejected.is_empty() {
        let n = fit.skipped.len() + records.rejected.len();
        let first = records
            .rejected
            .first()
            .map(|r| {
                format!(
                    "{} ({}): {}",
                    if r.point_id.is_empty() {
                        "a measurement"
                    } else {
                        &r.point_id
                    },
                    r.at,
                    r.reason
                )
            })
            .or_else(|| {
                fit.skipped.first().map(|s| {
                    format!(
                        "{} at {:.1} s: {}",
                        who(&s.point_id, s.index),
                        s.time - t0,
                        s.reason
                    )
                })
            })
            .unwrap_or_default();
        let more = if n > 1 {
            format!(" — and {} more (all listed in --json)", n - 1)
        } else {
            String::new()
        };
        lines.push(format!(
            "{n} measurements were left out, the first: {first}{more}."
        ));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 32: parameters read as a metrologist reads them, never as raw SI exponents.
    #[test]
    fn values_read_in_the_units_metrologists_use() {
        assert_eq!(
            value_with_sigma(1.985e-5, Some(1.2e-7), "m"),
            "19.85 ± 0.12 µm"
        );
        assert_eq!(
            value_with_sigma(-1.19999999, Some(3.4e-7), "m"),
            "-1199.99999 ± 0.00034 mm"
        );
        assert_eq!(
            value_with_sigma(2.5e-6, Some(3.1e-7), "rad"),
            "2.50 ± 0.31 µrad"
        );
        assert_eq!(
            value_with_sigma(10.23e-6, Some(8.8e-8), "1/K"),
            "10.230 ± 0.088 µm/m/K"
        );
        assert_eq!(
            value_with_sigma(1801.0, Some(19.0), "s"),
            "30.02 ± 0.32 min"
        );
        assert_eq!(value_with_sigma(9000.0, Some(900.0), "s"), "2.50 ± 0.25 h");
        assert_eq!(value_with_sigma(45.0, Some(2.0), "s"), "45.0 ± 2.0 s");
        assert_eq!(value_with_sigma(4e-6, None, "m/K"), "4.0000 µm/K");
    }
}
