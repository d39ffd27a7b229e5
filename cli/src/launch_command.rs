//! `metrocell launch FILE [name:=value ...]`

use std::path::PathBuf;

#[derive(clap::Args)]
#[command(
    after_help = "Launch files use the ROS 2 YAML launch format (node, arg, let, include, group, executable;\n\
substitutions $(var), $(env), $(optenv), $(find-pkg-share), $(dirname)). Node executables are looked up next to\n\
the metrocell binary, then on PATH. Ctrl-C sends SIGINT to every node and SIGKILL after the grace period.\n\n\
Example:\n  metrocell launch launch-configs/demo.launch.yaml speed:=10 output:=/tmp/cell_bag"
)]
pub struct LaunchArgs {
    /// The launch file (ROS 2 YAML launch format)
    file: PathBuf,
    /// Launch arguments as name:=value, overriding the file's `arg` defaults
    arguments: Vec<String>,
    /// Seconds to wait after SIGINT before killing a node that has not stopped
    #[arg(long, default_value_t = 2.0)]
    grace: f64,
    /// Print the command line of every process and exit without starting anything
    #[arg(long)]
    dry_run: bool,
}

impl LaunchArgs {
    /// Whether this run only prints the plan (starts no process).
    pub fn dry_run(&self) -> bool {
        self.dry_run
    }
}

pub fn run(args: LaunchArgs) -> i32 {
    let launch_args = match metrocell_launch::parse_launch_arguments(&args.arguments) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("metrocell launch: {e}");
            return 2;
        }
    };
    let options = metrocell_launch::LaunchOptions {
        grace_period: std::time::Duration::from_secs_f64(args.grace.max(0.0)),
        ..Default::default()
    };
    if args.dry_run {
        return match metrocell_launch::load_launch_plan(&args.file, &launch_args, &options) {
            Ok(plan) => {
                for p in &plan.processes {
                    println!("[{}] {}", p.label, shell_words(&p.command_line()));
                }
                0
            }
            Err(e) => {
                eprintln!("metrocell launch: {e}");
                2
            }
        };
    }
    match metrocell_launch::run_launch(&args.file, &launch_args, &options) {
        Ok(outcome) => outcome.exit_code(),
        Err(e) => {
            eprintln!("metrocell launch: {e}");
            2
        }
    }
}

/// Joins argv for display, quoting words a shell would split.
fn shell_words(argv: &[String]) -> String {
    argv.iter()
        .map(|w| {
            if !w.is_empty()
                && w.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./:=@%+,".contains(c))
            {
                w.clone()
            } else {
                format!("'{}'", w.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}
