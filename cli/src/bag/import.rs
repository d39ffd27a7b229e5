//! `metrocell bag import CSV -o BAG [--mapping MAP.yaml]`

use std::path::PathBuf;

use metrocell_bag::WriterOptions;
use metrocell_bagtools::import::{import_csv, Mapping};

#[derive(clap::Args)]
#[command(after_help = "CSV layout (header row): timestamp, point_id, measured_x/y/z [m], u_x/u_y/u_z or u95 [m], \
optional nominal_x/y/z [m, the commanded tool point], joint.<name>, velocity.<name> [m/s], approach.<axis> [+1/-1], \
instrument_on_time [same forms as timestamp], temperature.<name> [°C], pressure [Pa], humidity [0..1], aux.<name>.\n\
Topics: /measured_points, /machine/commanded_joint_states (joints and velocities), /machine/approach_directions, \
/tracker/power_on, /temperature/<name>, /air/pressure, /air/humidity, /aux_channels.\n\
A mapping's scale/offset apply to the time columns too: timestamp: {column: t_s, offset: 1767225600} reads seconds since \
a job's start.\n\
A mapping YAML maps these fields to another file's columns with unit conversion (see \
crates/bagtools/examples/leica_mapping.yaml).\n\
Bad rows are reported (file:line, column) and skipped; exit status 1 if any row was skipped.\n\n\
Example:\n  metrocell bag import crates/bagtools/examples/leica_export.csv --mapping crates/bagtools/examples/leica_mapping.yaml -o run_leica")]
pub struct ImportArgs {
    /// The CSV file
    csv: PathBuf,
    /// Output bag directory (must not exist yet)
    #[arg(short, long)]
    output: PathBuf,
    /// Column-mapping YAML for exports of other software
    #[arg(long)]
    mapping: Option<PathBuf>,
}

pub fn run(a: ImportArgs) -> anyhow::Result<i32> {
    let mapping = a.mapping.as_deref().map(Mapping::load).transpose()?;
    let report = import_csv(&a.csv, &a.output, mapping.as_ref(), WriterOptions::default())?;
    for e in &report.errors {
        eprintln!("skipped: {e}");
    }
    println!(
        "{} rows read, {} imported, {} skipped -> {}",
        report.rows_read,
        report.rows_imported,
        report.rows_rejected(),
        a.output.display()
    );
    for (t, n) in &report.messages_per_topic {
        println!("  {t}: {n}");
    }
    Ok(if report.rows_rejected() > 0 { 1 } else { 0 })
}
