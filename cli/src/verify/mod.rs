//! `metrocell verify …`: seed 001's volumetric verification of a machine tool with a laser
//! tracker — planning the run (points, order, program, tracker station).

mod plan_command;

#[derive(clap::Subcommand)]
pub enum VerifyCommand {
    /// Plan a verification: the mesh, a visiting order that limits backlash, the G-code with dwells, and where to put the tracker
    Plan(plan_command::PlanArgs),
}

pub fn run(c: VerifyCommand) -> i32 {
    let r = match c {
        VerifyCommand::Plan(a) => plan_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
