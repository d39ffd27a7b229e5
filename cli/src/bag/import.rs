//! `metrocell bag import CSV|EXPORT_DIR -o BAG [--mapping MAP.yaml]`

use std::path::{Path, PathBuf};

use anyhow::Context;
use metrocell_bag::WriterOptions;
use metrocell_bagtools::export_manifest::ExportManifest;
use metrocell_bagtools::import::{import_csv, ImportReport, Mapping};
use metrocell_bagtools::reimport::{
    csv_rows, inferred_topic, is_export_header, rebuild_bag, ExportedFile, RowSource,
};

#[derive(clap::Args)]
#[command(after_help = "Two kinds of input:\n\
1. What `metrocell bag export` wrote (CSV or Parquet): the export directory, or one of its files. The bag is rebuilt \
as it was recorded — every message with its fields (header stamps included) and its log and publish times, each topic \
with its type and QoS from the directory's export.yaml (one file without it: the topic from its name, the type from its \
columns). No mapping is needed.\n\
2. A point-measurement CSV (metrocell's point layout, or another program's export with --mapping). Layout (header row): \
timestamp, point_id, measured_x/y/z [m], u_x/u_y/u_z or u95 [m], \
optional nominal_x/y/z [m, the commanded tool point], joint.<name>, velocity.<name> [m/s], approach.<axis> [+1/-1], \
instrument_on_time [same forms as timestamp], temperature.<name> [°C], pressure [Pa], humidity [0..1], aux.<name>.\n\
Topics: /measured_points, /machine/commanded_joint_states (joints and velocities), /machine/approach_directions, \
/tracker/power_on, /temperature/<name>, /air/pressure, /air/humidity, /aux_channels.\n\
A mapping's scale/offset apply to the time columns too: timestamp: {column: t_s, offset: 1767225600} reads seconds since \
a job's start.\n\
A mapping YAML maps these fields to another file's columns with unit conversion (see \
crates/bagtools/examples/leica_mapping.yaml).\n\
Bad rows are reported (file:line, column) and skipped; exit status 1 if any row was skipped.\n\n\
Examples:\n  metrocell bag export run42 -o run42_csv && metrocell bag import run42_csv -o run42_again\n  \
metrocell bag import crates/bagtools/examples/leica_export.csv --mapping crates/bagtools/examples/leica_mapping.yaml -o run_leica")]
pub struct ImportArgs {
    /// A point CSV, a `bag export` directory, or one file of an export (.csv or .parquet)
    #[arg(value_name = "CSV|EXPORT_DIR")]
    input: PathBuf,
    /// Output bag directory (must not exist yet)
    #[arg(short, long)]
    output: PathBuf,
    /// Column-mapping YAML for point CSVs of other software
    #[arg(long)]
    mapping: Option<PathBuf>,
}

pub fn run(a: ImportArgs) -> anyhow::Result<i32> {
    let report = match a.mapping.as_deref() {
        None if a.input.is_dir() => rebuild_bag(
            export_directory(&a.input)?,
            &a.output,
            WriterOptions::default(),
        )?,
        None if is_exported_file(&a.input)? => rebuild_bag(
            vec![exported_file(&a.input)?],
            &a.output,
            WriterOptions::default(),
        )?,
        mapping => {
            let mapping = mapping.map(Mapping::load).transpose()?;
            import_csv(
                &a.input,
                &a.output,
                mapping.as_ref(),
                WriterOptions::default(),
            )?
        }
    };
    print_report(&report, &a.output);
    Ok(if report.rows_rejected() > 0 { 1 } else { 0 })
}

fn print_report(report: &ImportReport, output: &Path) {
    for e in &report.errors {
        eprintln!("skipped: {e}");
    }
    println!(
        "{} rows read, {} imported, {} skipped -> {}",
        report.rows_read,
        report.rows_imported,
        report.rows_rejected(),
        output.display()
    );
    for (t, n) in &report.messages_per_topic {
        println!("  {t}: {n}");
    }
}

/// Every file an export directory's manifest lists.
fn export_directory(dir: &Path) -> anyhow::Result<Vec<ExportedFile>> {
    let manifest = ExportManifest::read(dir)?.with_context(|| {
        format!("{} holds no export.yaml: give a directory `metrocell bag export` wrote, or one CSV file (point layout or an exported topic)", dir.display())
    })?;
    manifest
        .topics
        .iter()
        .map(|t| {
            let path = dir.join(&t.file);
            let (header, rows) = rows_of(&path)?;
            Ok(ExportedFile {
                path,
                topic: t.clone(),
                header,
                rows,
            })
        })
        .collect()
}

/// One file of an export: its topic from the manifest beside it, or inferred.
fn exported_file(path: &Path) -> anyhow::Result<ExportedFile> {
    let (header, rows) = rows_of(path)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let listed = match path.parent() {
        Some(dir) => ExportManifest::read(dir)?.and_then(|m| m.entry(&name).cloned()),
        None => None,
    };
    let topic = match listed {
        Some(t) => t,
        None => inferred_topic(path, &header)?,
    };
    Ok(ExportedFile {
        path: path.to_path_buf(),
        topic,
        header,
        rows,
    })
}

fn is_parquet(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"))
}

fn rows_of(path: &Path) -> anyhow::Result<(Vec<String>, RowSource)> {
    Ok(if is_parquet(path) {
        metrocell_parquet_export::parquet_rows(path)?
    } else {
        csv_rows(path)?
    })
}

/// A Parquet file, or a CSV whose header is `bag export`'s (log_time_ns, publish_time_ns, …).
fn is_exported_file(path: &Path) -> anyhow::Result<bool> {
    if is_parquet(path) {
        return Ok(true);
    }
    let (header, _) = csv_rows(path)?;
    Ok(is_export_header(&header))
}
