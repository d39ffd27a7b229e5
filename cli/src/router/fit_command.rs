//! `metrocell router fit --errors HOLES.csv [--gcode PART.nc -o PART_COMP.nc]`: seed 000's
//! planar error field from a drilled plate's hole errors, validated on held-out columns, and the
//! part program compensated with it.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use metrocell_estimation::design_of_experiments::{best_random_log_det, d_optimal};
use metrocell_estimation::general_tolerance::finest_class_met;
use metrocell_estimation::improvement::{improvement, ErrorStatistics};
use metrocell_gcode::planar_field_fit::{
    cross_validate_by_columns, fit_planar_field, fit_planar_field_rows, regressors, HoleError,
    COEFFICIENTS,
};
use metrocell_gcode::{compensate_program, CompensationOptions, InverseMethod, Region};
use nalgebra::{DMatrix, Vector3};

#[derive(clap::Args)]
#[command(
    after_help = "Input: a CSV with a header naming the columns x_mm, y_mm (the hole's nominal \
position), ex_mm, ey_mm (reached − commanded) and sigma_x_mm, sigma_y_mm (the error's standard uncertainty), \
in any order; other columns are ignored. `metrocell router measure` writes it; a CMM's or another program's \
export works after renaming its columns.\n\n\
What it does: fits the nine coefficients A–I of seed 000's eq. 7 (the combinations a plane of holes can \
identify; the paper's twelve kinematic parameters are not separable from them, see the crate docs), with their \
σ; predicts every column of holes from a fit to the other columns (blocked cross-validation: the compensation \
a user would get, judged on holes it did not see); prints seed 000's Table 3 statistics of |e| before and \
after and the ISO 2768-1 class the plate meets before and after; with --gcode, rewrites the program with the \
fitted field (the paper's first-order C = T − e(T) with --first-order, else the exact fixed point).\n\n\
With --design K: K equations chosen by D-optimality (seed 000's DETMAX question: which rows pin the nine \
coefficients down best), compared with the best of 1000 random K-row designs, and a fit on them alone judged \
on all the other equations.\n\n\
Example:\n  metrocell router fit --errors plate_holes.csv --gcode part.nc -o part_comp.nc"
)]
pub struct FitArgs {
    /// The hole error table (CSV, see below)
    #[arg(long)]
    errors: PathBuf,
    /// The constant X3 of eq. 7 (the paper holds it at 1)
    #[arg(long, default_value_t = 1.0)]
    x3: f64,
    /// A part program to compensate with the fitted field
    #[arg(long)]
    gcode: Option<PathBuf>,
    /// Where to write the compensated program (with --gcode)
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Seed 000's one-step inverse C = T − e(T) instead of the exact fixed point
    #[arg(long)]
    first_order: bool,
    /// Write an HTML report (index.html and its figures) to this directory
    #[arg(long)]
    report: Option<PathBuf>,
    /// Choose this many equations (a hole's e_x or e_y) by D-optimal design (seed 000's DETMAX),
    /// fit on them alone and judge the fit on all the others: which holes to measure next time
    #[arg(long)]
    design: Option<usize>,
}

