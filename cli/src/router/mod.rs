//! `metrocell router …`: seed 000's photogrammetric calibration of a CNC router — from the
//! drilled plate's hole errors to compensated G-code.

mod fit_command;

#[derive(clap::Subcommand)]
pub enum RouterCommand {
    /// Fit seed 000's planar error field to a plate's hole errors, validate it on held-out columns, compensate G-code
    Fit(fit_command::FitArgs),
}

pub fn run(c: RouterCommand) -> i32 {
    let r = match c {
        RouterCommand::Fit(a) => fit_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
