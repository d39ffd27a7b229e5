//! The measurements table `metrocell delta fit` reads: one CSV row per measurement, mm.
//!
//! Columns (header names, any order, other columns ignored): `kind` — `plan` (a printed feature's
//! position in the object's frame), `height` (a probed bed height) or `distance` (between two
//! printed features); `x_mm, y_mm, z_mm` — where it was commanded (a distance's first feature);
//! `to_x_mm, to_y_mm, to_z_mm` — a distance's second feature; `measured_x_mm, measured_y_mm` —
//! a plan position as measured; `measured_mm` — a height or a distance as measured; `sigma_mm` —
//! the measurement's standard uncertainty (per axis for a plan position); for a plan position a
//! camera measured, `view_x_mm, view_y_mm, view_z_mm` — the camera's centre in the object's
//! frame (z up from the bed) — and `plane_z_mm`, the height of the plane it carried the image
//! back onto (the fit models the parallax of a feature standing at another height). Cells a
//! kind does not use may be empty.

use std::path::Path;

use anyhow::{bail, Context};
use metrocell_estimation::delta_calibration::{DeltaMeasurement, PlanView};
use nalgebra::{Vector2, Vector3};

pub const COLUMNS: [&str; 15] = [
    "kind",
    "x_mm",
    "y_mm",
    "z_mm",
    "to_x_mm",
    "to_y_mm",
    "to_z_mm",
    "measured_x_mm",
    "measured_y_mm",
    "measured_mm",
    "sigma_mm",
    "view_x_mm",
    "view_y_mm",
    "view_z_mm",
    "plane_z_mm",
];

/// The measurements, each with its line number in the file (1-based).
pub fn read(path: &Path) -> anyhow::Result<Vec<(usize, DeltaMeasurement)>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the measurements {}", path.display()))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        bail!(
            "{}: empty; expected a CSV header with {}",
            path.display(),
            COLUMNS.join(",")
        );
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |w: &str| names.iter().position(|n| *n == w);
    for needed in ["kind", "x_mm", "y_mm", "z_mm", "sigma_mm"] {
        if column(needed).is_none() {
            bail!(
                "{}: no column `{needed}` in the header `{header}` (the columns: {})",
                path.display(),
                COLUMNS.join(", ")
            );
        }
    }
    let mut out = Vec::new();
    for (number, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let at = |w: &str| column(w).and_then(|k| fields.get(k)).copied().unwrap_or("");
        let mm = |w: &str| -> anyhow::Result<f64> {
            let text = at(w);
            let v: f64 = text
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .with_context(|| {
                    format!(
                        "{}:{}: column `{w}` is `{text}`, not a number (a `{}` row needs it)",
                        path.display(),
                        number + 1,
                        at("kind")
                    )
                })?;
            Ok(v * 1e-3)
        };
        let point = |x: &str, y: &str, z: &str| -> anyhow::Result<Vector3<f64>> {
            Ok(Vector3::new(mm(x)?, mm(y)?, mm(z)?))
        };
        let sigma = mm("sigma_mm")?;
        let commanded = point("x_mm", "y_mm", "z_mm")?;
        out.push((
            number + 1,
            match at("kind") {
                "plan" => DeltaMeasurement::PlanPosition {
                    commanded,
                    measured: Vector2::new(mm("measured_x_mm")?, mm("measured_y_mm")?),
                    sigma,
                    view: if at("view_z_mm").is_empty() {
                        None
                    } else {
                        Some(PlanView {
                            viewpoint: point("view_x_mm", "view_y_mm", "view_z_mm")?,
                            plane_z: mm("plane_z_mm")?,
                        })
                    },
                },
                "height" => DeltaMeasurement::Height {
                    commanded,
                    measured: mm("measured_mm")?,
                    sigma,
                },
                "distance" => DeltaMeasurement::Distance {
                    from: commanded,
                    to: point("to_x_mm", "to_y_mm", "to_z_mm")?,
                    measured: mm("measured_mm")?,
                    sigma,
                },
                other => bail!(
                    "{}:{}: kind `{other}` is not one of plan, height, distance",
                    path.display(),
                    number + 1
                ),
            },
        ));
    }
    if out.is_empty() {
        bail!("{}: a header and no measurements", path.display());
    }
    Ok(out)
}