pub fn run(a: FitArgs) -> anyhow::Result<i32> {
    let holes = read_holes(&a.errors)?;
    println!("{}: {} holes", a.errors.display(), holes.len());
    let fit = fit_planar_field(&holes, a.x3)
        .with_context(|| format!("fitting {}", a.errors.display()))?;
    println!(
        "eq. 7 field (X3 = {}): χ²/dof = {:.2} on {} dof{}",
        a.x3,
        fit.chi_square / fit.degrees_of_freedom as f64,
        fit.degrees_of_freedom,
        if fit.covariance_scale > 1.0 {
            format!(
                " — the holes scatter more than their σ: σ below widened by √{:.2} (understated σ, or \
                 error the planar field does not hold)",
                fit.covariance_scale
            )
        } else {
            String::new()
        }
    );
    for (((name, regressor), value), sigma) in COEFFICIENTS
        .iter()
        .zip(fit.field.coefficients)
        .zip(fit.sigmas())
    {
        let z = value / sigma;
        let note = if z.abs() < 2.0 {
            "  (not significant: within 2σ of 0)"
        } else {
            ""
        };
        println!("  {name} = {value:+.4e} ± {sigma:.1e}   {regressor}{note}");
    }
    let held = cross_validate_by_columns(&holes, a.x3).context("cross-validating by columns")?;
    let before: Vec<f64> = holes
        .iter()
        .map(|h| h.error_mm.0.hypot(h.error_mm.1))
        .collect();
    let after: Vec<f64> = held
        .iter()
        .map(|h| h.residual_mm.0.hypot(h.residual_mm.1))
        .collect();
    let noise: Vec<f64> = holes
        .iter()
        .map(|h| h.sigma_mm.0.hypot(h.sigma_mm.1))
        .collect();
    let mean_noise = noise.iter().sum::<f64>() / noise.len() as f64;
    print_statistics(&before, &after, mean_noise, &holes)?;
    if let Some(k) = a.design {
        print_design(&holes, a.x3, k)?;
    }
    if let Some(dir) = &a.report {
        let page = super::fit_report::write(dir, &a.errors, &holes, &fit, &held)?;
        println!("report: {}", page.display());
    }
    if let Some(program) = &a.gcode {
        let Some(output) = &a.output else {
            bail!("--gcode needs -o OUT.nc: where to write the compensated program");
        };
        let mut field = fit.field;
        field.region = Some(region(&holes));
        let text = std::fs::read_to_string(program)
            .with_context(|| format!("reading the part program {}", program.display()))?;
        let options = CompensationOptions {
            method: if a.first_order {
                InverseMethod::FirstOrder
            } else {
                InverseMethod::FixedPoint
            },
            model_name: format!("seed 000 eq. 7 fitted to {}", a.errors.display()),
            ..CompensationOptions::default()
        };
        let (out, report) = compensate_program(&text, &field, &options);
        std::fs::write(output, out).with_context(|| format!("writing {}", output.display()))?;
        println!(
            "{} → {}: {}",
            program.display(),
            output.display(),
            report.summary()
        );
    }
    Ok(0)
}

fn print_statistics(
    before: &[f64],
    after: &[f64],
    noise: f64,
    holes: &[HoleError],
) -> anyhow::Result<()> {
    let (Some(b), Some(a)) = (ErrorStatistics::of(before), ErrorStatistics::of(after)) else {
        bail!("too few holes for statistics");
    };
    let (percent, average) = improvement(&b, &a);
    println!("|e| over the plate (mm), before and after compensation (after: each column predicted by the other columns' fit)");
    println!(
        "  {:<7} {:>9} {:>9} {:>9}",
        "", "before", "after", "improved"
    );
    for (((name, bv), (_, av)), (_, p)) in b.named().iter().zip(a.named()).zip(percent) {
        println!("  {name:<7} {bv:>9.4} {av:>9.4} {p:>8.2} %");
    }
    println!("  average improvement {average:.2} % (seed 000's Table 3 row)");
    println!(
        "  after / measurement noise (mean √(σx² + σy²) = {:.4} mm): {:.2}",
        noise,
        a.mean / noise
    );
    let size = holes
        .iter()
        .map(|h| h.nominal_mm.0.max(h.nominal_mm.1))
        .fold(0.0, f64::max);
    let class = |e: f64| match finest_class_met(size, e) {
        Ok(Some(c)) => c.to_string(),
        Ok(None) => "outside ISO 2768-1 (coarser than v)".into(),
        Err(e) => e.to_string(),
    };
    println!(
        "  ISO 2768-1 at the plate's {size:.0} mm, largest |e|: before {} ({:.3} mm), after {} ({:.3} mm)",
        class(b.max),
        b.max,
        class(a.max),
        a.max
    );
    Ok(())
}

