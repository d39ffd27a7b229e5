//! `metrocell calibrate --model CELL.yaml BAG... -o MODEL.yaml [--report DIR] [--json FILE|-]`:
//! the declared error model fitted to the measurements of recordings (batch identification),
//! written back as the same cell file with fitted values and their uncertainties.

mod accelerometer;
mod placements;
pub(crate) mod report;
mod result_json;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use metrocell_estimation::fit_summary::summary_lines;
use metrocell_estimation::{fit, rms, Fit, FitOptions, RecordSet};
use metrocell_model_file::CellModel;
use metrocell_records::{records_from_bags, PointSource, RecordingOptions};
use metrocell_solver::Loss;
use metrocell_twin::{write_model, FittedParameter, ModelUpdate};

#[derive(clap::Args)]
#[command(after_help = "What it does:\n\
  1. reads the model: a cell file (the twin's format; only `machine` and `terms` are needed) whose `terms:` declare\n\
     the error model to fit; `estimation:` says which parameters are free and gives priors (default: all free);\n\
  2. builds measurement records from the bags: /measured_points (tracker node, bag import) or /tracker/measurements\n\
     (metrocell sim, drivers), and /probe/hits when the model declares sensors.probe (--no-probe-hits: not), each\n\
     with its covariance, commanded joints and the signals at its time (temperatures, air, time since power-on...).\n\
     A signal a declared term needs that the bag lacks is an error naming the topic;\n\
  3. fits: registers the tracker if the points are in its frame, then least squares weighted by each point's\n\
     covariance with a robust loss (--loss; outliers are down-weighted, counted and named), bounded only where a\n\
     value is physically impossible (a negative time constant; sign-free quantities such as a reversal, a\n\
     squareness or a scale have no bound); a parameter that ends on a bound is said to (text, JSON `at_bound`),\n\
     with no interior σ; parameters the measurements cannot separate are held at their start and said so;\n\
  4. writes MODEL.yaml: your file with the fitted values in place (your units, comments and order kept), an\n\
     `uncertainty:` section (standard uncertainties, k = 1) and a `fit:` section; it reads back in `metrocell sim`,\n\
     `calibrate`, `diagnose` and `compensate`;\n\
  5. prints a summary in words (on stderr with --json -, so stdout holds the JSON alone); --report DIR writes an\n\
     HTML report (residuals before/after, error functions with uncertainty bands, identifiability, uncertainty\n\
     budget); --json writes the numbers. Files are written before anything is printed.\n\n\
Examples:\n\
  metrocell sim --cell launch-configs/cells/quick_demo.yaml --duration 30min -o demo_bag\n\
  metrocell calibrate --model my_model.yaml demo_bag -o fitted.yaml --report calib_report\n\
  metrocell calibrate --model my_model.yaml run1 run2 -o fitted.yaml --json - --loss cauchy")]
pub struct CalibrateArgs {
    /// The model to fit: a cell file whose `terms:` declare the error model
    #[arg(long)]
    model: PathBuf,
    /// Recordings (rosbag2 directories or .mcap files); several are concatenated
    #[arg(required = true)]
    bags: Vec<PathBuf>,
    /// Where to write the fitted model (a cell file)
    #[arg(short, long)]
    output: PathBuf,
    /// Write an HTML report with plots into this directory
    #[arg(long)]
    report: Option<PathBuf>,
    /// Write the result as JSON to this file, or `-` for stdout
    #[arg(long)]
    json: Option<String>,
    /// Loss on the whitened residuals: huber, cauchy or linear (plain least squares)
    #[arg(long, default_value = "huber")]
    loss: String,
    /// Where the robust loss starts, in standard deviations of a measurement
    #[arg(long, default_value_t = 4.0)]
    outlier_threshold: f64,
    /// Which messages are the measurements: auto (measured points if the bag has them), measured, tracker
    #[arg(long, default_value = "auto")]
    points: String,
    /// Topic of the measured points (e.g. /measured_points/thermal_compensated)
    #[arg(long, default_value = "/measured_points")]
    measured_points_topic: String,
    /// Leave the probe hits (/probe/hits) out; by default a model that declares `sensors.probe`
    /// is fitted to them too (its pretravel with them)
    #[arg(long)]
    no_probe_hits: bool,
    /// Refit only these and keep the rest of the model: `poses` — the instrument's placements
    /// (one pose per setup, the base's tilt), the stationing step at a new site with the
    /// physics a previous calibration fitted
    #[arg(long, value_parser = ["poses"])]
    refit: Option<String>,
}

pub fn run(a: CalibrateArgs) -> i32 {
    match calibrate(a) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}

fn calibrate(a: CalibrateArgs) -> anyhow::Result<i32> {
    let started = Instant::now();
    let loss = match a.loss.as_str() {
        "huber" => Loss::Huber(a.outlier_threshold),
        "cauchy" => Loss::Cauchy(a.outlier_threshold),
        "linear" => Loss::Linear,
        other => anyhow::bail!("--loss `{other}`: allowed huber, cauchy, linear"),
    };
    if !(a.outlier_threshold > 0.0 && a.outlier_threshold.is_finite()) {
        anyhow::bail!(
            "--outlier-threshold must be > 0 (standard deviations), got {}",
            a.outlier_threshold
        );
    }
    let points = match a.points.as_str() {
        "auto" => PointSource::Auto,
        "measured" => PointSource::MeasuredPoints,
        "tracker" => PointSource::TrackerMeasurements,
        other => anyhow::bail!("--points `{other}`: allowed auto, measured, tracker"),
    };
    let file_model = CellModel::from_path(&a.model)?;
    eprintln!("reading {} recording(s)…", a.bags.len());
    // a model that declares a touch probe is fitted to the recording's probe hits too
    let probe_hits = file_model.raw.sensors.probe.is_some() && !a.no_probe_hits;
    let options = RecordingOptions {
        points,
        measured_points_topic: a.measured_points_topic.clone(),
        probe_hits,
        ..RecordingOptions::default()
    };
    let mut records = records_from_bags(&a.bags, &file_model.forward_model()?, &options)?;
    // one pose per placement of the instrument (the recordings' `setup`), the base's tilt for a
    // levelled one; placements with too few fit points set aside, named
    let (setups, short) = metrocell_estimation::check_points::usable_setups(
        &mut records,
        file_model.placement_fit_points(),
    );
    let model = file_model.with_setups(&setups)?;
    let fm = model.forward_model()?;
    let setup = match a.refit.as_deref() {
        Some(_) => placements::poses_only(&model.setup),
        None => model.setup.clone(),
    };
    eprintln!(
        "model {}: {} terms, {} parameters ({} free){}",
        a.model.display(),
        model.machine_terms.terms.len() + model.instrument_terms.terms.len(),
        fm.param_count(),
        setup.free.iter().filter(|f| **f).count(),
        if setups.is_empty() {
            String::new()
        } else {
            format!(
                ", a pose for each of {} setups ({})",
                setups.len(),
                setups.join(", ")
            )
        }
    );
    for note in &short {
        eprintln!("warning: {note}");
    }
    eprintln!(
        "{} measurement records, {} check points ({} rejected) in {:.1} s; fitting…",
        records.len(),
        records.check.len(),
        records.rejected.len(),
        started.elapsed().as_secs_f64()
    );
    let fit_options = FitOptions {
        loss,
        ..FitOptions::default()
    };
    let result = fit(&fm, &setup, &records, None, &fit_options)
        .with_context(|| format!("fitting {} to {} records", a.model.display(), records.len()))?;
    // the base accelerometer's alignment against the levelled instrument (a nuisance, reported)
    let alignment = accelerometer::find(&fm, &result, &records);
    let check = if records.check.is_empty() {
        None
    } else {
        Some(
            placements::compare_on_check_points(&fm, &setup, &records, &result, &fit_options)
                .context("predicting the check points")?,
        )
    };
    let iterations = result.solution.iterations;
    eprintln!(
        "fitted in {:.1} s ({iterations} iteration{}; {})",
        started.elapsed().as_secs_f64(),
        if iterations == 1 { "" } else { "s" },
        result.solution.termination.in_words()
    );
    let mut lines = summary_lines(&result, &records);
    if a.refit.is_some() {
        // the kept physics is taken as exact here: its own σ (the fitted file's `uncertainty:`)
        // would widen the placements' and the predictions' uncertainty, and is not propagated
        lines.push("note: the placements' σ above treat the kept physics as exact (its own uncertainty, in the model file's `uncertainty:` section, is not propagated into them)".to_string());
    }
    lines.extend(short.iter().cloned());
    if let Some(c) = &check {
        lines.extend(placements::check_lines(c));
    }
    if let Some(al) = &alignment {
        lines.extend(accelerometer::lines(al));
    }
    // Files first, words last: a reader that closes stdout early (`| head`, `| true`) must not
    // cost the user the fitted model (see `restore_sigpipe` in main.rs).
    let update = model_update(&result, &records, &a);
    // the fitted file is the file's model: placements are per recording, not written into it
    let per_recording = |name: &str| {
        metrocell_estimation::check_points::is_placement_parameter(name)
            && (!setups.is_empty() || name.starts_with("base_tilt"))
    };
    let update = ModelUpdate {
        parameters: update
            .parameters
            .into_iter()
            .filter(|p| !per_recording(&p.name))
            .collect(),
        output_dir: a.output.parent().map(std::path::Path::to_path_buf),
        ..update
    };
    let text = write_model(&model, &update)?;
    std::fs::write(&a.output, &text)
        .with_context(|| format!("cannot write `{}`", a.output.display()))?;
    let page = match &a.report {
        Some(dir) => Some(report::write(
            dir, &a, &model, &fm, &result, &records, &lines,
        )?),
        None => None,
    };
    let json = match &a.json {
        Some(_) => Some(serde_json::to_string_pretty(&result_json::result(
            &result,
            &records,
            &a.output,
            check.as_ref(),
            alignment.as_ref(),
        ))?),
        None => None,
    };
    let json_to_stdout = a.json.as_deref() == Some("-");
    if let (Some(target), Some(json)) = (a.json.as_deref().filter(|t| *t != "-"), &json) {
        std::fs::write(target, json).with_context(|| format!("cannot write `{target}`"))?;
    }
    lines.push(format!("fitted model written to {}", a.output.display()));
    if let Some(page) = page {
        lines.push(format!("report: {}", page.display()));
    }
    // With `--json -` stdout carries the JSON alone (for `jq` and friends); the words go to stderr.
    for l in &lines {
        if json_to_stdout {
            eprintln!("{l}");
        } else {
            println!("{l}");
        }
    }
    if let (true, Some(json)) = (json_to_stdout, json) {
        println!("{json}");
    }
    Ok(0)
}

/// Fitted values (the free, identifiable parameters) and the `fit:` section.
fn model_update(f: &Fit, records: &RecordSet, a: &CalibrateArgs) -> ModelUpdate {
    let parameters = f
        .parameters
        .iter()
        .filter(|p| p.free)
        .map(|p| FittedParameter {
            name: p.name.clone(),
            value: p.value,
            sigma: p.sigma,
        })
        .collect();
    let mut fit_section = serde_yaml::Mapping::new();
    let mut put = |k: &str, v: serde_yaml::Value| {
        fit_section.insert(k.into(), v);
    };
    put(
        "recordings",
        a.bags
            .iter()
            .map(|b| serde_yaml::Value::from(b.display().to_string()))
            .collect::<Vec<_>>()
            .into(),
    );
    put("records", (f.used.len() as u64).into());
    put("residual_rms_um", {
        let mut m = serde_yaml::Mapping::new();
        m.insert(
            "before".into(),
            round(rms(&f.residuals_before) * 1e6, 3).into(),
        );
        m.insert(
            "after".into(),
            round(rms(&f.residuals_after) * 1e6, 3).into(),
        );
        m.into()
    });
    put("chi2_per_dof", round(f.chi2_per_dof, 4).into());
    put("outliers_downweighted", (f.outliers.len() as u64).into());
    put(
        "skipped",
        ((f.skipped.len() + records.rejected.len()) as u64).into(),
    );
    if !f.held.is_empty() {
        put(
            "not_identifiable",
            f.held
                .iter()
                .map(|h| serde_yaml::Value::from(h.combination.clone()))
                .collect::<Vec<_>>()
                .into(),
        );
    }
    ModelUpdate {
        parameters,
        fit: Some(fit_section.into()),
        ..ModelUpdate::default()
    }
}

fn round(v: f64, decimals: i32) -> f64 {
    let s = 10f64.powi(decimals);
    (v * s).round() / s
}
