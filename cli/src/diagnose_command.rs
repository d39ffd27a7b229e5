//! `metrocell diagnose`: where a recording and a model disagree, which physics the model left
//! out, the model with it added, and the held-out fit before and after (crates/diagnose).

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use metrocell_diagnose::html_report::html_report;
use metrocell_diagnose::residual_table::residuals_csv;
use metrocell_diagnose::{diagnose, DeclaredModel, DiagnoseOptions, Diagnosis, Strategy};
use metrocell_model_file::CellModel;
use metrocell_records::{records_from_bags, PointSource, RecordingOptions};
use metrocell_twin::{write_model, FittedParameter, ModelUpdate};

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum StrategyArg {
    /// Greedy forward selection judged on held-out blocks of time and of workspace (the method)
    Select,
    /// Every candidate term at once by plain least squares, terms claimed where significant
    /// (a baseline to compare with)
    AllAtOnce,
}

#[derive(Args, Debug)]
#[command(
    about = "Find where a recording and a model disagree, name the missing physics, add it, and show the held-out fit improve",
    long_about = "Find where a recording and a model disagree, name the missing physics, add it, and show the held-out fit improve.\n\n\
The model is a cell file (machine, sensors, declared `terms:` and `estimation:` settings, as `metrocell calibrate` reads it); the\n\
recording one or more bags (recorded from the nodes, made by `metrocell sim`, or imported with `bag import` from another program's\n\
export). diagnose first fits what the model declares (so a mis-set declared parameter is not taken for missing physics), tests the\n\
residuals against the stated noise and locates any structure (channel and axis, region, time window, direction of motion,\n\
condition), then tries every catalog term the model lacks that the recording can inform — with their variants: series orders,\n\
screw leads, lag time constants, sensors — and empirical smooth corrections, keeping a term only if it lowers the error on\n\
held-out blocks of time and of workspace, is significant and plausible, and lowers the BIC. It refits the augmented model and\n\
reports the held-out RMS before and after, in a metrologist's words, or says that no catalog term explains a structure and\n\
where it lives.\n\n\
Output: a summary on stdout (stderr when --json -), `--json` (fields documented in the README: noise_rms_m, before, after,\n\
findings, unexplained, explained, …), `--report DIR` (DIR/model.yaml: the model file with the found terms added and fitted —\n\
machine terms under terms:, a tracker's warm-up and refraction in sensors.tracker, a probe's pretravel in sensors.probe,\n\
what no model file can hold (an empirical correction) in comments; calibrate, diagnose, compensate, sim and the estimator\n\
node read it; DIR/index.html with plots; DIR/diagnosis.json), `--residuals FILE.csv` (per record: time, channel, position, residual after the\n\
declared fit with its σ, and the signals).",
    after_help = "Examples:\n  metrocell diagnose --model cell.yaml shift_bag --report diag/\n  metrocell diagnose --model bags/cases/case_12/model.yaml rec/case_12/seed_1 --json -\n  metrocell bag import export.csv -o points --mapping map.yaml && metrocell diagnose --model model.yaml points --json result.json\n  metrocell diagnose --model cell.yaml run1 run2 --strategy all-at-once --residuals residuals.csv"
)]
pub struct DiagnoseArgs {
    /// The model: a cell file (crates/twin model file: machine required, terms and estimation settings)
    #[arg(long, value_name = "CELL.yaml")]
    pub model: PathBuf,
    /// Bags (rosbag2 MCAP directories or .mcap files), one recording each; their records are diagnosed together
    #[arg(required = true, value_name = "BAG")]
    pub bags: Vec<PathBuf>,
    /// Write DIR/model.yaml (the augmented model), DIR/index.html (report with plots) and DIR/diagnosis.json
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Write the result as JSON to FILE, or to stdout with `-`
    #[arg(long, value_name = "FILE|-")]
    pub json: Option<String>,
    /// Write per-record residuals after the declared fit, with σ and signals, as CSV
    #[arg(long, value_name = "FILE.csv")]
    pub residuals: Option<PathBuf>,
    /// How terms are chosen
    #[arg(long, value_enum, default_value = "select")]
    pub strategy: StrategyArg,
    /// Most terms added by the selection
    #[arg(long, default_value_t = 3)]
    pub max_terms: usize,
    /// Family-wise significance level of the tests (after correction for the number made)
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Do not try empirical corrections (structure no term explains is then only located)
    #[arg(long)]
    pub no_empirical: bool,
}