/// Seed 000's design question: `k` equations chosen by D-optimality from the measured ones,
/// against the best of 1000 random choices, and what a fit on them alone leaves on the rest.
fn print_design(holes: &[HoleError], x3: f64, k: usize) -> anyhow::Result<()> {
    // candidate rows: e_x then e_y of each hole; coordinates in 100 mm so the columns compare
    let mut rows = Vec::with_capacity(2 * holes.len());
    for h in holes {
        let (gx, gy) = regressors(h.nominal_mm.0 / 100.0, h.nominal_mm.1 / 100.0, x3);
        rows.push([gx[0], gx[1], gx[2], gx[3], 0.0, 0.0, 0.0, 0.0, 0.0]);
        rows.push([0.0, 0.0, 0.0, 0.0, gy[0], gy[1], gy[2], gy[3], gy[4]]);
    }
    let candidates = DMatrix::from_fn(rows.len(), 9, |i, j| rows[i][j]);
    let design = d_optimal(&candidates, k, 20, 2026)
        .with_context(|| format!("choosing {k} of {} equations", rows.len()))?;
    let random = best_random_log_det(&candidates, k, 1000, 7);
    println!(
        "\nD-optimal design of {k} equations (of {}): ln det(XᵀX) {:.2}, best of 1000 random \
         designs {:.2}; rank {} of 9{}",
        rows.len(),
        design.log_det,
        random,
        design.rank,
        if design.rank < 9 {
            " — too few equations: some coefficients are not determined"
        } else {
            ""
        }
    );
    let named: Vec<String> = design
        .rows
        .iter()
        .map(|&r| {
            let h = &holes[r / 2];
            format!(
                "({}, {}) e_{}",
                h.nominal_mm.0,
                h.nominal_mm.1,
                ["x", "y"][r % 2]
            )
        })
        .collect();
    println!("  measure: {}", named.join(", "));
    let mut use_x = vec![false; holes.len()];
    let mut use_y = vec![false; holes.len()];
    for &r in &design.rows {
        if r % 2 == 0 {
            use_x[r / 2] = true;
        } else {
            use_y[r / 2] = true;
        }
    }
    let fit = match fit_planar_field_rows(holes, x3, &use_x, &use_y) {
        Ok(f) => f,
        Err(e) => {
            println!("  a fit on these equations alone: {e}");
            return Ok(());
        }
    };
    let (mut sum2, mut n) = (0.0, 0);
    for (i, (rx, ry)) in fit.residuals_mm.iter().enumerate() {
        for (used, r) in [(use_x[i], rx), (use_y[i], ry)] {
            if !used {
                sum2 += r * r;
                n += 1;
            }
        }
    }
    let after: Vec<f64> = fit.residuals_mm.iter().map(|r| r.0.hypot(r.1)).collect();
    let mean = after.iter().sum::<f64>() / after.len() as f64;
    println!(
        "  fitted on them alone: RMS {:.4} mm on the {n} equations it did not see; mean |e| \
         {mean:.4} mm over all {} holes",
        (sum2 / n.max(1) as f64).sqrt(),
        holes.len()
    );
    Ok(())
}

/// The plate's extent (m), where the field was identified.
fn region(holes: &[HoleError]) -> Region {
    let (mut min, mut max) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for h in holes {
        let p = Vector3::new(h.nominal_mm.0, h.nominal_mm.1, 0.0) * 1e-3;
        min = min.inf(&p);
        max = max.sup(&p);
    }
    // a plane: any Z
    (min.z, max.z) = (f64::NEG_INFINITY, f64::INFINITY);
    Region { min, max }
}

fn read_holes(path: &Path) -> anyhow::Result<Vec<HoleError>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the hole error table {}", path.display()))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        bail!(
            "{}: empty; expected a CSV header with x_mm,y_mm,ex_mm,ey_mm,sigma_x_mm,sigma_y_mm",
            path.display()
        );
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let wanted = ["x_mm", "y_mm", "ex_mm", "ey_mm", "sigma_x_mm", "sigma_y_mm"];
    let mut at = [0usize; 6];
    for (k, w) in wanted.iter().enumerate() {
        at[k] = names.iter().position(|n| n == w).with_context(|| {
            format!(
                "{}: no column `{w}` in the header `{header}` (needed: {})",
                path.display(),
                wanted.join(", ")
            )
        })?;
    }
    let mut holes = Vec::new();
    for (number, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let value = |k: usize| -> anyhow::Result<f64> {
            let text = fields.get(at[k]).copied().unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "{}:{}: column `{}` is `{text}`, not a number",
                        path.display(),
                        number + 1,
                        wanted[k]
                    )
                })
        };
        holes.push(HoleError {
            nominal_mm: (value(0)?, value(1)?),
            error_mm: (value(2)?, value(3)?),
            sigma_mm: (value(4)?, value(5)?),
        });
    }
    Ok(holes)
}
