//! The node on a bag (`--bag FILE`): no DDS. Inputs are read in log-time order and each is
//! processed at its log time, which is also the node's clock (staleness, model period), so the
//! numbers equal those of the live node fed by `metrocell bag play`. Outputs are stamped with
//! the log time of the input that caused them.

use std::io::Write;
use std::path::PathBuf;

use metrocell_bagtools::{BagSink, BagSource};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_node::OfflineNode;
use rosmsg::RosMessage;

use crate::parameters;
use crate::thermal_state::ThermalState;

/// `--bag FILE [--output OUT_BAG]`, the node's own (non-ROS) arguments.
pub struct ReplayArgs {
    pub bag: PathBuf,
    pub output: Option<PathBuf>,
}

impl ReplayArgs {
    /// `None` when `--bag` is absent (live run).
    pub fn parse(args: &[String]) -> Result<Option<ReplayArgs>, String> {
        let (mut bag, mut output) = (None, None);
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut value = |flag: &str| it.next().map(PathBuf::from).ok_or_else(|| format!("{flag} needs a path"));
            match a.as_str() {
                "--bag" => bag = Some(value("--bag")?),
                "--output" => output = Some(value("--output")?),
                other => return Err(format!("unknown argument '{other}' (expected --bag FILE [--output OUT_BAG] before --ros-args)")),
            }
        }
        match (bag, output) {
            (Some(bag), output) => Ok(Some(ReplayArgs { bag, output })),
            (None, Some(_)) => Err("--output needs --bag".into()),
            (None, None) => Ok(None),
        }
    }
}

/// Where replay outputs go.
enum Output {
    Bag(BagSink),
    JsonLines(std::io::StdoutLock<'static>),
}

impl Output {
    fn write<T: RosMessage>(&mut self, topic: &str, m: &T, time_ns: u64) -> Result<(), Box<dyn std::error::Error>> {
        match self {
            Output::Bag(sink) => sink.write(topic, m, time_ns)?,
            Output::JsonLines(out) => {
                let line = serde_json::json!({ "topic": topic, "time_ns": time_ns, "message": m });
                writeln!(out, "{line}")?;
            }
        }
        Ok(())
    }
}

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let compensator = parameters::compensator(node.parameters())?;
    node.logger().info(parameters::describe(&compensator));
    let mut state = ThermalState::new(compensator, node.param::<f64>("publish_period")?, node.param::<f64>("stale_after")?);

    let mut source = BagSource::open(&args.bag)?;
    let mut sensor_of_topic = Vec::new();
    for s in state.compensator.sensors() {
        let topic = node.resolve_topic(&format!("temperature/{}", s.name))?;
        source.subscribe::<Temperature>(&topic)?;
        sensor_of_topic.push((topic, s.name.clone()));
    }
    let points_topic = node.resolve_topic("measured_points")?;
    source.subscribe::<MeasuredPoint>(&points_topic)?;
    let compensated_topic = node.resolve_topic("measured_points/thermal_compensated")?;
    let model_topic = node.resolve_topic("thermal/error_model")?;

    let mut output = match &args.output {
        Some(dir) => {
            let mut sink = BagSink::create(dir, Default::default())?;
            sink.advertise::<MeasuredPoint>(&compensated_topic)?;
            sink.advertise::<ErrorModel>(&model_topic)?;
            Output::Bag(sink)
        }
        None => Output::JsonLines(std::io::stdout().lock()),
    };

    let (mut inputs, mut compensated, mut not_compensated) = (0u64, 0u64, 0u64);
    for m in source.messages()? {
        let m = m?;
        inputs += 1;
        let now = m.log_time_ns as i64;
        if m.topic == points_topic {
            match state.compensate(&m.decode::<MeasuredPoint>()?, now) {
                Ok(out) => {
                    output.write(&compensated_topic, &out, m.log_time_ns)?;
                    compensated += 1;
                }
                Err(e) => {
                    node.logger().warn(format!("{} at log time {} ns: {e}", m.topic, m.log_time_ns));
                    not_compensated += 1;
                }
            }
        } else if let Some((_, sensor)) = sensor_of_topic.iter().find(|(t, _)| *t == m.topic) {
            if let Err(e) = state.temperature(sensor, &m.decode::<Temperature>()?, now) {
                node.logger().warn(e);
            }
        }
        match state.model_if_due(now) {
            Some(Ok(model)) => output.write(&model_topic, &model, m.log_time_ns)?,
            Some(Err(e)) => node.logger().debug(format!("error model at {now} ns: {e}")),
            None => {}
        }
    }
    if let Output::Bag(sink) = output {
        sink.finish()?;
    }
    node.logger().info(format!(
        "replayed {inputs} messages from {}: {compensated} points compensated, {not_compensated} not",
        args.bag.display()
    ));
    Ok(())
}
