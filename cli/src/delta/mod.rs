//! `metrocell delta …`: seed 002's calibration of a delta printer from what it printed — the
//! star to print, its dots measured in photos, and the geometry fitted to them with Marlin and
//! Klipper settings.

mod fit_command;
mod fit_report;
mod measure_command;
mod measurements_file;
mod simulate_command;
mod target_command;

#[derive(clap::Subcommand)]
pub enum DeltaCommand {
    /// Write the calibration star to print: its dots and ArUco tiles as STL, and the dots' commanded positions
    Target(target_command::TargetArgs),
    /// Measure the printed star in photos beside a checkerboard card: each dot's position on the bed with its σ
    Measure(measure_command::MeasureArgs),
    /// The twin prints the star with a printer of known geometry and photographs it (photos, camera_info, the truth)
    Simulate(simulate_command::SimulateArgs),
    /// Identify a delta printer's rod length, tower angles (and, with probed heights, radius and endstops) from a printed target; write M665/M666 and Klipper settings
    Fit(fit_command::FitArgs),
}

pub fn run(c: DeltaCommand) -> i32 {
    let r = match c {
        DeltaCommand::Target(a) => target_command::run(a),
        DeltaCommand::Measure(a) => measure_command::run(a),
        DeltaCommand::Fit(a) => fit_command::run(a),
        DeltaCommand::Simulate(a) => simulate_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
