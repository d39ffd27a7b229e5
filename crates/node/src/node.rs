//! `MetrocellNode`: a ROS 2 node (ros2-client Context + Node) with metrocell's conventions:
//! names and parameters from the ROS 2 command line, typed and raw endpoints on resolved topic
//! names, rosout logging, a diagnostics heartbeat, simulated time, and shutdown on SIGINT/SIGTERM.
//!
//! Dropping the node stops its background thread (Spinner, heartbeat, clock) and withdraws it
//! from the ROS graph; this takes well under a second.

use ros2_client::qos::QosProfile;
use ros2_client::{MessageTypeName, Name, Publisher, ROSTime, Subscription};
use rosmsg::RosMessage;

use crate::background::{Background, SimTime};
use crate::diagnostics::Diagnostics;
use crate::error::{create_error, NodeError};
use crate::logging::Logger;
use crate::names::{dds_topic_name, fully_qualified_node_name, resolve_topic_name, split_ros_type};
use crate::params::{ParamDecl, ParamError, ParamKind, ParamValue, Parameters};
use crate::raw::{RawPublisher, RawSubscription};
use crate::ros_args::RosArgs;
use crate::shutdown::ShutdownToken;
use crate::topics::{ros_topics_from_dds, TopicInfo};

pub(crate) struct Parts {
    pub name: String,
    pub namespace: String,
    pub ros_args: RosArgs,
    pub parameters: Parameters,
    pub context: ros2_client::Context,
    pub ros_node: ros2_client::Node,
    pub logger: Logger,
    pub diagnostics: Diagnostics,
    pub sim_time: SimTime,
    pub use_sim_time: bool,
    pub shutdown: ShutdownToken,
}

/// A running metrocell node. Create it with [`MetrocellNode::builder`] or [`MetrocellNode::from_env_args`].
pub struct MetrocellNode {
    parts: Parts,
    raw_publisher: Option<rustdds::Publisher>,
    raw_subscriber: Option<rustdds::Subscriber>,
    background: Option<Background>,
}

impl MetrocellNode {
    pub fn builder(default_name: &str) -> crate::builder::NodeBuilder {
        crate::builder::NodeBuilder::new(default_name)
    }

    /// The usual start of a node's `main`: parse `std::env::args()`, declare `decls`, build.
    /// Returns the node and its own (non-ROS) arguments, argv[0] first.
    pub fn from_env_args(
        default_name: &str,
        decls: Vec<ParamDecl>,
    ) -> Result<(MetrocellNode, Vec<String>), NodeError> {
        let (builder, rest) = MetrocellNode::builder(default_name)
            .params(decls)
            .args(std::env::args())?;
        Ok((builder.build()?, rest))
    }

    pub(crate) fn assemble(parts: Parts) -> MetrocellNode {
        MetrocellNode {
            parts,
            raw_publisher: None,
            raw_subscriber: None,
            background: None,
        }
    }

    pub(crate) fn set_background(&mut self, b: Background) {
        self.background = Some(b);
    }

    /// ros2-client's simulated time (it stamps the node's parameter events under
    /// `use_sim_time`), kept current by the node's own `/clock` reader.
    pub(crate) fn ros2_client_simulated_time(
        &self,
    ) -> std::sync::Arc<std::sync::Mutex<ros2_client::ROSTime>> {
        self.parts.ros_node.simulated_time_handle()
    }

    /// Base name after remapping (`talker`).
    pub fn name(&self) -> &str {
        &self.parts.name
    }

    /// Namespace after remapping (`/` or `/cell`).
    pub fn namespace(&self) -> &str {
        &self.parts.namespace
    }

    /// `/cell/talker`.
    pub fn fully_qualified_name(&self) -> String {
        fully_qualified_node_name(&self.parts.namespace, &self.parts.name)
    }

    pub fn ros_args(&self) -> &RosArgs {
        &self.parts.ros_args
    }

    /// Expand a topic name for this node and apply the command-line remaps.
    pub fn resolve_topic(&self, topic: &str) -> Result<String, NodeError> {
        Ok(resolve_topic_name(
            topic,
            &self.parts.namespace,
            &self.parts.name,
            &self.parts.ros_args.remaps,
        )?)
    }

