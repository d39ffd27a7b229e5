//! The publishing loop: one raw publisher per topic of the cell's map, messages released when
//! their simulated time is due, `/clock` ticks in between.

use std::time::{Duration, Instant};

use metrocell_msgs::RosMessage;
use metrocell_node::node_directory::guid_prefix;
use metrocell_node::{qos, Diagnostics, MetrocellNode, NodeDirectory, RawPublisher};
use metrocell_simulation::cell_options::load_cell;
use metrocell_simulation::{
    CameraIntrinsics, FrameRendering, MessageConverter, MessageStream, QosKind, TopicSpec,
};
use metrocell_twin::Simulation;
use ros2_client::qos::History;

use crate::parameters::Settings;

/// How often diagnostics values are refreshed (wall clock).
const DIAGNOSTICS_PERIOD: Duration = Duration::from_millis(500);

/// How long the twin still waits after the recorder's readers matched before its first
/// message, so that the recorder can read it (see [`LiveSim::wait_for_recorder`]).
pub const RECORDER_SETTLE: Duration = Duration::from_secs(2);
/// Lag behind schedule above which the node reports a warning (s of wall time).
const LAG_WARNING: f64 = 1.0;

/// History of the live writers: 2.5 s of the fastest stream (joint states at 400 Hz when
/// speed is 20), so a reliable reader that stalls that long still gets every sample.
const LIVE_HISTORY: usize = 1000;

/// Bytes of camera frames a live writer keeps for retransmission: 32 MiB, i.e. 6 frames of the
/// twin's default 5 MP camera, 109 of a 640 × 480 one.
const FRAME_HISTORY_BYTES: usize = 32 << 20;

/// Live, every stream is published reliably, whatever its nominal kind (the bag `metrocell sim`
/// writes keeps the nominal profiles): a reliable writer also matches best-effort readers
/// (ClockQoS, SensorDataQoS subscribers such as the fiducial node), and a recorder, which reads
/// reliably when every publisher is reliable, then gets every message even on a busy machine.
/// Camera frames (`frame_bytes` each, mono8) keep a history bounded in bytes, at least 2 frames,
/// and held to it (`bounded_raw_publisher`): a history of 1000 frames, or RustDDS's default
/// backstop of 8192 while a best-effort reader is matched, would hold gigabytes.
fn publisher_of(
    node: &mut MetrocellNode,
    t: &TopicSpec,
    frame_bytes: usize,
) -> Result<RawPublisher, metrocell_node::NodeError> {
    let stream = qos::reliable().history(History::KeepLast {
        depth: LIVE_HISTORY,
    });
    match t.qos {
        QosKind::SensorData if t.ros_type == metrocell_msgs::sensor_msgs::msg::Image::ROS_TYPE => {
            let frames = (FRAME_HISTORY_BYTES / frame_bytes.max(1)).clamp(2, LIVE_HISTORY);
            node.bounded_raw_publisher(
                &t.name,
                t.ros_type,
                qos::reliable().history(History::KeepLast { depth: frames }),
            )
        }
        QosKind::Clock | QosKind::SensorData | QosKind::Reliable => {
            node.raw_publisher(&t.name, t.ros_type, stream)
        }
        // a state (power-on time, load): a subscriber that joins late still gets it
        QosKind::Latched => node.raw_publisher(&t.name, t.ros_type, qos::latched()),
    }
}

pub struct LiveSim {
    converter: MessageConverter,
    publishers: Vec<RawPublisher>,
    diagnostics: Diagnostics,
    published: u64,
    /// Messages published per topic (index = topic id of the cell's map), /clock included.
    published_per_topic: Vec<u64>,
    wall_start: Instant,
    next_clock: Instant,
    next_diagnostics: Instant,
    /// Last /clock value published (ns), to keep it monotonic.
    last_clock_ns: u64,
}

