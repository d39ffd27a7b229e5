//! `metrocell-robot-twin`: a robot with a camera on its tool, for the align node's tests and
//! for trying it without a robot. It serves `robot/move_tool` (metrocell_msgs/action/MoveTool)
//! by moving its tool at once, and publishes what the camera and the fiducial node would:
//! the fixed target's pose in the camera on `fiducials/pose` at `rate`, with Gaussian noise of
//! `noise` m per position component and `rotation_noise` rad per axis.
//!
//! The truth (parameters): the camera's origin `camera_offset` from the tool's (base axes, m) and
//! its axes `camera_rpy` (URDF roll, pitch, yaw in rad, R = Rz·Ry·Rx: camera → tool, the tool
//! starting with the base's axes), the target `target_distance` m ahead of the camera's start.
//!
//! With `camera_images:=true` it publishes the camera's frames instead (`camera/image_raw`,
//! mono8, and `camera/camera_info`): a checkerboard target (`board` squares of `square` m,
//! centred on the camera's start axis) rendered by the twin's renderer through a 1280 × 960 px,
//! f = 1400 px lens with the twin's blur and sensor noise — for the camera and fiducial nodes
//! (`metrocell-fiducial` with `family:=checkerboard`) to measure.
//!
//!   metrocell-robot-twin --ros-args -p camera_offset:="[0.06, -0.02, 0.09]" -p noise:=1e-5

use std::time::{Duration, Instant};

use metrocell_align_node::move_tool::{
    from_msg, server_qos, MoveToolFeedback, MoveToolGoal, MoveToolResult, ROTATE, TRANSLATE,
};
use metrocell_msgs::geometry_msgs::msg::{
    Point, Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion,
};
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, MetrocellNode, ParamDecl};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use ros2_client::action::{GetResultResponse, GoalStatusEnum, SendGoalResponse};

fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new(
            "camera_offset",
            vec![0.06, -0.02, 0.09],
            "true camera origin from the tool's [m] (base axes)",
        ),
        ParamDecl::new(
            "camera_rpy",
            vec![3.10, 0.05, -0.08],
            "true camera axes in the tool's: URDF roll, pitch, yaw [rad]",
        ),
        ParamDecl::new(
            "target_distance",
            0.4,
            "the target's distance ahead of the camera at the start [m]",
        )
        .with_range(0.01, 10.0),
        ParamDecl::new("noise", 1e-5, "σ of each position component of a pose [m]")
            .with_range(0.0, 1.0),
        ParamDecl::new(
            "rotation_noise",
            1e-5,
            "σ of a pose's rotation about each axis [rad]",
        )
        .with_range(0.0, 1.0),
        ParamDecl::new("rate", 50.0, "poses per second").with_range(0.1, 10000.0),
        ParamDecl::new("seed", 1i64, "noise seed"),
        ParamDecl::new(
            "camera_images",
            false,
            "publish rendered camera frames of a checkerboard instead of poses",
        ),
        ParamDecl::new(
            "board",
            vec![10i64, 7],
            "camera_images: the checkerboard's squares (x, y)",
        ),
        ParamDecl::new(
            "square",
            0.012,
            "camera_images: the checkerboard's square [m]",
        )
        .with_range(1e-3, 1.0),
    ]
}

fn vec3(v: Vec<f64>, name: &str) -> Result<Vector3<f64>, String> {
    match v[..] {
        [x, y, z] => Ok(Vector3::new(x, y, z)),
        _ => Err(format!("{name}: expected three numbers, got {v:?}")),
    }
}

fn gaussian(rng: &mut impl Rng) -> f64 {
    // Box–Muller
    let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// The tool after `goal` (base frame), or why the goal is refused.
fn moved(tool: &Isometry3<f64>, goal: &MoveToolGoal) -> Result<Isometry3<f64>, String> {
    match goal.kind {
        TRANSLATE => {
            let v = from_msg(&goal.translation);
            if !v.iter().all(|c| c.is_finite()) {
                return Err("translation is not finite".into());
            }
            Ok(Translation3::from(v) * tool)
        }
        ROTATE => {
            let axis = from_msg(&goal.axis);
            let through = from_msg(&goal.through);
            if !(axis.iter().chain(through.iter()).all(|c| c.is_finite()) && goal.angle.is_finite())
                || axis.norm() < 1e-9
            {
                return Err("axis, angle and point must be finite, the axis not zero".into());
            }
            let turn = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), goal.angle);
            let a = tool.translation.vector + through;
            Ok(Isometry3::from_parts(
                (a + turn * (tool.translation.vector - a)).into(),
                turn * tool.rotation,
            ))
        }
        k => Err(format!("kind {k} is neither TRANSLATE (0) nor ROTATE (1)")),
    }
}

