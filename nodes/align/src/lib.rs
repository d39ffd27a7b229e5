//! The align node (seed 003, claims 1–9): the camera's frame in a robot tool's, found by driving
//! the robot through pure translations and rotations about parallel axes and watching a fixed
//! target with the camera. Pure parts, unit-tested here:
//! - [`move_tool`]: the `metrocell_msgs/action/MoveTool` action a robot driver implements;
//! - [`camera_reading`]: the target's positions (and the commanded turn) → the camera's own displacement;
//! - [`action_rig`]: the procedure's rig over ROS 2 (the action, the fiducial node's poses);
//! - [`alignment_outputs`]: `/tf_static`, the URDF joint, the cell file's camera mount;
//! - [`run`]: the node's whole job, shared by `metrocell-align` and `metrocell align`.

pub mod action_rig;
pub mod alignment_outputs;
pub mod camera_reading;
pub mod move_tool;

use std::time::Duration;

use metrocell_kinematics::frame_alignment_procedure::{align, Alignment, AlignmentPlan};
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use metrocell_node::{qos, MetrocellNode, ParamDecl};

use action_rig::{ActionRig, RigTiming};

/// The node's parameters (SI).
pub fn declarations() -> Vec<ParamDecl> {
    let plan = AlignmentPlan::default();
    vec![
        ParamDecl::new("action", "robot/move_tool".to_string(), "the robot's MoveTool action (metrocell_msgs/action/MoveTool)"),
        ParamDecl::new("poses", "fiducials/pose".to_string(), "the fixed target's pose in the camera (the fiducial node's output)"),
        ParamDecl::new("move_length", plan.move_length, "length of the rotation stage's two translations [m]").with_range(1e-3, 2.0),
        ParamDecl::new("angle", plan.angle, "turn of the offset stages [rad]").with_range(1e-3, 1.6),
        ParamDecl::new("axis_offset", plan.axis_offset, "distance between the two parallel axes of each offset stage [m]").with_range(1e-3, 2.0),
        ParamDecl::new("camera_sigma", plan.camera_sigma, "the camera's noise per reading component [m]: a stage stops within 3× what it alone gives").with_range(1e-9, 1e-2),
        ParamDecl::new("max_passes", plan.max_passes as i64, "passes a stage may take").with_range(1.0, 50.0),
        ParamDecl::new("frames", 5i64, "target poses averaged per reading").with_range(1.0, 1000.0),
        ParamDecl::new("move_timeout", 30.0, "longest wait for the robot to make one move [s]").with_range(0.1, 3600.0),
        ParamDecl::new("reading_timeout", 10.0, "longest wait for a reading's poses [s]").with_range(0.1, 3600.0),
        ParamDecl::new("tool_link", "tool0".to_string(), "the tool's link (parent of /tf_static's transform and of the URDF joint)"),
        ParamDecl::new("camera_link", "camera_optical_frame".to_string(), "the camera's link (child)"),
        ParamDecl::new("urdf", String::new(), "write the fixed URDF joint here (empty: do not)"),
        ParamDecl::new("cell_pose", String::new(), "write the cell file's camera `mount:` line here (empty: do not)"),
        ParamDecl::new("keep_publishing", false, "keep /tf_static published until shut down (else exit once aligned)"),
    ]
}

