//! The simulation as a time-ordered stream of ROS messages: the twin's samples converted by
//! [`MessageConverter`], with `/clock` ticks merged in.
//!
//! Order: the cell's states at t = 0 first (the tracker's power-on time, then the load; see
//! [`MessageConverter::initial_messages`]), then messages in the twin's sample order (time
//! order, ties broken by the twin); a machine-state sample gives the actual joint state, then
//! the commanded one. A `/clock` tick at time t_k = k·clock_period (k = 0, 1, …,
//! t_k < duration) comes before every sample with t ≥ t_k. A camera frame request gives its `CameraInfo`, then (when the
//! converter renders frames, see [`MessageConverter::with_frames`]) its mono8 `Image` with the
//! same stamp.
//!
//! Rendering a frame costs far more than simulating between frames, so a stream can render on
//! worker threads ([`MessageStream::with_render_threads`]): it reads ahead of the frame at the
//! front of its queue, hands later frames to the workers, and still yields every message in the
//! order above. Each frame is a pure function of its request and stamp, so the messages are the
//! same whatever the thread count.

use std::collections::VecDeque;
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::WrenchStamped;
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{
    CameraInfo, Image, Imu, JointState, Temperature, TimeReference,
};
use metrocell_twin::{CameraFrameRequest, Cell, PointRole, Sample, SampleStream, Simulation};
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
    PowerOn(TimeReference),
    Load(WrenchStamped),
    Point(MeasuredPoint),
    Imu(Imu),
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
            TypedMessage::PowerOn(_) => TimeReference::ROS_TYPE,
            TypedMessage::Load(_) => WrenchStamped::ROS_TYPE,
            TypedMessage::Point(_) => MeasuredPoint::ROS_TYPE,
            TypedMessage::Imu(_) => Imu::ROS_TYPE,
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
            TypedMessage::PowerOn(m) => encode_cdr(m, ty),
            TypedMessage::Load(m) => encode_cdr(m, ty),
            TypedMessage::Point(m) => encode_cdr(m, ty),
            TypedMessage::Imu(m) => encode_cdr(m, ty),
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
    /// The tracker's `powered_on_before_start` (s), if the cell has a tracker.
    powered_on_before_start: Option<f64>,
    /// The load force (N, machine frame), if the cell has one.
    load_force: Option<Vector3<f64>>,
    /// Per thermocouple: (name, topic, location).
    thermocouples: Vec<(String, TopicId, String)>,
    frames: Option<FrameRenderer>,
    /// The cell camera's fiducial plate (what the frames show).
    plate: Option<crate::camera_frame::FramePlate>,
}

impl MessageConverter {
    pub fn new(
        cell: &Cell,
        start_ns: u64,
        camera: CameraIntrinsics,
    ) -> Result<MessageConverter, SimError> {
        let topics = TopicMap::for_cell(cell)?;
        let thermocouples = cell
            .thermocouples
            .iter()
            .zip(&topics.temperatures)
            .map(|(tc, &id)| {
                (
                    tc.name.clone(),
                    id,
                    tc.node.clone().unwrap_or_else(|| "ambient".into()),
                )
            })
            .collect();
        let camera = CameraIntrinsics::for_cell(cell, camera);
        Ok(MessageConverter {
            topics,
            start_ns,
            camera,
            plate: cell.camera.as_ref().map(|c| c.plate),
            tool_offset: cell.machine.tool_offset,
            powered_on_before_start: cell.tracker.as_ref().map(|t| t.powered_on_before_start),
            load_force: cell.load_force,
            thermocouples,
            frames: None,
        })
    }