impl LiveSim {
    pub fn new(
        node: &mut MetrocellNode,
        s: &Settings,
    ) -> Result<LiveSim, Box<dyn std::error::Error>> {
        let cell = load_cell(std::path::Path::new(&s.cell), s.ground_tilt)?;
        // Camera frame requests are rendered as images on /camera/image_raw, like the bag writer.
        let mut converter = MessageConverter::new(&cell, s.start_ns, CameraIntrinsics::default())?;
        if s.camera_images {
            converter = converter.with_frames(FrameRendering::default(), s.seed)?;
        }
        // mono8: a byte per pixel
        let frame_bytes =
            converter.camera.lens.width as usize * converter.camera.lens.height as usize;
        let publishers = converter
            .topics
            .topics
            .iter()
            .map(|t| publisher_of(node, t, frame_bytes))
            .collect::<Result<Vec<_>, _>>()?;
        let now = Instant::now();
        Ok(LiveSim {
            published_per_topic: vec![0; publishers.len()],
            converter,
            publishers,
            diagnostics: node.diagnostics(),
            published: 0,
            wall_start: now,
            next_clock: now,
            next_diagnostics: now,
            last_clock_ns: 0,
        })
    }

    pub fn published(&self) -> u64 {
        self.published
    }

    /// (topic, messages published on it), in the cell map's order.
    pub fn published_per_topic(&self) -> Vec<(&str, u64)> {
        self.publishers
            .iter()
            .zip(&self.published_per_topic)
            .map(|(p, n)| (p.topic(), *n))
            .collect()
    }

    /// Wait until every reliable reader (the recorder among them) has acknowledged every message
    /// this twin published, at most `timeout` in all, so that the last seconds of a run are not
    /// lost when the twin exits with samples still unrepaired (a busy reader lags behind).
    /// Returns the topics still unacknowledged at the deadline.
    pub fn wait_for_acknowledgments(&self, timeout: Duration) -> Vec<&str> {
        let deadline = Instant::now() + timeout;
        self.publishers
            .iter()
            .filter(|p| {
                !p.wait_for_acknowledgments(deadline.saturating_duration_since(Instant::now()))
            })
            .map(|p| p.topic())
            .collect()
    }

    /// Put the per-topic counts in the diagnostics (`published/<topic>`), which is how the demo
    /// checks that the bag holds every message the twin sent.
    pub fn report_counts(&self, finished: bool) {
        for (topic, n) in self.published_per_topic() {
            self.diagnostics.set_value(&format!("published{topic}"), n);
        }
        self.diagnostics
            .set_value("messages_published", self.published);
        self.diagnostics.set_value("finished", finished);
    }

    /// Wait until the participant hosting the node called `recorder` (`recorder` for
    /// metrocell-recorder and `metrocell bag record`, `rosbag2_recorder` for `ros2 bag record`)
    /// subscribes to every topic this twin publishes and each writer has matched a reader, or
    /// `timeout` passes. The node is found by its name in ROS 2's `ros_discovery_info`, so
    /// another participant that reads every topic (the dashboard) does not count. Returns
    /// whether it did; false on timeout or shutdown. Once it does, waits [`RECORDER_SETTLE`]
    /// more before returning.
    pub fn wait_for_recorder(
        &self,
        node: &MetrocellNode,
        recorder: &str,
        timeout: Duration,
    ) -> Result<bool, metrocell_node::NodeError> {
        use std::collections::BTreeSet;
        let token = node.shutdown_token();
        let participant = node.context().domain_participant();
        let mut directory = NodeDirectory::new(&participant)?;
        let wanted: BTreeSet<String> = self
            .publishers
            .iter()
            .map(|p| metrocell_node::names::dds_topic_name(p.topic()))
            .collect();
        let deadline = Instant::now() + timeout;
        loop {
            directory.refresh();
            let recorders = directory.participants_of(recorder);
            let readers = participant.discovered_readers();
            let reads_every_topic = recorders.iter().any(|prefix| {
                let read: BTreeSet<&str> = readers
                    .iter()
                    .filter(|r| guid_prefix(r.reader_proxy.remote_reader_guid) == *prefix)
                    .map(|r| r.subscription_topic_data.topic_name.as_str())
                    .filter(|t| wanted.contains(*t))
                    .collect();
                read.len() == wanted.len()
            });
            if reads_every_topic
                && self
                    .publishers
                    .iter()
                    .all(|p| p.matched_subscriptions() > 0)
            {
                // Seeing the recorder's readers matched here does not mean it can read yet: with
                // DDS Security each writer's keys travel to the reader after the match, and a
                // message that arrives before them is lost to a late-joining reader (the secured
                // demo lost the first ~90 ms of every topic once on a loaded machine, 2026-11-30).
                return Ok(!token.wait_timeout(RECORDER_SETTLE));
            }
            if Instant::now() >= deadline || token.wait_timeout(Duration::from_millis(20)) {
                if !token.is_triggered() {
                    node.warn(format!(
                        "no node called '{recorder}' subscribed to every topic (nodes seen: {}; parameter recorder_node names the recorder)",
                        directory.node_names().join(", ")
                    ));
                }
                return Ok(false);
            }
        }
    }

