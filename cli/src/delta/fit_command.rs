//! `metrocell delta fit --firmware M503.txt --measurements TARGET.csv`: a delta printer's
//! physical geometry from what it printed (and, optionally, probed), and the Marlin and Klipper
//! settings that make its firmware agree.

use std::path::PathBuf;

use anyhow::{bail, Context};
use metrocell_estimation::delta_calibration::{
    fit_delta, name_of, parameter_index, DeltaFit, DeltaFitError, DeltaMeasurement, PLACEMENT_NAMES,
};
use metrocell_kinematics::delta::{DeltaGeometry, DELTA_PARAMETER_NAMES, MARLIN_TOWER_BASE_ANGLES};
use metrocell_kinematics::delta_firmware::{tower_letter, MarlinDelta};
use metrocell_kinematics::delta_rod_correction::rod_from_measured_move;

use super::measurements_file;

#[derive(clap::Args)]
#[command(after_help = "Inputs:\n\
  --firmware: the settings the printer ran when it printed the target: send M503 and save the reply \
(the `echo:  M665 …` and `M666 …` lines are read), or write `M665 L<rod> R<radius> H<height> X Y Z` and \
`M666 X Y Z` yourself.\n\
  --measurements: a CSV, one row per measurement, in mm: kind (plan | height | distance), x_mm, y_mm, \
z_mm (where the feature was commanded), to_x_mm, to_y_mm, to_z_mm (a distance's second feature), \
measured_x_mm, measured_y_mm (a plan position in the printed object's own frame), measured_mm (a height \
above the bed, or a distance), sigma_mm (its standard uncertainty).\n\n\
What it does: fits the physical geometry by least squares over the full delta kinematics — rod length and \
tower angles from plan positions and distances; with probed heights also the radius and the endstops — \
each with its σ (widened by χ²/dof when the data scatter more than stated). Parameters the measurements \
cannot see are held and named with the reason. Prints seed 002's single-arm estimate (eq. 13, averaged over \
the three arms) beside it for bars from the centre toward a tower. Writes the new Marlin settings \
(M665/M666/M500) and the same state as Klipper printer.cfg sections.\n\n\
Iterate: print the target again with the new settings, measure, fit with --round 2 (3, …); with \
--tolerance it says when a round's print is within it and how many rounds it took.\n\n\
Example:\n  metrocell delta fit --firmware m503.txt --measurements star.csv -o new_settings.gcode \
--klipper printer_delta.cfg")]
pub struct FitArgs {
    /// The printer's current settings (M503 reply, or M665/M666 lines)
    #[arg(long)]
    firmware: PathBuf,
    /// The measurements table (CSV, see below)
    #[arg(long)]
    measurements: PathBuf,
    /// Hold a parameter at its firmware value (repeatable): delta_rod_length, delta_radius,
    /// delta_tower_angle_a|b|c, delta_rod_trim_a|b|c (free them with --rod-trims), delta_endstop_a|b|c
    #[arg(long)]
    hold: Vec<String>,
    /// Fit a rod trim per tower (M665 A B C) instead of one rod length
    #[arg(long)]
    rod_trims: bool,
    /// Write the new Marlin settings (M665, M666, M500) here
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Write the new settings as Klipper printer.cfg sections here
    #[arg(long)]
    klipper: Option<PathBuf>,
    /// The print is done when every measured feature lies within this of its design (the object
    /// placed as well as it fits): say whether this round met it (e.g. 0.05mm)
    #[arg(long, value_parser = crate::vision::image_input::parse_length)]
    tolerance: Option<f64>,
    /// Write an HTML report (index.html and its figures) to this directory
    #[arg(long)]
    report: Option<PathBuf>,
    /// Which round of print, measure, fit this is (for the report of how many it took)
    #[arg(long, default_value_t = 1)]
    round: usize,
    /// With photographed positions and no probed heights: how well the nozzle touched the bed
    /// at its centre at z = 0 when the star was printed (the paper test done before printing)
    #[arg(long, default_value = "0.05mm", value_parser = crate::vision::image_input::parse_length)]
    paper_test: f64,
    /// The printer was not levelled before printing: do not assume the paper test (the common
    /// endstop is then held, and the dots' parallax computed as if it were zero)
    #[arg(long)]
    no_paper_test: bool,
}