    /// Also render an image for every camera frame request (module doc of
    /// [`crate::camera_frame`]); `seed` is the simulation seed (per-frame noise derives from
    /// it). A cell without a camera ignores this. Fails on invalid intrinsics or settings.
    pub fn with_frames(
        mut self,
        rendering: FrameRendering,
        seed: u64,
    ) -> Result<MessageConverter, SimError> {
        // the cell has a camera exactly when it has an image topic
        if let (Some(_), Some(plate)) = (self.topics.camera_image, &self.plate) {
            self.frames = Some(FrameRenderer::new(&self.camera, plate, rendering, seed)?);
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
        SimMessage {
            t,
            stamp_ns,
            topic: self.topics.clock,
            message: TypedMessage::Clock(convert::clock(ros_time(stamp_ns))),
        }
    }

    /// The cell's states, stamped at t = 0 (the start): when the tracker was powered on
    /// (`start − powered_on_before_start`) and the load. Published once, latched.
    pub fn initial_messages(&self) -> Vec<SimMessage> {
        let ns = stamp_ns(self.start_ns, 0.0);
        let mut out = Vec::new();
        if let (Some(topic), Some(before)) = (self.topics.power_on, self.powered_on_before_start) {
            let powered_on = ns as i64 - (before * 1e9).round() as i64;
            out.push(SimMessage {
                t: 0.0,
                stamp_ns: ns,
                topic,
                message: TypedMessage::PowerOn(convert::power_on(powered_on, ros_time(ns))),
            });
        }
        if let (Some(topic), Some(force)) = (self.topics.load, self.load_force) {
            out.push(SimMessage {
                t: 0.0,
                stamp_ns: ns,
                topic,
                message: TypedMessage::Load(convert::load(&force, ros_time(ns))),
            });
        }
        out
    }

    /// The messages of one sample (0, 1 or 2), appended to `out`. A sample whose sensor has
    /// no topic (cannot happen for samples of the same cell) is dropped.
    pub fn convert_into(&self, sample: &Sample, out: &mut VecDeque<SimMessage>) {
        if let Some(frame) = self.convert_all_but_image(sample, out) {
            if let Some(image) =
                self.render_image(&frame.request, frame.stamp_ns, frame.stamp.clone())
            {
                out.push_back(frame.message(image));
            }
        }
    }

    /// The image message of a frame request, or None if rendering failed: settings were
    /// validated by FrameRenderer::new, so a failure here would be a renderer bug, and dropping
    /// the image keeps the rest of the recording.
    fn render_image(
        &self,
        request: &CameraFrameRequest,
        stamp_ns: u64,
        stamp: Time,
    ) -> Option<Image> {
        let view = self.frames.as_ref()?.render(request, stamp_ns).ok()?;
        Some(convert::mono8_image(
            view.image,
            &self.camera.frame_id,
            stamp,
        ))
    }

    /// [`Self::convert_into`] without rendering: the frame to render, if this sample asks for
    /// an image, is returned instead (its message goes after those pushed here).
    fn convert_all_but_image(
        &self,
        sample: &Sample,
        out: &mut VecDeque<SimMessage>,
    ) -> Option<FrameJob> {
        let t = sample.t();
        let ns = stamp_ns(self.start_ns, t);
        let stamp = ros_time(ns);
        let mut push = |topic: TopicId, message: TypedMessage| {
            out.push_back(SimMessage {
                t,
                stamp_ns: ns,
                topic,
                message,
            })
        };
        match sample {
            Sample::Tracker(s) => {
                if let Some(id) = self.topics.tracker {
                    push(
                        id,
                        TypedMessage::Tracker(convert::tracker_measurement(s, stamp)),
                    );
                }
            }
            Sample::Temperature(s) => {
                if let Some((_, id, location)) = self
                    .thermocouples
                    .iter()
                    .find(|(name, _, _)| **name == *s.sensor)
                {
                    push(
                        *id,
                        TypedMessage::Temperature(convert::temperature(s, stamp, location)),
                    );
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
                    push(
                        id,
                        TypedMessage::Probe(convert::probe_hit(s, stamp, &self.tool_offset)),
                    );
                }
            }
            Sample::StationPoint(p) => {
                let topic = match p.role {
                    PointRole::Fit => self.topics.measured_points,
                    PointRole::Check => self.topics.check_points,
                };
                if let Some(id) = topic {
                    push(id, TypedMessage::Point(convert::station_point(p, stamp)));
                }
            }
            Sample::Acceleration(a) => {
                if let Some(id) = self.topics.imu(&a.sensor) {
                    push(id, TypedMessage::Imu(convert::imu(a, stamp)));
                }
            }
            Sample::CameraFrameRequest(r) => {
                if let Some(id) = self.topics.camera_info {
                    push(
                        id,
                        TypedMessage::CameraInfo(convert::camera_info(&self.camera, stamp.clone())),
                    );
                }
                if let (Some(topic), Some(_)) = (self.topics.camera_image, &self.frames) {
                    return Some(FrameJob {
                        t,
                        stamp_ns: ns,
                        stamp,
                        topic,
                        request: r.clone(),
                    });
                }
            }
        }
        None
    }

    /// The messages of one sample as a vector.
    pub fn convert(&self, sample: &Sample) -> Vec<SimMessage> {
        let mut q = VecDeque::new();
        self.convert_into(sample, &mut q);
        q.into()
    }
}

/// A camera frame still to be rendered, with where its message goes.
struct FrameJob {
    t: f64,
    stamp_ns: u64,
    stamp: Time,
    topic: TopicId,
    request: CameraFrameRequest,
}

impl FrameJob {
    fn message(&self, image: Image) -> SimMessage {
        SimMessage {
            t: self.t,
            stamp_ns: self.stamp_ns,
            topic: self.topic,
            message: TypedMessage::Image(image),
        }
    }
}

/// A queued message: ready, or a frame a worker is rendering (None = rendering failed).
enum Slot {
    Ready(SimMessage),
    Rendering {
        job: FrameJob,
        image: mpsc::Receiver<Option<Image>>,
    },
}

impl Slot {
    fn t(&self) -> f64 {
        match self {
            Slot::Ready(m) => m.t,
            Slot::Rendering { job, .. } => job.t,
        }
    }
}

/// One frame to render: the request, its sequence number, its stamp, and where the image goes.
type RenderJob = (
    CameraFrameRequest,
    u64,
    Time,
    mpsc::SyncSender<Option<Image>>,
);

/// Worker threads rendering frames for one stream.
struct RenderPool {
    jobs: Option<mpsc::Sender<RenderJob>>,
    workers: Vec<JoinHandle<()>>,
    /// Frames handed out and not yet taken from the queue.
    in_flight: usize,
}

impl RenderPool {
    fn new(converter: &MessageConverter, threads: usize) -> RenderPool {
        let (tx, rx) = mpsc::channel::<RenderJob>();
        let rx = Arc::new(Mutex::new(rx));
        let converter = Arc::new(converter.clone());
        let workers = (0..threads)
            .map(|_| {
                let (rx, converter) = (Arc::clone(&rx), Arc::clone(&converter));
                std::thread::spawn(move || loop {
                    // The lock is held only while waiting for a job, not while rendering.
                    let job = rx.lock().map(|r| r.recv());
                    let Ok(Ok((request, stamp_ns, stamp, reply))) = job else {
                        return;
                    };
                    // The stream may have been dropped meanwhile: nobody to tell.
                    let _ = reply.send(converter.render_image(&request, stamp_ns, stamp));
                })
            })
            .collect();
        RenderPool {
            jobs: Some(tx),
            workers,
            in_flight: 0,
        }
    }
}

impl Drop for RenderPool {
    fn drop(&mut self) {
        self.jobs = None; // closes the channel: workers finish their frame and return
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

/// Most messages a stream with render threads queues while it reads ahead.
const MAX_READ_AHEAD: usize = 1 << 17;

/// Iterator over the messages of a simulation (see the module doc for the order).
pub struct MessageStream<'a> {
    samples: SampleStream<'a>,
    converter: &'a MessageConverter,
    pending: VecDeque<Slot>,
    /// Scratch for one sample's ready messages.
    converted: VecDeque<SimMessage>,
    pool: Option<RenderPool>,
    clock_period: Option<f64>,
    clock_k: u64,
    duration: f64,
    samples_done: bool,
    /// Time of the last sample taken from the twin.
    last_t: f64,
}

impl<'a> MessageStream<'a> {
    /// `clock_period`: spacing of `/clock` ticks in simulated seconds, `None` for no ticks.
    pub fn new(
        sim: &'a Simulation,
        converter: &'a MessageConverter,
        clock_period: Option<f64>,
    ) -> MessageStream<'a> {
        MessageStream {
            samples: sim.samples(),
            converter,
            pending: converter
                .initial_messages()
                .into_iter()
                .map(Slot::Ready)
                .collect(),
            converted: VecDeque::new(),
            pool: None,
            clock_period: clock_period.filter(|p| *p > 0.0 && p.is_finite()),
            clock_k: 0,
            duration: sim.duration(),
            samples_done: false,
            last_t: 0.0,
        }
    }