fn options(a: &DiagnoseArgs) -> DiagnoseOptions {
    let mut o = DiagnoseOptions {
        strategy: match a.strategy {
            StrategyArg::Select => Strategy::Select,
            StrategyArg::AllAtOnce => Strategy::AllAtOnce,
        },
        empirical: !a.no_empirical,
        ..Default::default()
    };
    o.selection.max_terms = a.max_terms;
    o.selection.alpha = a.alpha;
    o
}

/// The summary a person reads.
pub fn summary_text(d: &Diagnosis) -> String {
    let r = &d.report;
    let mut s = String::new();
    s.push_str(&format!("{}\n\n", r.summary));
    for (k, f) in r.findings.iter().enumerate() {
        s.push_str(&format!(
            "{}. {} — {}\n   where: {}\n",
            k + 1,
            f.label,
            f.statement,
            f.location.description
        ));
    }
    for u in &r.unexplained {
        s.push_str(&format!(
            "unexplained: {}\n   where: {}\n",
            u.statement, u.location.description
        ));
    }
    s.push_str(&format!(
        "\nheld-out RMS {:.2} µm → {:.2} µm, max {:.2} µm → {:.2} µm, χ²/dof {:.2} → {:.2} (noise floor {:.2} µm; blocks of {})\n{}\n",
        r.before.heldout_rms_m * 1e6,
        r.after.heldout_rms_m * 1e6,
        r.before.heldout_max_m * 1e6,
        r.after.heldout_max_m * 1e6,
        r.before.chi2_per_dof,
        r.after.chi2_per_dof,
        r.noise_rms_m * 1e6,
        r.after.heldout_blocks.join(" and "),
        r.noise.statement
    ));
    s.push_str(&format!(
        "records: {} readings, {} used ({} averaged groups), {} set aside, {} outliers\n",
        r.records.readings,
        r.records.used,
        r.records.averaged_groups,
        r.records.rejected.len(),
        r.records.outliers.len()
    ));
    for m in &r.messages {
        s.push_str(&format!("note: {m}\n"));
    }
    s
}

/// The augmented model file: the user's file with every fitted value, the found terms appended.
fn augmented_model(model: &CellModel, d: &Diagnosis, dir: &Path) -> anyhow::Result<String> {
    let parameters = d
        .fitted
        .iter()
        .map(|(name, value, sigma)| FittedParameter {
            name: name.clone(),
            value: *value,
            sigma: *sigma,
        })
        .collect();
    let r = &d.report;
    let mut fit = serde_yaml::Mapping::new();
    fit.insert("by".into(), "metrocell diagnose".into());
    fit.insert(
        "found".into(),
        serde_yaml::Value::Sequence(
            r.findings
                .iter()
                .map(|f| f.statement.clone().into())
                .collect(),
        ),
    );
    if !r.unexplained.is_empty() {
        fit.insert(
            "not_explained".into(),
            serde_yaml::Value::Sequence(
                r.unexplained
                    .iter()
                    .map(|u| format!("{} (empirical, not in this model)", u.statement).into())
                    .collect(),
            ),
        );
    }
    fit.insert(
        "heldout_rms_um".into(),
        serde_yaml::Value::Sequence(vec![
            ((r.before.heldout_rms_m * 1e8).round() / 100.0).into(),
            ((r.after.heldout_rms_m * 1e8).round() / 100.0).into(),
        ]),
    );
    fit.insert(
        "chi2_per_dof".into(),
        ((r.after.chi2_per_dof * 100.0).round() / 100.0).into(),
    );
    let update = ModelUpdate {
        parameters,
        added_terms: d.added_terms.iter().map(|t| t.config.clone()).collect(),
        fit: Some(serde_yaml::Value::Mapping(fit)),
        notes: left_out(d),
        output_dir: Some(dir.to_path_buf()),
    };
    Ok(write_model(model, &update)?)
}

/// What the diagnosis found that the model file does not hold as found, for its comments.
fn left_out(d: &Diagnosis) -> Vec<String> {
    let r = &d.report;
    let mut notes = Vec::new();
    for u in &r.unexplained {
        notes.push(match &u.correction {
            Some(c) => format!(
                "left out: the empirical correction `{}` metrocell diagnose fitted ({}). No catalog term describes it, so no model file can hold it: its coefficients are in the report's diagnosis.json (unexplained[].correction); find the cause, or model it by a term when one fits.",
                c.label, u.statement
            ),
            None => format!("not explained by any catalog term, and not in this model: {}", u.statement),
        });
    }
    for f in r.findings.iter().filter(|f| f.variant.contains("freed")) {
        notes.push(format!(
            "{}: this model held it fixed; metrocell diagnose freed and fitted it, and its value is written in place. It stays fixed when this file is fitted again unless `estimation:` frees it.",
            f.label
        ));
    }
    notes
}

