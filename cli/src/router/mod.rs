//! `metrocell router …`: seed 000's photogrammetric calibration of a CNC router — the printed
//! pattern and drilling job, the photographed plate's hole errors, and the planar error field
//! fitted to them with compensated G-code.

mod fit_command;
mod fit_report;
mod measure_command;
mod pattern_command;
mod simulate_command;

#[derive(clap::Subcommand)]
pub enum RouterCommand {
    /// Write the checkerboard and its inverse to print (SVG, PDF), the nominal hole table and the drilling G-code
    Pattern(pattern_command::PatternArgs),
    /// Measure the drilled plate in photos: each hole's error (reached − commanded) with its σ
    Measure(measure_command::MeasureArgs),
    /// The twin drills the plate with a known error field and photographs it (photos, camera_info, truth)
    Simulate(simulate_command::SimulateArgs),
    /// Fit seed 000's planar error field to a plate's hole errors, validate it on held-out columns, compensate G-code
    Fit(fit_command::FitArgs),
}

pub fn run(c: RouterCommand) -> i32 {
    let r = match c {
        RouterCommand::Pattern(a) => pattern_command::run(a),
        RouterCommand::Measure(a) => measure_command::run(a),
        RouterCommand::Fit(a) => fit_command::run(a),
        RouterCommand::Simulate(a) => simulate_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
