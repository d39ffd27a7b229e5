//! `metrocell delta …`: seed 002's calibration of a delta printer from what it printed — from
//! measured features of a printed target to Marlin and Klipper settings.

mod fit_command;
mod measurements_file;

#[derive(clap::Subcommand)]
pub enum DeltaCommand {
    /// Identify a delta printer's rod length, tower angles (and, with probed heights, radius and endstops) from a printed target; write M665/M666 and Klipper settings
    Fit(fit_command::FitArgs),
}

pub fn run(c: DeltaCommand) -> i32 {
    let r = match c {
        DeltaCommand::Fit(a) => fit_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
