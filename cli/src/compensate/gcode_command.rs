//! `metrocell compensate gcode --model MODEL.yaml IN.nc -o OUT.nc`

use std::path::PathBuf;

use anyhow::Context;
use metrocell_gcode::{compensate_program, CompensationOptions, InverseMethod, ModelErrorField};
use metrocell_model_file::CellModel;

use super::conditions::{conditions, not_xyz_family, point_mm, sensors_read, ConditionOptions};

#[derive(clap::Args)]
#[command(
    after_help = "What it does: every programmed point T of G0/G1/G2/G3 is replaced by the commanded point C with \
C + e(C) = T, e the model's machine error (its terms' fitted values) at C for the direction each axis approaches it \
(fixed-point iteration, exact to 1e-12 m; --first-order gives seed 000's one step C = T − e(T)). Arcs become chords \
within --chord-tolerance; straight moves are split where the error bends them; a reversal (backlash) gets a take-up \
move. G20/G21, G90/G91, comments, F/S/M words and modal state are kept; lines that do not change are written byte for \
byte, so a zero model changes only the one header comment. Malformed lines are reported with their line numbers and \
passed through untouched; points outside the model's travel are reported (extrapolation).\n\
Thermal terms need the temperatures the part will be cut at (--temperature, one per sensor the model reads); a \
lagged one (thermal_growth with lag, as diagnose writes it) needs the sensor's history: --temperatures-from BAG \
(at --at-time), or, without it, a steady state at --temperature is assumed and said.\n\n\
Examples:\n  metrocell compensate gcode --model fitted.yaml part.nc -o part_comp.nc\n  \
metrocell compensate gcode --model fitted.yaml part.nc -o part_comp.nc --temperature x_left=21.4 --temperature x_right=21.9\n  \
metrocell compensate gcode --model diag/model.yaml part.nc -o part_comp.nc --temperatures-from shift_bag --at-time 2h"
)]
pub struct GcodeArgs {
    /// Fitted model file (a cell file, e.g. written by `metrocell calibrate -o`)
    #[arg(long)]
    model: PathBuf,
    /// The part program
    input: PathBuf,
    /// Where to write the compensated program
    #[arg(short, long)]
    output: PathBuf,
    /// Temperature of a sensor the model's thermal terms read, NAME=°C (repeat per sensor)
    #[arg(long = "temperature", value_name = "NAME=°C")]
    temperatures: Vec<String>,
    /// Load force for compliance terms, FX,FY,FZ in N
    #[arg(long, value_name = "FX,FY,FZ")]
    load: Option<String>,
    /// A recording whose temperature topics (/temperature/<sensor>) give the temperatures and the
    /// history a lagged thermal term reads; without it a lagged term assumes a steady state at --temperature
    #[arg(long, value_name = "BAG")]
    temperatures_from: Option<PathBuf>,
    /// The instant of --temperatures-from: time after its first temperature sample (e.g. 2h, 90min, 5400; default its end)
    #[arg(long, value_name = "TIME")]
    at_time: Option<String>,
    /// Largest distance between a chord and the path it replaces, mm
    #[arg(long, default_value_t = 0.001)]
    chord_tolerance: f64,
    /// Where the tool is before the first move, X,Y,Z in mm (program coordinates)
    #[arg(long, value_name = "X,Y,Z", default_value = "0,0,0")]
    start: String,
    /// Seed 000's one-step inverse C = T − e(T) instead of the exact fixed point
    #[arg(long)]
    first_order: bool,
}

pub fn run(a: GcodeArgs) -> anyhow::Result<i32> {
    let model = CellModel::from_path(&a.model)?;
    if let Some(family) = not_xyz_family(&model) {
        anyhow::bail!("model `{}`: G-code compensation rewrites X Y Z coordinates (machine families cartesian and delta); a {family} machine's programs are joint or pose programs", a.model.display());
    }
    let fm = model.forward_model()?;
    let c = conditions(
        &model,
        &ConditionOptions {
            temperatures: &a.temperatures,
            load: a.load.as_deref(),
            history: a.temperatures_from.as_deref(),
            at_time: a.at_time.as_deref(),
        },
    )
    .with_context(|| format!("model `{}`", a.model.display()))?;
    for line in &c.statements {
        println!("{line}");
    }
    let field = ModelErrorField::new(&fm, fm.params(), c.signals).map_err(|e| {
        let sensors = sensors_read(&model);
        let hint = if sensors.is_empty() {
            String::new()
        } else {
            format!(
                " (the model's terms read temperatures {}: give each with --temperature NAME=°C)",
                sensors.join(", ")
            )
        };
        anyhow::anyhow!("model `{}`: {e}{hint}", a.model.display())
    })?;
    let program = std::fs::read_to_string(&a.input)
        .with_context(|| format!("cannot read the program `{}`", a.input.display()))?;
    if !(a.chord_tolerance > 0.0 && a.chord_tolerance.is_finite()) {
        anyhow::bail!(
            "--chord-tolerance must be > 0 mm, got {}",
            a.chord_tolerance
        );
    }
    let options = CompensationOptions {
        method: if a.first_order {
            InverseMethod::FirstOrder
        } else {
            InverseMethod::FixedPoint
        },
        chord_tolerance_mm: a.chord_tolerance,
        start: point_mm(&a.start, "--start")? * 1e3,
        model_name: a
            .model
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_else(|| "model".into()),
    };
    let (out, report) = compensate_program(&program, &field, &options);
    std::fs::write(&a.output, out)
        .with_context(|| format!("cannot write `{}`", a.output.display()))?;
    println!("{}", report.summary());
    println!("written: {}", a.output.display());
    Ok(if report.malformed.is_empty() { 0 } else { 1 })
}