    /// Render camera frames on `threads` worker threads (0 = on the calling thread, the
    /// default), reading ahead by up to `threads + 1` frames. Same messages, same order.
    pub fn with_render_threads(mut self, threads: usize) -> MessageStream<'a> {
        self.pool = (threads > 0 && self.converter.frames.is_some())
            .then(|| RenderPool::new(self.converter, threads));
        self
    }

    /// Why the twin's stream ended early, if it did (a physics term failed mid-run).
    pub fn error(&self) -> Option<SimError> {
        self.samples.error().map(|e| SimError::Simulation {
            t: self.last_t,
            reason: e.to_string(),
        })
    }

    fn next_tick(&self) -> Option<f64> {
        let t = self.clock_period? * self.clock_k as f64;
        (t < self.duration).then_some(t)
    }

    /// Convert the next sample into the queue; false when the twin's stream has ended.
    fn pull(&mut self) -> bool {
        let Some(s) = self.samples.next() else {
            self.samples_done = true;
            return false;
        };
        self.last_t = s.t();
        let Some(pool) = self.pool.as_mut() else {
            self.converter.convert_into(&s, &mut self.converted);
            self.pending
                .extend(self.converted.drain(..).map(Slot::Ready));
            return true;
        };
        let frame = self
            .converter
            .convert_all_but_image(&s, &mut self.converted);
        self.pending
            .extend(self.converted.drain(..).map(Slot::Ready));
        if let Some(job) = frame {
            let (reply, image) = mpsc::sync_channel(1);
            let sent = pool.jobs.as_ref().is_some_and(|tx| {
                tx.send((job.request.clone(), job.stamp_ns, job.stamp.clone(), reply))
                    .is_ok()
            });
            if sent {
                pool.in_flight += 1;
                self.pending.push_back(Slot::Rendering { job, image });
            } else if let Some(img) =
                self.converter
                    .render_image(&job.request, job.stamp_ns, job.stamp.clone())
            {
                self.pending.push_back(Slot::Ready(job.message(img)));
            }
        }
        true
    }