/// Runs the procedure with the node's parameters, publishes and writes the result; logs a line
/// per move and stage. `Ok(None)`: shut down (SIGINT/SIGTERM) before it finished.
pub fn run(node: &mut MetrocellNode) -> Result<Option<Alignment>, String> {
    let p = |name: &str| node.param::<f64>(name).map_err(|e| e.to_string());
    let plan = AlignmentPlan {
        move_length: p("move_length")?,
        angle: p("angle")?,
        axis_offset: p("axis_offset")?,
        camera_sigma: p("camera_sigma")?,
        max_passes: node.param::<i64>("max_passes").map_err(|e| e.to_string())? as usize,
    };
    let timing = RigTiming {
        frames: node.param::<i64>("frames").map_err(|e| e.to_string())? as usize,
        move_timeout: Duration::from_secs_f64(p("move_timeout")?),
        reading_timeout: Duration::from_secs_f64(p("reading_timeout")?),
    };
    let s = |name: &str| node.param::<String>(name).map_err(|e| e.to_string());
    let (action, poses) = (s("action")?, s("poses")?);
    let (tool_link, camera_link) = (s("tool_link")?, s("camera_link")?);
    let (urdf, cell_pose) = (s("urdf")?, s("cell_pose")?);
    let keep = node
        .param::<bool>("keep_publishing")
        .map_err(|e| e.to_string())?;
    let tf = node
        .publisher::<TFMessage>("/tf_static", qos::latched())
        .map_err(|e| e.to_string())?;
    let logger = node.logger();
    logger.info(format!(
        "aligning through {action}: translations of {:.1} mm, turns of ±{:.2}° about axes {:.1} mm apart, {} poses a reading",
        plan.move_length * 1e3,
        plan.angle.to_degrees(),
        plan.axis_offset * 1e3,
        timing.frames
    ));
    let interrupted = |e: &str| e.contains(action_rig::INTERRUPTED);
    let alignment = {
        let mut rig = match ActionRig::connect(node, &action, &poses, timing) {
            Ok(rig) => rig,
            Err(e) if interrupted(&e) => return Ok(None),
            Err(e) => return Err(e),
        };
        let log = logger.clone();
        rig.on_move = Box::new(move |what: &str| log.info(what));
        let mut a = match align(&mut rig, &plan) {
            Ok(a) => a,
            Err(e) if interrupted(&e.to_string()) => return Ok(None),
            Err(e) => return Err(e.to_string()),
        };
        logger.info(format!("{} moves", rig.moves));
        if let Some(measured) = rig.measured_reading_sigma() {
            let n = rig.start_positions.len();
            if measured > plan.camera_sigma {
                // the uncertainty follows the camera the data show, never a narrower one
                let ratio = measured / plan.camera_sigma;
                a.offset_covariance *= ratio * ratio;
                a.rotation_sigma *= ratio;
                logger.warn(format!(
                    "the camera's readings scatter by {:.4} mm per component ({n} readings of \
                     the start pose), more than camera_sigma {:.4} mm: the stated uncertainty is \
                     widened by {ratio:.2}×, and the stages stopped on the smaller figure — set \
                     camera_sigma to the measured one",
                    measured * 1e3,
                    plan.camera_sigma * 1e3
                ));
            } else {
                logger.info(format!(
                    "the camera's readings scatter by {:.4} mm per component ({n} readings of the \
                     start pose), within camera_sigma {:.4} mm",
                    measured * 1e3,
                    plan.camera_sigma * 1e3
                ));
            }
        }
        // A turn's reading turns the target's position (|t| away) by the commanded turn through
        // the estimated camera axes: their error δ tilts the turn by ≈ angle·δ, which moves the
        // reading by angle·δ·|t| — at 0.4 m more than the camera's own noise. The procedure's
        // covariance counts the camera's noise only; widen it by what this adds (found by
        // repeating the alignment on the twin: x offsets scattered 2.3× the σ stated without it).
        if let Some(distance) = rig.target_distance() {
            let camera = rig
                .measured_reading_sigma()
                .unwrap_or(0.0)
                .max(plan.camera_sigma);
            let turn = plan.angle * a.rotation_sigma * distance;
            let ratio = (1.0 + (turn / camera).powi(2)).sqrt();
            a.offset_covariance *= ratio * ratio;
            logger.info(format!(
                "a turn's reading carries {:.4} mm from the rotation's uncertainty (target {:.0} mm \
                 away): the offset's σ widened by {ratio:.2}×",
                turn * 1e3,
                distance * 1e3
            ));
        }
        a
    };
    for (stage, passes) in ["rotation", "xy offset", "z offset"]
        .iter()
        .zip(&alignment.passes)
    {
        let sizes: Vec<String> = passes.iter().map(|c| format!("{c:.2e}")).collect();
        logger.info(format!(
            "{stage}: {} passes, corrections {} (rad or m)",
            passes.len(),
            sizes.join(", ")
        ));
    }
    let mount = alignment_outputs::cell_mount(&alignment);
    logger.info(format!(
        "camera in {tool_link}: {}",
        mount.lines().last().unwrap_or_default()
    ));
    logger.info(alignment_outputs::uncertainty(&alignment));
    let _ = tf.publish(alignment_outputs::tf_static(
        &alignment,
        &tool_link,
        &camera_link,
        metrocell_msgs::builtin_interfaces::msg::Time::from_nanos(node.now().to_nanos()),
    ));
    if !urdf.is_empty() {
        std::fs::write(
            &urdf,
            alignment.urdf_joint("camera_mount", &tool_link, &camera_link),
        )
        .map_err(|e| format!("writing {urdf}: {e}"))?;
        logger.info(format!("wrote {urdf}"));
    }
    if !cell_pose.is_empty() {
        std::fs::write(&cell_pose, &mount).map_err(|e| format!("writing {cell_pose}: {e}"))?;
        logger.info(format!("wrote {cell_pose}"));
    }
    let token = node.shutdown_token();
    if keep {
        logger.info("publishing /tf_static until shut down");
        token.wait();
    } else {
        // a latched sample outlives its writer only in the readers that already have it
        token.wait_timeout(Duration::from_secs(1));
    }
    Ok(Some(alignment))
}