    /// Current value of a declared parameter (reflects remote `ros2 param set`).
    pub fn param<T: ParamKind>(&self, name: &str) -> Result<T, ParamError> {
        let current = self
            .parts
            .ros_node
            .get_parameter(name)
            .and_then(|v| ParamValue::from_ros(&v));
        match current {
            Some(v) => T::from_value(&v).ok_or(ParamError::TypeMismatch {
                name: name.to_string(),
                actual: v.param_type(),
                requested: T::TYPE,
            }),
            None => self.parts.parameters.get(name),
        }
    }

    /// Start watching a declared parameter for changes made at run time (`ros2 param set`, a
    /// `set_parameters` service call, [`Self::set_param`]): poll it with
    /// `watch.poll(|n| node.param(n))`, which gives the new value once per change.
    pub fn watch_param<T: ParamKind + PartialEq + Clone>(
        &self,
        name: &str,
    ) -> Result<crate::params::ParamWatch<T>, ParamError> {
        Ok(crate::params::ParamWatch::new(name, self.param(name)?))
    }

    /// Set a declared parameter from inside the node, as a remote `set_parameters` call would:
    /// checked against its declaration, announced on `/parameter_events`. `Err` says why it was
    /// refused.
    pub fn set_param(&self, name: &str, value: impl Into<ParamValue>) -> Result<(), String> {
        self.parts
            .ros_node
            .set_parameter(name, value.into().to_ros())
    }

    /// The parameters as resolved at start-up, with where each value came from.
    pub fn parameters(&self) -> &Parameters {
        &self.parts.parameters
    }

    fn ros_topic(
        &self,
        topic: &str,
        type_name: MessageTypeName,
        qos: &QosProfile,
    ) -> Result<(String, rustdds::Topic), NodeError> {
        let resolved = self.resolve_topic(topic)?;
        let name =
            Name::parse(&resolved).map_err(|e| create_error(format!("topic '{resolved}'"), e))?;
        let t = self
            .parts
            .ros_node
            .create_topic(&name, type_name, qos)
            .map_err(|e| create_error(format!("topic '{resolved}'"), e))?;
        Ok((resolved, t))
    }

    /// Typed publisher: DDS topic `rt/<resolved>`, DDS type `T::PACKAGE::msg::dds_::T::NAME_`.
    pub fn publisher<T: RosMessage>(
        &mut self,
        topic: &str,
        qos: QosProfile,
    ) -> Result<Publisher<T>, NodeError> {
        let (resolved, t) =
            self.ros_topic(topic, MessageTypeName::new(T::PACKAGE, T::NAME), &qos)?;
        self.parts
            .ros_node
            .create_publisher(&t, Some(qos))
            .map_err(|e| create_error(format!("publisher on '{resolved}' ({})", T::ROS_TYPE), e))
    }

    /// Typed subscription (see [`MetrocellNode::publisher`] for names).
    pub fn subscription<T: RosMessage>(
        &mut self,
        topic: &str,
        qos: QosProfile,
    ) -> Result<Subscription<T>, NodeError> {
        let (resolved, t) =
            self.ros_topic(topic, MessageTypeName::new(T::PACKAGE, T::NAME), &qos)?;
        self.parts
            .ros_node
            .create_subscription(&t, Some(qos))
            .map_err(|e| create_error(format!("subscription on '{resolved}' ({})", T::ROS_TYPE), e))
    }

    /// The DDS topic of a raw endpoint, created with the endpoint's own DDS QoS (as ros2-client's
    /// `Context::create_topic` does from a profile), so that a bound stated there
    /// ([`crate::qos::bounded_qos`]) also holds for RustDDS's topic cache.
    fn raw_topic(
        &self,
        topic: &str,
        ros_type: &str,
        qos: &rustdds::QosPolicies,
    ) -> Result<(String, rustdds::Topic), NodeError> {
        let (pkg, ty) = split_ros_type(ros_type)?;
        let resolved = self.resolve_topic(topic)?;
        let t = self
            .parts
            .context
            .domain_participant()
            .create_topic(
                dds_topic_name(&resolved),
                MessageTypeName::new(&pkg, &ty).dds_msg_type(),
                qos,
                rustdds::TopicKind::NoKey,
            )
            .map_err(|e| create_error(format!("topic '{resolved}'"), e))?;
        Ok((resolved, t))
    }