    /// Run until the simulation ends (true) or shutdown is requested (false).
    pub fn run(
        &mut self,
        node: &MetrocellNode,
        s: &Settings,
    ) -> Result<bool, Box<dyn std::error::Error>> {
        let token = node.shutdown_token();
        self.diagnostics.set_value("speed", s.pacer.speed());
        self.diagnostics.set_value("cell", &s.cell);
        self.wall_start = Instant::now();
        for run in 0u64.. {
            // Each repetition continues simulated time where the previous one ended.
            let offset = run as f64 * s.duration;
            let mut converter = self.converter.clone();
            converter.start_ns = metrocell_simulation::sim_time::stamp_ns(s.start_ns, offset);
            let sim = Simulation::new(
                load_cell(std::path::Path::new(&s.cell), s.ground_tilt)?,
                s.duration,
                s.seed,
            )?;
            let mut stream = MessageStream::new(&sim, &converter, None);
            for m in stream.by_ref() {
                if !self.wait_until(node, s, offset + m.t)? {
                    return Ok(false);
                }
                let bytes = m.message.encode()?;
                match self.publishers[m.topic].publish(&bytes) {
                    Ok(()) => {
                        self.published += 1;
                        self.published_per_topic[m.topic] += 1;
                    }
                    Err(e) => self.diagnostics.warn(format!(
                        "publishing on {} failed: {e}",
                        converter.topics.get(m.topic).name
                    )),
                }
            }
            if let Some(e) = stream.error() {
                return Err(e.into());
            }
            if !self.wait_until(node, s, offset + s.duration)? {
                return Ok(false);
            }
            self.publish_clock(s.start_ns, offset + s.duration);
            self.diagnostics.set_value("runs_completed", run + 1);
            if !s.repeat || token.is_triggered() {
                return Ok(!token.is_triggered());
            }
        }
        Ok(true)
    }

    /// Publish /clock = start + t, never going backwards.
    fn publish_clock(&mut self, start_ns: u64, t: f64) {
        let ns = metrocell_simulation::sim_time::stamp_ns(start_ns, t).max(self.last_clock_ns);
        self.last_clock_ns = ns;
        let clock = metrocell_simulation::TypedMessage::Clock(
            metrocell_simulation::convert::clock(metrocell_simulation::sim_time::ros_time(ns)),
        );
        if let Ok(bytes) = clock.encode() {
            let id = self.converter.topics.clock;
            match self.publishers[id].publish(&bytes) {
                Ok(()) => self.published_per_topic[id] += 1,
                Err(_) => {
                    self.diagnostics.add_count("clock_publish_failures", 1);
                }
            }
        }
    }

    /// Sleep until simulated time `t` is due, publishing /clock and diagnostics meanwhile.
    /// Returns false when shutdown was requested.
    fn wait_until(
        &mut self,
        node: &MetrocellNode,
        s: &Settings,
        t: f64,
    ) -> Result<bool, Box<dyn std::error::Error>> {
        let token = node.shutdown_token();
        let due = self.wall_start + s.pacer.wall_offset(t);
        loop {
            let now = Instant::now();
            if now >= self.next_clock {
                let sim_now = s.pacer.sim_time(now - self.wall_start).min(t);
                self.publish_clock(s.start_ns, sim_now);
                self.next_clock =
                    (self.next_clock + Duration::from_secs_f64(s.clock_period)).max(now);
            }
            if now >= self.next_diagnostics {
                let lag = s.pacer.lag(t, now - self.wall_start);
                self.diagnostics.set_value("sim_time_s", format!("{t:.3}"));
                self.report_counts(false);
                self.diagnostics.set_value("lag_s", format!("{lag:.3}"));
                if lag > LAG_WARNING {
                    self.diagnostics
                        .warn(format!("{lag:.1} s behind schedule: lower speed"));
                } else {
                    self.diagnostics.ok("publishing on schedule");
                }
                self.next_diagnostics = now + DIAGNOSTICS_PERIOD;
            }
            if now >= due {
                return Ok(!token.is_triggered());
            }
            if token.wait_timeout(due.min(self.next_clock).min(self.next_diagnostics) - now) {
                return Ok(false);
            }
        }
    }
}
