//! Seed 003's procedure driven over ROS 2: each move is a `MoveTool` goal to the robot's action
//! server, answered when the robot has settled; the camera's reading comes from the target's
//! position in the mean of the next `frames` poses on `fiducials/pose` (the fiducial node's
//! output) stamped after the robot answered, before and after the move, and — for a turn — the
//! turn the robot was told to make ([`crate::camera_reading`]). Every move is followed by the
//! move back, so the procedure always measures from its start pose.

use std::time::{Duration, Instant};

use metrocell_kinematics::frame_alignment_procedure::AlignmentRig;
use metrocell_kinematics::KinematicsError;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_node::{qos, MetrocellNode, Subscription};
use nalgebra::{Unit, Vector3};
use ros2_client::action::ActionClient;

use crate::camera_reading::{displacement_after_translation, displacement_after_turn};
use crate::move_tool::{client_qos, MoveToolFeedback, MoveToolGoal, MoveToolResult};

/// How long to wait, and how many frames make a reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigTiming {
    /// Poses averaged per reading.
    pub frames: usize,
    /// Longest wait for the robot to accept and finish one move.
    pub move_timeout: Duration,
    /// Longest wait for a reading's frames.
    pub reading_timeout: Duration,
}

/// The robot behind its action, and the camera behind the fiducial node.
pub struct ActionRig<'a> {
    node: &'a mut MetrocellNode,
    client: ActionClient<MoveToolGoal, MoveToolResult, MoveToolFeedback>,
    poses: Subscription<PoseWithCovarianceStamped>,
    token: metrocell_node::ShutdownToken,
    action: String,
    timing: RigTiming,
    /// Moves made (each move and each move back).
    pub moves: usize,
    /// What happened, a line per move, for the log.
    pub on_move: Box<dyn FnMut(&str) + 'a>,
    /// The camera's axes in the base's, once the rotation stage has found them.
    r_rc: Option<nalgebra::Matrix3<f64>>,
    /// The target's position at the start pose, one per move (every move starts there): their
    /// scatter is the camera's reading noise, measured.
    pub start_positions: Vec<Vector3<f64>>,
}

/// What the rig says when the node was asked to shut down mid-procedure.
pub const INTERRUPTED: &str = "interrupted (shutdown requested) before the alignment finished";

fn rig_error(reason: impl Into<String>) -> KinematicsError {
    KinematicsError::Rig {
        reason: reason.into(),
    }
}

impl<'a> ActionRig<'a> {
    /// Connects to the action `action` (e.g. `robot/move_tool`) and the poses on `poses_topic`,
    /// waiting up to `timing.move_timeout` for the robot's action server.
    pub fn connect(
        node: &'a mut MetrocellNode,
        action: &str,
        poses_topic: &str,
        timing: RigTiming,
    ) -> Result<Self, String> {
        let (name, resolved) = crate::move_tool::action_name(node, action)?;
        let client = node
            .ros_node()
            .create_action_client::<MoveToolGoal, MoveToolResult, MoveToolFeedback>(
                ros2_client::ServiceMapping::Enhanced,
                &name,
                &crate::move_tool::action_type(),
                client_qos(),
            )
            .map_err(|e| format!("action client of {resolved}: {e:?}"))?;
        let poses = node
            .subscription::<PoseWithCovarianceStamped>(poses_topic, qos::reliable())
            .map_err(|e| e.to_string())?;
        // in slices, so a shutdown request is seen within one
        let token = node.shutdown_token();
        let deadline = Instant::now() + timing.move_timeout;
        let slice = Duration::from_millis(100);
        let mut matched = [false; 2];
        while !(matched[0] && matched[1]) && Instant::now() < deadline {
            if token.is_triggered() {
                return Err(INTERRUPTED.into());
            }
            if !matched[0] {
                matched[0] = metrocell_node::block_on_within(
                    client.goal_client().wait_for_service(node.ros_node()),
                    slice,
                )
                .is_some();
            } else {
                matched[1] = metrocell_node::block_on_within(
                    client.result_client().wait_for_service(node.ros_node()),
                    slice,
                )
                .is_some();
            }
        }
        if !(matched[0] && matched[1]) {
            return Err(format!(
                "no robot answers the action {resolved} (metrocell_msgs/action/MoveTool) within \
                 {:?}: start the robot's driver (or metrocell-robot-twin), check its name with \
                 -p action:=…, and that both run in the same ROS domain",
                timing.move_timeout
            ));
        }
        // the server's readers of our answers' topics are matched a moment after ours of its
        std::thread::sleep(Duration::from_millis(300));
        Ok(Self {
            node,
            client,
            poses,
            token,
            action: resolved,
            timing,
            moves: 0,
            on_move: Box::new(|_| {}),
            r_rc: None,
            start_positions: Vec::new(),
        })
    }