    /// Publisher of already encoded payloads (4-byte header + CDR) of type `ros_type`
    /// (`pkg/msg/Type`). Raw endpoints are plain DDS writers: they are not listed in the
    /// node's ROS graph entry (`ros2 node info`), but match any peer on the topic.
    pub fn raw_publisher(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: QosProfile,
    ) -> Result<RawPublisher, NodeError> {
        self.create_raw_publisher(topic, ros_type, rustdds::QosPolicies::from(&qos))
    }

    /// [`Self::raw_publisher`] whose history never holds more than its keep-last depth, for
    /// bulky messages (camera frames) sent reliably to readers some of which may be best effort:
    /// see [`crate::qos::bounded_qos`].
    pub fn bounded_raw_publisher(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: QosProfile,
    ) -> Result<RawPublisher, NodeError> {
        self.create_raw_publisher(topic, ros_type, crate::qos::bounded_qos(&qos))
    }

    fn create_raw_publisher(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: rustdds::QosPolicies,
    ) -> Result<RawPublisher, NodeError> {
        let (resolved, t) = self.raw_topic(topic, ros_type, &qos)?;
        if self.raw_publisher.is_none() {
            let p = self
                .parts
                .context
                .domain_participant()
                .create_publisher(&rustdds::QosPolicies::from(crate::qos::reliable()))
                .map_err(|e| create_error("DDS publisher", e))?;
            self.raw_publisher = Some(p);
        }
        let writer = self
            .raw_publisher
            .as_ref()
            .expect("created above")
            .create_datawriter_no_key(&t, Some(qos))
            .map_err(|e| create_error(format!("raw writer on '{resolved}' ({ros_type})"), e))?;
        Ok(RawPublisher {
            writer,
            topic: resolved,
            ros_type: ros_type.to_string(),
            matched: Default::default(),
        })
    }

    /// Subscription that yields payload bytes, source timestamp and publisher GID, for any type.
    pub fn raw_subscription(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: QosProfile,
    ) -> Result<RawSubscription, NodeError> {
        self.create_raw_subscription(topic, ros_type, rustdds::QosPolicies::from(&qos))
    }

    /// [`Self::raw_subscription`] that keeps no more than its keep-last depth of samples: for
    /// bulky messages (camera frames) a node reads only in passing. RustDDS's topic cache
    /// otherwise keeps a reader's last max(64, depth) samples ([`crate::qos::bounded_qos`]).
    pub fn bounded_raw_subscription(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: QosProfile,
    ) -> Result<RawSubscription, NodeError> {
        self.create_raw_subscription(topic, ros_type, crate::qos::bounded_qos(&qos))
    }

    fn create_raw_subscription(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos: rustdds::QosPolicies,
    ) -> Result<RawSubscription, NodeError> {
        let (resolved, t) = self.raw_topic(topic, ros_type, &qos)?;
        if self.raw_subscriber.is_none() {
            let s = self
                .parts
                .context
                .domain_participant()
                .create_subscriber(&rustdds::QosPolicies::from(crate::qos::sensor_data()))
                .map_err(|e| create_error("DDS subscriber", e))?;
            self.raw_subscriber = Some(s);
        }
        let reader = self
            .raw_subscriber
            .as_ref()
            .expect("created above")
            .create_simple_datareader_no_key(&t, Some(qos))
            .map_err(|e| create_error(format!("raw reader on '{resolved}' ({ros_type})"), e))?;
        Ok(RawSubscription {
            reader,
            topic: resolved,
            ros_type: ros_type.to_string(),
        })
    }

    /// ROS topics known from DDS discovery (remote participants' endpoints), sorted by name.
    pub fn discovered_topics(&self) -> Vec<TopicInfo> {
        let raw = self.parts.context.discovered_topics();
        ros_topics_from_dds(raw.iter().map(|t| (t.name.as_str(), t.type_name.as_str())))
    }

    /// ROS topics that have at least one publisher (discovered DDS writers), with the type the
    /// publishers declare. Prefer this to [`Self::discovered_topics`] when the type matters:
    /// readers can declare other types on the same topic (ros2-client's own spinner reads
    /// `/clock` as `builtin_interfaces/msg/Time`, while `/clock` publishers send
    /// `rosgraph_msgs/msg/Clock`).
    pub fn discovered_publications(&self) -> Vec<TopicInfo> {
        let writers = self.parts.context.domain_participant().discovered_writers();
        ros_topics_from_dds(writers.iter().map(|w| {
            (
                w.publication_topic_data.topic_name.as_str(),
                w.publication_topic_data.type_name.as_str(),
            )
        }))
    }