    /// Whether to read further ahead: the front frame is still rendering and the workers
    /// could take another one.
    fn read_ahead(&self) -> bool {
        match (&self.pool, self.pending.front()) {
            (Some(pool), Some(Slot::Rendering { .. })) => {
                pool.in_flight <= pool.workers.len() && self.pending.len() < MAX_READ_AHEAD
            }
            _ => false,
        }
    }
}

impl Iterator for MessageStream<'_> {
    type Item = SimMessage;
    fn next(&mut self) -> Option<SimMessage> {
        loop {
            while (self.pending.is_empty() || self.read_ahead()) && !self.samples_done {
                self.pull();
            }
            if let Some(tick) = self.next_tick() {
                if self.pending.front().is_none_or(|m| tick <= m.t()) {
                    self.clock_k += 1;
                    return Some(self.converter.clock(tick));
                }
            }
            match self.pending.pop_front()? {
                Slot::Ready(m) => return Some(m),
                Slot::Rendering { job, image } => {
                    if let Some(pool) = self.pool.as_mut() {
                        pool.in_flight -= 1;
                    }
                    // A worker that died (panicked) counts as a failed render.
                    if let Ok(Some(img)) = image.recv() {
                        return Some(job.message(img));
                    }
                }
            }
        }
    }
}
