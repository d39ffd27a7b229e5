//! `metrocell compensate gcode|table`: a fitted model file turned into what a machine runs — a
//! rewritten part program, or per-axis compensation tables for the controller.

mod conditions;
mod gcode_command;
mod table_command;

#[derive(clap::Subcommand)]
pub enum CompensateCommand {
    /// Rewrite a G-code program so the machine, with the model's errors, reaches the programmed points
    Gcode(gcode_command::GcodeArgs),
    /// Write per-axis compensation tables (pitch, straightness, reversal) and squareness as CSV
    Table(table_command::TableArgs),
}

pub fn run(c: CompensateCommand) -> i32 {
    let r = match c {
        CompensateCommand::Gcode(a) => gcode_command::run(a),
        CompensateCommand::Table(a) => table_command::run(a),
    };
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    }
}
