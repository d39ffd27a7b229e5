//! `metrocell verify …`: seed 001's volumetric verification of a machine tool with a laser
//! tracker — planning the run (points, order, program, tracker station) and reporting it
//! (identification, Monte Carlo uncertainty, length test, budget).

mod plan_command;
mod plate_command;
mod probe_tip_command;
mod report_command;

#[derive(clap::Subcommand)]
pub enum VerifyCommand {
    /// Plan a verification: the mesh, a visiting order that limits backlash, the G-code with dwells, and where to put the tracker
    Plan(plan_command::PlanArgs),
    /// A calibrated hole plate measured in the XY plane: six XY error components, the squareness in mrad, what correcting them compensates
    Plate(plate_command::PlateArgs),
    /// The probe-tip check: a sphere measured every 15° of the head → range, repeatability, tip eccentricity, three-lobe pattern
    ProbeTip(probe_tip_command::ProbeTipArgs),
    /// Identify the errors from a verification's recordings; Monte Carlo uncertainty, length test against the MPE, ISO/TS 15530-3 budget, one HTML page
    Report(report_command::ReportArgs),
}

pub fn run(c: VerifyCommand) -> i32 {
    let r = match c {
        VerifyCommand::Plan(a) => plan_command::run(a),
        VerifyCommand::Report(a) => report_command::run(a),
        VerifyCommand::Plate(a) => plate_command::run(a),
        VerifyCommand::ProbeTip(a) => probe_tip_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
