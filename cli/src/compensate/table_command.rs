//! `metrocell compensate table --model MODEL.yaml -o DIR`

use std::path::PathBuf;

use anyhow::Context;
use metrocell_gcode::controller_table::{axis_csv, axis_tables, squareness, squareness_csv};
use metrocell_gcode::{ErrorField, ModelErrorField};
use metrocell_model_file::CellModel;

use super::conditions::{conditions, not_xyz_family, point_mm, sensors_read, ConditionOptions};

#[derive(clap::Args)]
#[command(
    after_help = "Writes DIR/axis_x.csv, axis_y.csv, axis_z.csv and DIR/squareness.csv. Each axis table samples \
the model along that axis every --step mm over its travel, the other axes at --at (default: the middle of the \
travel), with the columns\n  position_mm,pitch_um,straightness_<a>_um,straightness_<b>_um,reversal_um\n\
pitch = the error along the axis, straightness = the errors across it (approaching in +), reversal = the error \
approaching in − minus approaching in + (backlash). Values are errors, reached − commanded; a controller \
compensates by commanding position − error (most controllers' \"compensation value\" is −error). \
squareness.csv: pair,squareness_urad from the straightness lines (catalog sign: xy means d = (−y·s, 0, 0)). \
Lines starting with # are comments naming the model, the reference position and the conditions (where the \
temperatures came from; for a lagged thermal term without --temperatures-from BAG, the steady state assumed).\n\n\
Example:\n  metrocell compensate table --model fitted.yaml -o comp_tables --step 25 --temperature x_left=20 --temperature x_right=20"
)]
pub struct TableArgs {
    /// Fitted model file (a cell file, e.g. written by `metrocell calibrate -o`)
    #[arg(long)]
    model: PathBuf,
    /// Output directory (created)
    #[arg(short, long)]
    output: PathBuf,
    /// Spacing of the table points, mm
    #[arg(long, default_value_t = 10.0)]
    step: f64,
    /// Position of the other axes while one is tabulated, X,Y,Z in mm (default: the middle of the travel)
    #[arg(long, value_name = "X,Y,Z")]
    at: Option<String>,
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
}

pub fn run(a: TableArgs) -> anyhow::Result<i32> {
    if !(a.step > 0.0 && a.step.is_finite()) {
        anyhow::bail!("--step must be > 0 mm, got {} mm", a.step);
    }
    let model = CellModel::from_path(&a.model)?;
    if let Some(family) = not_xyz_family(&model) {
        anyhow::bail!(
            "model `{}`: compensation tables are per linear axis X, Y, Z (machine families cartesian and delta); a {family} machine \
             is commanded in joints, so its fitted model is applied through the controller's own kinematic parameters (the fitted \
             values in the model file), not through axis tables",
            a.model.display()
        );
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
    let stated: String = c.statements.iter().map(|l| format!("# {l}\n")).collect();
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
    let region = field
        .calibrated_region()
        .context("the model has no travel to tabulate")?;
    let reference = match &a.at {
        Some(t) => {
            let at = point_mm(t, "--at")?;
            if !region.contains(&at) {
                let travel: Vec<String> = (0..3)
                    .map(|k| {
                        format!(
                            "{} {:.3}…{:.3} mm",
                            ["X", "Y", "Z"][k],
                            region.min[k] * 1e3,
                            region.max[k] * 1e3
                        )
                    })
                    .collect();
                anyhow::bail!("--at {t}: outside the machine's travel ({}); the tables hold the other axes inside it", travel.join(", "));
            }
            at
        }
        None => (region.min + region.max) / 2.0,
    };
    let tables = axis_tables(&field, &region, &reference, a.step * 1e-3)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create `{}`", a.output.display()))?;
    let title = a.model.display().to_string();
    for t in &tables {
        let path = a
            .output
            .join(format!("axis_{}.csv", ["x", "y", "z"][t.axis]));
        std::fs::write(&path, format!("{stated}{}", axis_csv(t, &title)))
            .with_context(|| format!("cannot write `{}`", path.display()))?;
        let pitch: Vec<f64> = t.errors.iter().map(|e| e[t.axis]).collect();
        let span = pitch.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v))
            - pitch.iter().fold(f64::INFINITY, |m, v| m.min(*v));
        let rev = t.reversal.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        println!(
            "{}: {} points, pitch error span {:.2} µm, largest reversal {:.2} µm",
            path.display(),
            t.positions.len(),
            span * 1e6,
            rev * 1e6
        );
    }
    let sq = squareness(&tables);
    let path = a.output.join("squareness.csv");
    std::fs::write(&path, format!("{stated}{}", squareness_csv(&sq, &title)))
        .with_context(|| format!("cannot write `{}`", path.display()))?;
    println!(
        "{}: {}",
        path.display(),
        sq.iter()
            .map(|(p, v)| format!("{p} {:.2} µrad", (v * 1e8).round() / 1e2 + 0.0))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(0)
}