/// The twin's camera looking at a checkerboard.
struct BoardCamera {
    camera: metrocell_camera_model::CameraModel,
    target: metrocell_vision::render::PlanarTarget,
    size: [f64; 2],
    info: CameraInfo,
}

impl BoardCamera {
    fn new(board: &[i64], square: f64) -> Result<Self, String> {
        let &[x, y] = board else {
            return Err(format!("board: expected two square counts, got {board:?}"));
        };
        if x < 2 || y < 2 {
            return Err(format!("board: at least 2 × 2 squares, got {x} × {y}"));
        }
        let camera = metrocell_camera_model::CameraModel::new(
            1280,
            960,
            1400.0,
            1400.0,
            639.5,
            479.5,
            metrocell_camera_model::Distortion::none(),
        )
        .map_err(|e| e.to_string())?;
        let info = metrocell_camera_model::CameraInfo::from_model("camera_optical_frame", &camera)
            .to_msg();
        Ok(Self {
            camera,
            target: metrocell_vision::render::PlanarTarget {
                items: vec![metrocell_vision::render::TargetItem::Checkerboard {
                    top_left: [0.0, 0.0],
                    square,
                    squares_x: x as u32,
                    squares_y: y as u32,
                    top_left_black: true,
                }],
            },
            size: [x as f64 * square, y as f64 * square],
            info,
        })
    }

    /// A frame of the board at `pose` (board → camera).
    fn render(&self, pose: Isometry3<f64>, seed: u64) -> Result<image::GrayImage, String> {
        let settings = metrocell_vision::render::RenderSettings {
            seed,
            ..metrocell_simulation::FrameRendering::default().settings
        };
        metrocell_vision::render::render_view(&self.camera, &pose, &self.target, &settings)
            .map(|v| v.image)
            .map_err(|e| format!("rendering the camera's frame: {e}"))
    }
}

