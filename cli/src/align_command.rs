//! `metrocell align`: seed 003's frame alignment from the command line — the align node's job
//! (nodes/align) in this process: drive the robot through its `MoveTool` action, watch the fixed
//! target through the fiducial node's poses, and write the camera's frame in the tool's.

use std::path::PathBuf;

use metrocell_node::params::set_default as set;
use metrocell_node::MetrocellNode;

use crate::vision::image_input::parse_length;

#[derive(clap::Args)]
#[command(
    after_help = "What it needs running (in the same ROS domain): a robot driver serving the action \
(metrocell_msgs/action/MoveTool: TRANSLATE by a vector, or ROTATE by an angle about an axis through a point; \
msgs/action/MoveTool.action) — or `metrocell-robot-twin` to try it — and the camera with the fiducial node \
publishing the fixed target's pose on fiducials/pose.\n\n\
What it does (seed 003, claims 1–9): translations of --move each way along three axes give the camera's \
rotation (Kabsch; the patent's two moves leave twice the rotation's uncertainty, which a turn's reading of a \
target |t| away carries into the offset); turns of ±ANGLE about two parallel vertical axes AXIS-OFFSET apart give the camera's x/y offset, \
the same about horizontal axes its z offset (solved exactly, not by the patent's ratio equations); each \
stage is repeated in the frame its estimate moved to until its correction falls to three times the \
camera's noise (--sigma), at most 5 passes; the last two estimates of a stage that converged are averaged. Each move is followed by the move back. A reading is the target's position before and \
after a move (the mean of --frames poses) and, for a turn, the turn commanded — not the poses' orientations, \
their noisiest part.\n\n\
Uncertainty: the result's σ (offset per axis, rotation) is logged and written above the mount line; it is \
widened when the start pose's readings scatter more than --sigma (never narrowed).\n\n\
Output: the camera's frame in the tool's on /tf_static (--publish keeps it there), as a fixed URDF \
joint (--urdf) and as a cell file's `mount:` line (--cell-pose).\n\n\
Example:\n  metrocell align --action /ur5/move_tool --move 100mm --angle 30 --axis-offset 100mm --sigma 0.01mm \
--urdf camera_joint.urdf --cell-pose camera_mount.yaml"
)]
pub struct AlignArgs {
    /// The robot's MoveTool action
    #[arg(long, default_value = "robot/move_tool")]
    action: String,
    /// Length of the rotation stage's translations
    #[arg(long = "move", default_value = "100mm", value_parser = parse_length)]
    move_length: f64,
    /// Turn of the offset stages (degrees)
    #[arg(long, default_value_t = 30.0)]
    angle: f64,
    /// Distance between each offset stage's two parallel axes
    #[arg(long, default_value = "100mm", value_parser = parse_length)]
    axis_offset: f64,
    /// The camera's noise per reading component
    #[arg(long, default_value = "0.01mm", value_parser = parse_length)]
    sigma: f64,
    /// Target poses averaged per reading
    #[arg(long, default_value_t = 5)]
    frames: u32,
    /// Longest wait for the robot to make one move (s)
    #[arg(long, default_value_t = 30.0)]
    move_timeout: f64,
    /// Write the fixed URDF joint (tool → camera) here
    #[arg(long)]
    urdf: Option<PathBuf>,
    /// Write the cell file's camera `mount:` line here
    #[arg(long)]
    cell_pose: Option<PathBuf>,
    /// Keep /tf_static published until Ctrl-C
    #[arg(long)]
    publish: bool,
    /// ROS arguments, after `--`: --ros-args -r __ns:=/cell1 -p tool_link:=flange ...
    #[arg(last = true)]
    ros_args: Vec<String>,
}

pub fn run(a: AlignArgs) -> i32 {
    let mut decls = metrocell_align_node::declarations();
    set(&mut decls, "action", a.action.clone());
    set(&mut decls, "move_length", a.move_length);
    set(&mut decls, "angle", a.angle.to_radians());
    set(&mut decls, "axis_offset", a.axis_offset);
    set(&mut decls, "camera_sigma", a.sigma);
    set(&mut decls, "frames", i64::from(a.frames.max(1)));
    set(&mut decls, "move_timeout", a.move_timeout);
    let path = |p: &Option<PathBuf>| {
        p.as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default()
    };
    set(&mut decls, "urdf", path(&a.urdf));
    set(&mut decls, "cell_pose", path(&a.cell_pose));
    set(&mut decls, "keep_publishing", a.publish);
    let argv = std::iter::once("metrocell align".to_string()).chain(a.ros_args.iter().cloned());
    let node = MetrocellNode::builder("align")
        .params(decls)
        .args(argv)
        .and_then(|(b, _)| b.build());
    let mut node = match node {
        Ok(n) => n,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    match metrocell_align_node::run(&mut node) {
        Ok(None) => {
            eprintln!("interrupted before the alignment finished: nothing written");
            130
        }
        Ok(Some(alignment)) => {
            print!("{}", alignment.urdf_joint("camera_mount", "tool", "camera"));
            print!(
                "{}",
                metrocell_align_node::alignment_outputs::cell_mount(&alignment)
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