/// A photographed dot's parallax depends on its top's absolute height, which plan positions
/// cannot see (a common endstop raises the effector and nothing else): without probed heights,
/// the paper test a user does before printing — the nozzle touching the bed at its centre at
/// z = 0 — is that height, with its σ. Found on the twin's levelled printer: holding the common
/// endstop at the settings' value instead put a 1.15 mm height error into the parallax and
/// biased the radius by 16σ.
fn paper_test(a: &FitArgs, measurements: &[DeltaMeasurement]) -> Option<DeltaMeasurement> {
    let photographed = measurements
        .iter()
        .any(|m| matches!(m, DeltaMeasurement::PlanPosition { view: Some(_), .. }));
    let probed = measurements
        .iter()
        .any(|m| matches!(m, DeltaMeasurement::Height { .. }));
    (photographed && !probed && !a.no_paper_test).then_some(DeltaMeasurement::Height {
        commanded: nalgebra::Vector3::zeros(),
        measured: 0.0,
        sigma: a.paper_test,
    })
}

pub fn run(a: FitArgs) -> anyhow::Result<i32> {
    let text = std::fs::read_to_string(&a.firmware)
        .with_context(|| format!("reading the firmware settings {}", a.firmware.display()))?;
    let settings =
        MarlinDelta::from_gcode(&text).with_context(|| a.firmware.display().to_string())?;
    let firmware = settings
        .firmware_geometry()
        .with_context(|| format!("the settings in {}", a.firmware.display()))?;
    print!(
        "{}: {}",
        a.firmware.display(),
        settings.marlin_commands().replace("M500\n", "")
    );
    let numbered = measurements_file::read(&a.measurements)?;
    let measurements: Vec<DeltaMeasurement> = numbered.iter().map(|(_, m)| *m).collect();
    let count = |f: fn(&DeltaMeasurement) -> bool| measurements.iter().filter(|m| f(m)).count();
    println!(
        "{}: {} plan positions, {} heights, {} distances",
        a.measurements.display(),
        count(|m| matches!(m, DeltaMeasurement::PlanPosition { .. })),
        count(|m| matches!(m, DeltaMeasurement::Height { .. })),
        count(|m| matches!(m, DeltaMeasurement::Distance { .. })),
    );
    let hold = held_by_request(&a)?;
    // the measured rows come first: the round's check and eq. 13 read only those
    let measured = measurements.len();
    let mut measurements = measurements;
    if let Some(level) = paper_test(&a, &measurements) {
        println!(
            "assumed: the printer was levelled by a paper test before printing — the nozzle at the \
             bed's centre at z = 0 ± {:.3} mm (it sets the dots' heights, so their parallax; probe \
             heights or say --no-paper-test if it was not)",
            a.paper_test * 1e3
        );
        measurements.push(level);
    }
    let fit = fit_delta(&firmware, &measurements, &hold).map_err(|e| match e {
        DeltaFitError::BadMeasurement { index, what } => {
            anyhow::anyhow!("{}:{}: {what}", a.measurements.display(), numbered[index].0)
        }
        e => anyhow::anyhow!("fitting {}: {e}", a.measurements.display()),
    })?;
    print_fit(&fit, &firmware, &measurements);
    if let Some(t) = a.tolerance {
        print_round(&fit, &measurements[..measured], t, a.round);
    }
    print_single_arm(&settings, &firmware, &measurements[..measured]);
    let new = settings
        .corrected(&fit.geometry)
        .context("turning the fitted geometry into settings")?;
    println!("\nnew settings (Marlin; M500 stores them):");
    print!("{}", new.marlin_commands());
    println!("\nthe same as Klipper printer.cfg sections:");
    print!("{}", new.klipper_sections());
    if let Some(dir) = &a.report {
        let page =
            super::fit_report::write(dir, &a.measurements, &fit, &firmware, &measurements, &new)?;
        println!("report: {}", page.display());
    }
    if let Some(path) = &a.output {
        std::fs::write(path, new.marlin_commands())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("\nwrote {}", path.display());
    }
    if let Some(path) = &a.klipper {
        std::fs::write(path, new.klipper_sections())
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(0)
}

/// The parameter indices --hold names, and the rod-length/trim choice.
fn held_by_request(a: &FitArgs) -> anyhow::Result<Vec<usize>> {
    let mut hold = Vec::new();
    for name in &a.hold {
        let Some(k) = parameter_index(name).filter(|&k| k < DELTA_PARAMETER_NAMES.len()) else {
            bail!(
                "--hold {name}: not a parameter; one of {}",
                DELTA_PARAMETER_NAMES.join(", ")
            );
        };
        hold.push(k);
    }
    if a.rod_trims {
        // three rods: the trims carry them, the common length is held
        hold.push(0);
    }
    Ok(hold)
}

/// A parameter in the firmware's units: (label, unit, factor from SI).
fn display(k: usize) -> (String, &'static str, f64) {
    let name = name_of(k);
    let label = name.trim_start_matches("delta_").replace('_', " ");
    match k {
        2..=4 => (label, "°", 180.0 / std::f64::consts::PI),
        _ if name == PLACEMENT_NAMES[0] => (label, "°", 180.0 / std::f64::consts::PI),
        _ => (label, "mm", 1e3),
    }
}

fn print_fit(fit: &DeltaFit, firmware: &DeltaGeometry, measurements: &[DeltaMeasurement]) {
    let dof = fit.degrees_of_freedom;
    println!(
        "\nfit: χ²/dof = {:.2} on {dof} dof{}",
        if dof > 0 {
            fit.chi_square / dof as f64
        } else {
            f64::NAN
        },
        if fit.covariance_scale > 1.0 {
            format!(
                " — the measurements scatter more than their σ: σ below widened by √{:.2} \
                 (understated σ, or error the delta geometry does not hold)",
                fit.covariance_scale
            )
        } else {
            String::new()
        }
    );
    println!(
        "  {:<22} {:>11} {:>11} {:>10} {:>9}",
        "parameter", "firmware", "physical", "change", "σ"
    );
    let fitted = fit.geometry.to_vector();
    let before = firmware.to_vector();
    for &k in &fit.estimated {
        let (label, unit, f) = display(k);
        let sigma = fit.sigma_of(k).unwrap_or(f64::NAN) * f;
        if k >= DELTA_PARAMETER_NAMES.len() {
            let p = fit.placement.unwrap_or_default()[k - DELTA_PARAMETER_NAMES.len()] * f;
            println!(
                "  {:<22} {:>11} {p:>11.4} {:>10} {sigma:>9.4}",
                format!("{label} ({unit})"),
                "",
                ""
            );
            continue;
        }
        let (now, was) = (fitted[k] * f, before[k] * f);
        let change = now - was;
        let note = if change.abs() < 2.0 * sigma {
            "  (not significant: within 2σ of the firmware's value)"
        } else {
            ""
        };
        println!(
            "  {:<22} {was:>11.4} {now:>11.4} {change:>+10.4} {sigma:>9.4}{note}",
            format!("{label} ({unit})")
        );
    }
    println!("  endstops are the physical carriage height minus the firmware's count");
    for (name, why) in &fit.held {
        println!(
            "  held: {} — {why}",
            name.trim_start_matches("delta_").replace('_', " ")
        );
    }
    for (kind, label) in [(0u8, "plan positions"), (1, "heights"), (2, "distances")] {
        let rows = residual_rows(measurements, kind);
        if rows.is_empty() {
            continue;
        }
        let rms = |r: &[f64]| {
            (rows.iter().map(|&(i, _)| r[i] * r[i]).sum::<f64>() / rows.len() as f64).sqrt() * 1e3
        };
        let sigma =
            (rows.iter().map(|&(_, s)| s * s).sum::<f64>() / rows.len() as f64).sqrt() * 1e3;
        println!(
            "  {label}: residual RMS {:.4} mm with the firmware's geometry, {:.4} mm fitted \
             (stated σ {sigma:.4} mm)",
            rms(&fit.residuals_before),
            rms(&fit.residuals)
        );
    }
}

/// The iteration's verdict: the print's largest error from its design (before this fit's
/// correction) against the tolerance.
fn print_round(fit: &DeltaFit, measurements: &[DeltaMeasurement], tolerance: f64, round: usize) {
    let mut largest: f64 = 0.0;
    let mut at = 0;
    for m in measurements {
        let r = &fit.residuals_before[at..at + m.rows()];
        largest = largest.max(r.iter().map(|v| v * v).sum::<f64>().sqrt());
        at += m.rows();
    }
    let (largest_mm, tolerance_mm) = (largest * 1e3, tolerance * 1e3);
    if largest <= tolerance {
        println!(
            "\nround {round}: every feature within {tolerance_mm:.3} mm of its design (largest \
             {largest_mm:.4} mm): calibrated in {round} round{} — keep the settings the printer has",
            if round == 1 { "" } else { "s" }
        );
    } else {
        println!(
            "\nround {round}: the largest error is {largest_mm:.4} mm, over the {tolerance_mm:.3} mm \
             tolerance: load the new settings, print the star again, measure it and run round {}",
            round + 1
        );
    }
}

/// Residual row indices of one kind of measurement (0 plan, 1 height, 2 distance), each with
/// its measurement's σ.
fn residual_rows(measurements: &[DeltaMeasurement], kind: u8) -> Vec<(usize, f64)> {
    let mut rows = Vec::new();
    let mut at = 0;
    for m in measurements {
        let k = match m {
            DeltaMeasurement::PlanPosition { .. } => 0,
            DeltaMeasurement::Height { .. } => 1,
            DeltaMeasurement::Distance { .. } => 2,
        };
        if k == kind {
            rows.extend((at..at + m.rows()).map(|i| (i, m.sigma())));
        }
        at += m.rows();
    }
    rows
}

/// Seed 002's estimate: eq. 13 for each bar from the centre toward a tower, averaged.
fn print_single_arm(
    settings: &MarlinDelta,
    firmware: &DeltaGeometry,
    measurements: &[DeltaMeasurement],
) {
    let mut rods = Vec::new();
    for m in measurements {
        let DeltaMeasurement::Distance {
            from, to, measured, ..
        } = m
        else {
            continue;
        };
        if from.xy().norm() > 1e-6 {
            continue;
        }
        let Some(t) = (0..3).find(|&t| {
            let a = MARLIN_TOWER_BASE_ANGLES[t] + firmware.tower_angle_trim[t];
            (to.y.atan2(to.x) - a).sin().abs() < 1e-3 && (to.y.atan2(to.x) - a).cos() > 0.0
        }) else {
            continue;
        };
        let commanded = to.xy().norm() * 1e3;
        let d0 = settings.diagonal_rod_mm + settings.diagonal_rod_trim_mm[t];
        match rod_from_measured_move(d0, settings.radius_mm, commanded, measured * 1e3) {
            Ok(d) => rods.push((t, commanded, measured * 1e3, d)),
            Err(e) => println!(
                "  eq. 13, tower {}: {e} (bar {commanded:.3} mm measured {:.3} mm)",
                tower_letter(t),
                measured * 1e3
            ),
        }
    }
    if rods.is_empty() {
        return;
    }
    println!("\nseed 002's single-arm estimate (eq. 13), for comparison — one arm at a time, every bar error put on the rod: it under-corrects a rod error (iterate), and a radius error, which also scales the bars, can turn its sign:");
    for (t, commanded, measured, d) in &rods {
        println!(
            "  tower {}: bar {commanded:.3} mm printed {measured:.4} mm → rod {d:.4} mm",
            tower_letter(*t)
        );
    }
    let mean = rods.iter().map(|r| r.3).sum::<f64>() / rods.len() as f64;
    println!("  mean rod {mean:.4} mm (the paper's new DELTA_DIAGONAL_ROD)");
}