    fn execute(&mut self, goal: MoveToolGoal, what: &str) -> Result<(), KinematicsError> {
        let deadline = Instant::now() + self.timing.move_timeout;
        let timed_out = || {
            rig_error(format!(
                "the robot did not finish `{what}` on {} within {:?}",
                self.action, self.timing.move_timeout
            ))
        };
        let (request, goal_id) = self
            .client
            .send_goal(goal)
            .map_err(|e| rig_error(format!("sending `{what}`: {e:?}")))?;
        let accepted = loop {
            match self.client.receive_goal_response(request) {
                Ok(Some(r)) => break r.accepted,
                Ok(None) if self.token.is_triggered() => return Err(rig_error(INTERRUPTED)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(2))
                }
                Ok(None) => return Err(timed_out()),
                Err(e) => return Err(rig_error(format!("reading the robot's answer: {e:?}"))),
            }
        };
        if !accepted {
            return Err(rig_error(format!("the robot refused `{what}`")));
        }
        let request = self
            .client
            .request_result(goal_id)
            .map_err(|e| rig_error(format!("asking for `{what}`'s result: {e:?}")))?;
        let result = loop {
            match self.client.receive_result(request) {
                Ok(Some((_, r))) => break r,
                Ok(None) if self.token.is_triggered() => return Err(rig_error(INTERRUPTED)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(2))
                }
                Ok(None) => return Err(timed_out()),
                Err(e) => return Err(rig_error(format!("reading `{what}`'s result: {e:?}"))),
            }
        };
        if !result.success {
            return Err(rig_error(format!(
                "the robot could not `{what}`: {}",
                result.message
            )));
        }
        self.moves += 1;
        (self.on_move)(what);
        Ok(())
    }

    /// The target's mean position in the next `frames` poses stamped after now.
    fn reading(&mut self) -> Result<Vector3<f64>, KinematicsError> {
        let after = self.node.now().to_nanos();
        let deadline = Instant::now() + self.timing.reading_timeout;
        let mut got = Vec::new();
        while got.len() < self.timing.frames {
            match self.poses.take() {
                Ok(Some((m, _))) => {
                    if m.header.stamp.nanos() > after {
                        let p = &m.pose.pose.position;
                        got.push(Vector3::new(p.x, p.y, p.z));
                    }
                }
                Ok(None) if self.token.is_triggered() => return Err(rig_error(INTERRUPTED)),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(2))
                }
                Ok(None) => {
                    return Err(rig_error(format!(
                    "{} of {} target poses within {:?} on fiducials/pose: is the camera running, \
                         the fiducial node detecting the target, and the target in view?",
                    got.len(),
                    self.timing.frames,
                    self.timing.reading_timeout
                )))
                }
                Err(e) => return Err(rig_error(format!("reading fiducials/pose: {e:?}"))),
            }
        }
        Ok(got.iter().sum::<Vector3<f64>>() / got.len() as f64)
    }

    /// The target's position in the camera before and after `there` (then `back`).
    fn measured_move(
        &mut self,
        there: MoveToolGoal,
        back: MoveToolGoal,
        what: &str,
    ) -> Result<(Vector3<f64>, Vector3<f64>), KinematicsError> {
        let before = self.reading()?;
        self.start_positions.push(before);
        self.execute(there, what)?;
        let after = self.reading()?;
        self.execute(back, &format!("{what}, back"))?;
        Ok((before, after))
    }
}

impl ActionRig<'_> {
    /// The target's mean distance from the camera at the start pose (m).
    pub fn target_distance(&self) -> Option<f64> {
        let n = self.start_positions.len();
        (n > 0).then(|| self.start_positions.iter().map(|p| p.norm()).sum::<f64>() / n as f64)
    }

    /// The noise of one displacement reading per component (m), from the scatter of the start
    /// pose's positions (a reading differences two of them): the largest component's
    /// `√2 · SD`. None below three readings.
    pub fn measured_reading_sigma(&self) -> Option<f64> {
        let n = self.start_positions.len();
        if n < 3 {
            return None;
        }
        let mean = self.start_positions.iter().sum::<Vector3<f64>>() / n as f64;
        let var = self
            .start_positions
            .iter()
            .map(|p| (p - mean).component_mul(&(p - mean)))
            .sum::<Vector3<f64>>()
            / (n - 1) as f64;
        Some((2.0 * var.max()).sqrt())
    }
}

impl AlignmentRig for ActionRig<'_> {
    fn translate(&mut self, v: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError> {
        let what = format!(
            "translate by ({:.1}, {:.1}, {:.1}) mm",
            v.x * 1e3,
            v.y * 1e3,
            v.z * 1e3
        );
        let (before, after) = self.measured_move(
            MoveToolGoal::translate(v),
            MoveToolGoal::translate(&-v),
            &what,
        )?;
        Ok(displacement_after_translation(&before, &after))
    }

    fn rotate(
        &mut self,
        axis: &Unit<Vector3<f64>>,
        angle: f64,
        through: &Vector3<f64>,
    ) -> Result<Vector3<f64>, KinematicsError> {
        let what = format!(
            "turn {:.2}° about ({:.3}, {:.3}, {:.3}) through ({:.1}, {:.1}, {:.1}) mm",
            angle.to_degrees(),
            axis.x,
            axis.y,
            axis.z,
            through.x * 1e3,
            through.y * 1e3,
            through.z * 1e3
        );
        let r_rc = self.r_rc.ok_or_else(|| {
            rig_error("a turn before the rotation stage: the camera's axes are not known yet")
        })?;
        let turn = nalgebra::Rotation3::from_axis_angle(axis, angle).into_inner();
        // the point is given from the tool's origin, which the turn moved: the same point seen
        // from there is R(θ)·through (o₁ = a + R(θ)(o₀ − a), so a − o₁ = R(θ)(a − o₀))
        let (before, after) = self.measured_move(
            MoveToolGoal::rotate(axis, angle, through),
            MoveToolGoal::rotate(axis, -angle, &(turn * through)),
            &what,
        )?;
        Ok(displacement_after_turn(&before, &after, &r_rc, &turn))
    }

    fn rotation_estimate(&mut self, r_rc: &nalgebra::Matrix3<f64>) {
        self.r_rc = Some(*r_rc);
    }
}