fn write(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
}

/// Read the model and the bags and diagnose them (progress lines on stderr).
pub fn diagnose_bags(
    model_path: &Path,
    bags: &[PathBuf],
    options: &DiagnoseOptions,
) -> anyhow::Result<(CellModel, Diagnosis)> {
    diagnose_bags_from(model_path, bags, options, PointSource::Auto)
}

/// [`diagnose_bags`] with the points taken from `points` (`Auto`: `/measured_points` when the
/// bag has it, else the raw `/tracker/measurements`).
pub fn diagnose_bags_from(
    model_path: &Path,
    bags: &[PathBuf],
    options: &DiagnoseOptions,
    points: PointSource,
) -> anyhow::Result<(CellModel, Diagnosis)> {
    let file_model = CellModel::from_path(model_path)?;
    eprintln!("reading {} bag(s) …", bags.len());
    // a model that declares a touch probe is judged on the recording's probe hits too
    let recording = RecordingOptions {
        points,
        probe_hits: file_model.raw.sensors.probe.is_some(),
        ..RecordingOptions::default()
    };
    let mut records = records_from_bags(bags, &file_model.forward_model()?, &recording)?;
    // one pose per placement of the instrument (the recordings' `setup`)
    let (setups, short) = metrocell_estimation::check_points::usable_setups(
        &mut records,
        file_model.placement_fit_points(),
    );
    for note in &short {
        eprintln!("warning: {note}");
    }
    let model = file_model.with_setups(&setups)?;
    eprintln!(
        "{} measured points{} ({} set aside while reading); diagnosing …",
        records.records.len(),
        if setups.is_empty() {
            String::new()
        } else {
            format!(
                " from {} setups ({}), {} check points kept out",
                setups.len(),
                setups.join(", "),
                records.check.len()
            )
        },
        records.rejected.len()
    );
    let declared = DeclaredModel {
        machine: &model.machine,
        machine_terms: &model.machine_terms,
        instrument_terms: &model.instrument_terms,
        setup: &model.setup,
    };
    let d = diagnose(&declared, &records, options)?;
    Ok((model, d))
}

/// Write the report directory: DIR/model.yaml (the augmented model), DIR/diagnosis.json and
/// DIR/index.html with its figures. Returns the page's path.
pub fn write_report(
    dir: &Path,
    model: &CellModel,
    d: &Diagnosis,
    title: &str,
) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    write(&dir.join("model.yaml"), &augmented_model(model, d, dir)?)?;
    write(
        &dir.join("diagnosis.json"),
        &serde_json::to_string_pretty(&d.report)?,
    )?;
    let page = html_report(d, title)?;
    page.write_to(dir)
        .map_err(|e| anyhow::anyhow!("cannot write the report into {}: {e}", dir.display()))
}

fn run_inner(a: &DiagnoseArgs) -> anyhow::Result<()> {
    let json_to_stdout = a.json.as_deref() == Some("-");
    let say = |s: &str| {
        if json_to_stdout {
            eprint!("{s}");
        } else {
            print!("{s}");
        }
    };
    let (model, d) = diagnose_bags(&a.model, &a.bags, &options(a))?;
    // Files first, words last: a reader that closes stdout early must not cost the report.
    let json = serde_json::to_string_pretty(&d.report)?;
    if let Some(file) = a.json.as_deref().filter(|f| *f != "-") {
        write(Path::new(file), &json)?;
    }
    if let Some(path) = &a.residuals {
        write(path, &residuals_csv(&d))?;
    }
    let index = match &a.report {
        Some(dir) => Some(write_report(
            dir,
            &model,
            &d,
            &format!("metrocell diagnose: {}", a.model.display()),
        )?),
        None => None,
    };
    say(&summary_text(&d));
    if let (Some(index), Some(dir)) = (index, &a.report) {
        say(&format!(
            "report: {} (augmented model: {})\n",
            index.display(),
            dir.join("model.yaml").display()
        ));
    }
    if json_to_stdout {
        println!("{json}");
    }
    Ok(())
}

/// Run the command; the exit status.
pub fn run(a: DiagnoseArgs) -> i32 {
    match run_inner(&a) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("metrocell diagnose: {e:#}");
            1
        }
    }
}
