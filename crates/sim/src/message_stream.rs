//! The simulation as a time-ordered stream of ROS messages: the twin's samples converted by
//! [`MessageConverter`], with `/clock` ticks merged in.
//!
//! Order: messages come in the twin's sample order (time order, ties broken by the twin);
//! a machine-state sample gives the actual joint state, then the commanded one. A `/clock`
//! tick at time t_k = k·clock_period (k = 0, 1, …, t_k < duration) comes before every
//! sample with t ≥ t_k. A camera frame request gives its `CameraInfo`, then (when the
//! converter renders frames, see [`MessageConverter::with_frames`]) its mono8 `Image` with the
//! same stamp.

use std::collections::VecDeque;

use metrocell_msgs::msg::{ProbeHit, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image, JointState, Temperature};
use metrocell_twin::{Cell, Sample, SampleStream, Simulation};
use nalgebra::Vector3;
use rosmsg::RosMessage;

use crate::camera_frame::{FrameRenderer, FrameRendering};
use crate::camera_intrinsics::CameraIntrinsics;
use crate::cdr::encode_cdr;
use crate::convert;
use crate::error::SimError;
use crate::sim_time::{ros_time, stamp_ns};
use crate::topic_map::{TopicId, TopicMap};

/// A typed ROS message of one of the simulator's types.
#[derive(Debug, Clone, PartialEq)]
pub enum TypedMessage {
    Clock(Clock),
    JointState(JointState),
    Temperature(Temperature),
    Tracker(TrackerMeasurement),
    Probe(ProbeHit),
    CameraInfo(CameraInfo),
    Image(Image),
}

impl TypedMessage {
    /// `pkg/msg/Type`.
    pub fn ros_type(&self) -> &'static str {
        match self {
            TypedMessage::Clock(_) => Clock::ROS_TYPE,
            TypedMessage::JointState(_) => JointState::ROS_TYPE,
            TypedMessage::Temperature(_) => Temperature::ROS_TYPE,
            TypedMessage::Tracker(_) => TrackerMeasurement::ROS_TYPE,
            TypedMessage::Probe(_) => ProbeHit::ROS_TYPE,
            TypedMessage::CameraInfo(_) => CameraInfo::ROS_TYPE,
            TypedMessage::Image(_) => Image::ROS_TYPE,
        }
    }

    /// CDR bytes with the encapsulation header.
    pub fn encode(&self) -> Result<Vec<u8>, SimError> {
        let ty = self.ros_type();
        match self {
            TypedMessage::Clock(m) => encode_cdr(m, ty),
            TypedMessage::JointState(m) => encode_cdr(m, ty),
            TypedMessage::Temperature(m) => encode_cdr(m, ty),
            TypedMessage::Tracker(m) => encode_cdr(m, ty),
            TypedMessage::Probe(m) => encode_cdr(m, ty),
            TypedMessage::CameraInfo(m) => encode_cdr(m, ty),
            TypedMessage::Image(m) => encode_cdr(m, ty),
        }
    }
}

/// One message of the stream, routed to a topic of the [`TopicMap`].
#[derive(Debug, Clone, PartialEq)]
pub struct SimMessage {
    /// Simulation time (s from the start).
    pub t: f64,
    /// `start_time + t` (ns since the Unix epoch) — the header stamp, and the bag's log and
    /// publish time.
    pub stamp_ns: u64,
    pub topic: TopicId,
    pub message: TypedMessage,
}

/// Converts samples of one cell into routed messages (pure given its fields).
#[derive(Debug, Clone)]
pub struct MessageConverter {
    pub topics: TopicMap,
    /// Start of simulated time (ns since the Unix epoch).
    pub start_ns: u64,
    pub camera: CameraIntrinsics,
    tool_offset: Vector3<f64>,
    /// Per thermocouple: (name, topic, location).
    thermocouples: Vec<(String, TopicId, String)>,
    /// Camera mount on the tool (rotation, translation), when the cell has a camera.
    camera_mount: Option<(nalgebra::Matrix3<f64>, Vector3<f64>)>,
    frames: Option<FrameRenderer>,
}

impl MessageConverter {
    pub fn new(cell: &Cell, start_ns: u64, camera: CameraIntrinsics) -> Result<MessageConverter, SimError> {
        let topics = TopicMap::for_cell(cell)?;
        let thermocouples = cell
            .thermocouples
            .iter()
            .zip(&topics.temperatures)
            .map(|(tc, &id)| (tc.name.clone(), id, tc.node.clone().unwrap_or_else(|| "ambient".into())))
            .collect();
        let camera_mount = cell.camera.as_ref().map(|c| (c.mount.rotation, c.mount.translation));
        Ok(MessageConverter { topics, start_ns, camera, tool_offset: cell.machine.tool_offset, thermocouples, camera_mount, frames: None })
    }

    /// Also render an image for every camera frame request (module doc of
    /// [`crate::camera_frame`]); `seed` is the simulation seed (per-frame noise derives from
    /// it). A cell without a camera ignores this. Fails on invalid intrinsics or settings.
    pub fn with_frames(mut self, rendering: FrameRendering, seed: u64) -> Result<MessageConverter, SimError> {
        if let Some((rotation, translation)) = self.camera_mount {
            self.frames = Some(FrameRenderer::new(&self.camera, rendering, rotation, translation, seed)?);
        }
        Ok(self)
    }