fn run() -> Result<(), String> {
    let (mut node, _) =
        MetrocellNode::from_env_args("robot_twin", declarations()).map_err(|e| e.to_string())?;
    let offset = vec3(
        node.param("camera_offset").map_err(|e| e.to_string())?,
        "camera_offset",
    )?;
    let rpy = vec3(
        node.param("camera_rpy").map_err(|e| e.to_string())?,
        "camera_rpy",
    )?;
    let distance: f64 = node.param("target_distance").map_err(|e| e.to_string())?;
    let noise: f64 = node.param("noise").map_err(|e| e.to_string())?;
    let rotation_noise: f64 = node.param("rotation_noise").map_err(|e| e.to_string())?;
    let rate: f64 = node.param("rate").map_err(|e| e.to_string())?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
        node.param::<i64>("seed").map_err(|e| e.to_string())? as u64,
    );
    // tool → camera; the target ahead of the camera's start, facing it
    let mount = Isometry3::from_parts(
        offset.into(),
        UnitQuaternion::from_euler_angles(rpy.x, rpy.y, rpy.z),
    );
    let mut tool = Isometry3::identity();
    let target = tool * mount * Isometry3::translation(0.0, 0.0, distance);

    let (name, resolved) = metrocell_align_node::move_tool::action_name(&node, "robot/move_tool")?;
    let server = node
        .ros_node()
        .create_action_server::<MoveToolGoal, MoveToolResult, MoveToolFeedback>(
            ros2_client::ServiceMapping::Enhanced,
            &name,
            &metrocell_align_node::move_tool::action_type(),
            server_qos(),
        )
        .map_err(|e| format!("action server {resolved}: {e:?}"))?;
    let poses = node
        .publisher::<PoseWithCovarianceStamped>("fiducials/pose", qos::reliable())
        .map_err(|e| e.to_string())?;
    let images = if node
        .param::<bool>("camera_images")
        .map_err(|e| e.to_string())?
    {
        let board = node.param::<Vec<i64>>("board").map_err(|e| e.to_string())?;
        let square: f64 = node.param("square").map_err(|e| e.to_string())?;
        let renderer = BoardCamera::new(&board, square)?;
        Some((
            node.publisher::<Image>("camera/image_raw", qos::reliable())
                .map_err(|e| e.to_string())?,
            node.publisher::<CameraInfo>("camera/camera_info", qos::reliable())
                .map_err(|e| e.to_string())?,
            renderer,
        ))
    } else {
        None
    };
    // the board's centre on the camera's start axis, its axes the camera's
    let target = match &images {
        Some((_, _, r)) => target * Isometry3::translation(-r.size[0] / 2.0, -r.size[1] / 2.0, 0.0),
        None => target,
    };
    node.info(format!("serving {resolved}; poses on fiducials/pose at {rate} Hz, σ {noise} m, {rotation_noise} rad"));
    let mut results: std::collections::BTreeMap<_, MoveToolResult> = Default::default();
    let token = node.shutdown_token();
    let period = Duration::from_secs_f64(1.0 / rate);
    let mut next = Instant::now();
    let mut moves = 0usize;
    while !token.is_triggered() {
        while let Ok(Some((request, goal))) = server.receive_goal() {
            let result = match moved(&tool, &goal.goal) {
                Ok(t) => {
                    tool = t;
                    moves += 1;
                    MoveToolResult {
                        success: true,
                        message: String::new(),
                    }
                }
                Err(why) => MoveToolResult {
                    success: false,
                    message: why,
                },
            };
            results.insert(goal.goal_id, result);
            let stamp = ros2_client::builtin_interfaces::Time::from_nanos(node.now().to_nanos());
            let _ = server.send_goal_response(
                request,
                SendGoalResponse {
                    accepted: true,
                    stamp,
                },
            );
            // what is published from now on is the settled new pose
            next = Instant::now();
        }
        while let Ok(Some((request, asked))) = server.receive_result_request() {
            if let Some(result) = results.remove(&asked.goal_id) {
                let status = if result.success {
                    GoalStatusEnum::Succeeded
                } else {
                    GoalStatusEnum::Aborted
                };
                let _ = server.send_result(request, GetResultResponse { status, result });
            }
        }
        if let (true, Some((frames, infos, renderer))) = (Instant::now() >= next, &images) {
            next += period;
            let stamp =
                metrocell_msgs::builtin_interfaces::msg::Time::from_nanos(node.now().to_nanos());
            let image = renderer.render((tool * mount).inverse() * target, rng.random())?;
            let mut info = renderer.info.clone();
            info.header.stamp = stamp.clone();
            let _ = infos.publish(info);
            let _ = frames.publish(metrocell_simulation::convert::mono8_image(
                image,
                "camera_optical_frame",
                stamp,
            ));
        } else if Instant::now() >= next {
            next += period;
            let truth = (tool * mount).inverse() * target;
            let dt = Vector3::from_fn(|_, _| noise * gaussian(&mut rng));
            let dr = Vector3::from_fn(|_, _| rotation_noise * gaussian(&mut rng));
            let seen = Isometry3::from_parts(
                (truth.translation.vector + dt).into(),
                UnitQuaternion::from_scaled_axis(dr) * truth.rotation,
            );
            let (t, q) = (seen.translation.vector, seen.rotation);
            let mut covariance = [0.0; 36];
            for k in 0..3 {
                covariance[7 * k] = noise * noise;
                covariance[7 * (k + 3)] = rotation_noise * rotation_noise;
            }
            let _ = poses.publish(PoseWithCovarianceStamped {
                header: Header {
                    stamp: metrocell_msgs::builtin_interfaces::msg::Time::from_nanos(
                        node.now().to_nanos(),
                    ),
                    frame_id: "camera_optical_frame".into(),
                },
                pose: PoseWithCovariance {
                    pose: Pose {
                        position: Point {
                            x: t.x,
                            y: t.y,
                            z: t.z,
                        },
                        orientation: Quaternion {
                            x: q.i,
                            y: q.j,
                            z: q.k,
                            w: q.w,
                        },
                    },
                    covariance,
                },
            });
        }
        token.wait_timeout(Duration::from_millis(1));
    }
    node.info(format!("{moves} moves made"));
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-robot-twin: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