    /// Wait for discovery to settle, then list topics: polls until the list has not changed for
    /// `quiet` (or `max_wait` passes). For `metrocell topic list` and friends.
    pub fn discovered_topics_settled(
        &self,
        quiet: std::time::Duration,
        max_wait: std::time::Duration,
    ) -> Vec<TopicInfo> {
        let start = std::time::Instant::now();
        let mut last = self.discovered_topics();
        let mut last_change = std::time::Instant::now();
        while start.elapsed() < max_wait && last_change.elapsed() < quiet {
            std::thread::sleep(std::time::Duration::from_millis(20));
            let now = self.discovered_topics();
            if now != last {
                last = now;
                last_change = std::time::Instant::now();
            }
        }
        last
    }

    /// Watches these input topics (resolved here) for silence longer than the node's
    /// `input_timeout` parameter ([`crate::diagnostics::input_timeout_param`]), if it declares
    /// one and it is not 0; returns the resolved names, for [`crate::Diagnostics::input_seen`].
    pub fn watch_inputs<'t>(
        &self,
        topics: impl IntoIterator<Item = &'t str>,
    ) -> Result<Vec<String>, NodeError> {
        let timeout = self
            .param::<f64>(crate::diagnostics::INPUT_TIMEOUT)
            .unwrap_or(0.0);
        let mut resolved = Vec::new();
        for topic in topics {
            let name = self.resolve_topic(topic)?;
            if timeout > 0.0 {
                self.diagnostics()
                    .watch_input(&name, std::time::Duration::from_secs_f64(timeout));
            }
            resolved.push(name);
        }
        Ok(resolved)
    }

    pub fn logger(&self) -> Logger {
        self.parts.logger.clone()
    }
    pub fn info(&self, message: impl AsRef<str>) {
        self.parts.logger.info(message)
    }
    pub fn warn(&self, message: impl AsRef<str>) {
        self.parts.logger.warn(message)
    }
    pub fn error(&self, message: impl AsRef<str>) {
        self.parts.logger.error(message)
    }

    /// Handle on the status the heartbeat publishes on `/diagnostics`.
    pub fn diagnostics(&self) -> Diagnostics {
        self.parts.diagnostics.clone()
    }

    /// Current ROS time: the latest `/clock` if `use_sim_time` is true (zero before the first
    /// message, as in rclcpp), otherwise the system clock.
    pub fn now(&self) -> ROSTime {
        if self.parts.use_sim_time {
            ROSTime::from_nanos(self.parts.sim_time.get().unwrap_or(0))
        } else {
            ROSTime::from_nanos(crate::logging::system_time_ns())
        }
    }

    pub fn use_sim_time(&self) -> bool {
        self.parts.use_sim_time
    }

    /// Token triggered by SIGINT/SIGTERM (or by the program).
    pub fn shutdown_token(&self) -> ShutdownToken {
        self.parts.shutdown.clone()
    }

    pub fn is_shutting_down(&self) -> bool {
        self.parts.shutdown.is_triggered()
    }

    /// Block until shutdown is requested.
    pub fn spin_until_shutdown(&self) {
        self.parts.shutdown.wait()
    }

    /// Resolves when shutdown is requested.
    pub async fn wait_for_shutdown(&self) {
        self.parts.shutdown.triggered().await
    }

    /// The underlying ros2-client node (services, actions, graph queries).
    pub fn ros_node(&mut self) -> &mut ros2_client::Node {
        &mut self.parts.ros_node
    }

    pub fn context(&self) -> &ros2_client::Context {
        &self.parts.context
    }

    /// Stop the background thread and leave the graph (the same as dropping the node).
    pub fn shutdown(self) {}
}

impl Drop for MetrocellNode {
    fn drop(&mut self) {
        self.parts.shutdown.trigger();
        self.parts.ros_node.stop_spinner();
        if let Some(mut b) = self.background.take() {
            b.stop();
        }
    }
}