    /// The frame renderer, if images are rendered (tests use it for the ground truth).
    pub fn frames(&self) -> Option<&FrameRenderer> {
        self.frames.as_ref()
    }

    /// The `/clock` message at simulation time t.
    pub fn clock(&self, t: f64) -> SimMessage {
        let stamp_ns = stamp_ns(self.start_ns, t);
        SimMessage { t, stamp_ns, topic: self.topics.clock, message: TypedMessage::Clock(convert::clock(ros_time(stamp_ns))) }
    }

    /// The messages of one sample (0, 1 or 2), appended to `out`. A sample whose sensor has
    /// no topic (cannot happen for samples of the same cell) is dropped.
    pub fn convert_into(&self, sample: &Sample, out: &mut VecDeque<SimMessage>) {
        let t = sample.t();
        let ns = stamp_ns(self.start_ns, t);
        let stamp = ros_time(ns);
        let mut push = |topic: TopicId, message: TypedMessage| out.push_back(SimMessage { t, stamp_ns: ns, topic, message });
        match sample {
            Sample::Tracker(s) => {
                if let Some(id) = self.topics.tracker {
                    push(id, TypedMessage::Tracker(convert::tracker_measurement(s, stamp)));
                }
            }
            Sample::Temperature(s) => {
                if let Some((_, id, location)) = self.thermocouples.iter().find(|(name, _, _)| **name == *s.sensor) {
                    push(*id, TypedMessage::Temperature(convert::temperature(s, stamp, location)));
                }
            }
            Sample::MachineState(s) => {
                if let Some((actual_id, commanded_id)) = self.topics.joint_states {
                    let (actual, commanded) = convert::joint_states(s, stamp);
                    push(actual_id, TypedMessage::JointState(actual));
                    push(commanded_id, TypedMessage::JointState(commanded));
                }
            }
            Sample::ProbeHit(s) => {
                if let Some(id) = self.topics.probe {
                    push(id, TypedMessage::Probe(convert::probe_hit(s, stamp, &self.tool_offset)));
                }
            }
            Sample::CameraFrameRequest(r) => {
                if let Some(id) = self.topics.camera_info {
                    push(id, TypedMessage::CameraInfo(convert::camera_info(&self.camera, stamp.clone())));
                }
                if let (Some(id), Some(frames)) = (self.topics.camera_image, &self.frames) {
                    // Settings were validated by FrameRenderer::new; a failure here would be a
                    // renderer bug, and dropping the image keeps the rest of the recording.
                    if let Ok(view) = frames.render(r, ns) {
                        push(id, TypedMessage::Image(convert::mono8_image(view.image, &self.camera.frame_id, stamp)));
                    }
                }
            }
        }
    }

    /// The messages of one sample as a vector.
    pub fn convert(&self, sample: &Sample) -> Vec<SimMessage> {
        let mut q = VecDeque::new();
        self.convert_into(sample, &mut q);
        q.into()
    }
}

/// Iterator over the messages of a simulation (see the module doc for the order).
pub struct MessageStream<'a> {
    samples: SampleStream<'a>,
    converter: &'a MessageConverter,
    pending: VecDeque<SimMessage>,
    clock_period: Option<f64>,
    clock_k: u64,
    duration: f64,
    samples_done: bool,
    /// Time of the last sample taken from the twin.
    last_t: f64,
}

impl<'a> MessageStream<'a> {
    /// `clock_period`: spacing of `/clock` ticks in simulated seconds, `None` for no ticks.
    pub fn new(sim: &'a Simulation, converter: &'a MessageConverter, clock_period: Option<f64>) -> MessageStream<'a> {
        MessageStream {
            samples: sim.samples(),
            converter,
            pending: VecDeque::new(),
            clock_period: clock_period.filter(|p| *p > 0.0 && p.is_finite()),
            clock_k: 0,
            duration: sim.duration(),
            samples_done: false,
            last_t: 0.0,
        }
    }

    /// Why the twin's stream ended early, if it did (a physics term failed mid-run).
    pub fn error(&self) -> Option<SimError> {
        self.samples.error().map(|e| SimError::Simulation { t: self.last_t, reason: e.to_string() })
    }

    fn next_tick(&self) -> Option<f64> {
        let t = self.clock_period? * self.clock_k as f64;
        (t < self.duration).then_some(t)
    }
}

impl Iterator for MessageStream<'_> {
    type Item = SimMessage;
    fn next(&mut self) -> Option<SimMessage> {
        while self.pending.is_empty() && !self.samples_done {
            match self.samples.next() {
                Some(s) => {
                    self.last_t = s.t();
                    self.converter.convert_into(&s, &mut self.pending)
                }
                None => self.samples_done = true,
            }
        }
        if let Some(tick) = self.next_tick() {
            if self.pending.front().is_none_or(|m| tick <= m.t) {
                self.clock_k += 1;
                return Some(self.converter.clock(tick));
            }
        }
        self.pending.pop_front()
    }
}
