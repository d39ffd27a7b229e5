//! `metrocell topic echo TOPIC`

use std::time::Duration;

use super::QosChoice;

#[derive(clap::Args)]
#[command(
    after_help = "Examples:\n  metrocell topic echo /tracker/measurements --count 1\n  metrocell topic echo /temperature/x_scale --json | jq .temperature"
)]
pub struct EchoArgs {
    /// Topic name, e.g. /tracker/measurements
    topic: String,
    /// Message type (pkg/msg/Type); discovered from the publishers when omitted
    #[arg(long = "type")]
    type_name: Option<String>,
    /// Stop after this many messages
    #[arg(long)]
    count: Option<u64>,
    /// Print one JSON object per line instead of YAML documents
    #[arg(long)]
    json: bool,
    /// QoS of the reader
    #[arg(long, value_enum, default_value = "sensor-data")]
    qos: QosChoice,
    /// Seconds to wait for the topic to be discovered (when --type is not given)
    #[arg(long, default_value_t = 10.0)]
    discovery_timeout: f64,
}

pub fn run(args: EchoArgs) -> anyhow::Result<i32> {
    let mut node = super::cli_node("topic_echo")?;
    let type_name = match &args.type_name {
        Some(t) => super::known_type(t)?,
        None => super::known_type(&super::discover_type(
            &node,
            &args.topic,
            Duration::from_secs_f64(args.discovery_timeout),
        )?)?,
    };
    let sub = node.raw_subscription(&args.topic, &type_name, args.qos.profile())?;
    let registry = metrocell_msgs::registry();
    let token = node.shutdown_token();
    let mut printed = 0u64;
    while !token.is_triggered() && args.count.is_none_or(|n| printed < n) {
        let Some(msg) = sub.take()? else {
            token.wait_timeout(Duration::from_millis(5));
            continue;
        };
        match rosmsg::decode(registry, &type_name, &msg.payload) {
            Ok(value) => {
                if args.json {
                    println!("{}", rosmsg::to_json(&value));
                } else {
                    println!("{}---", rosmsg::to_yaml_string(&value));
                }
                printed += 1;
            }
            // A malformed message is reported and skipped; the next one may be fine.
            Err(e) => eprintln!(
                "metrocell topic echo: {}: message {} from {:?}: {e}",
                sub.topic(),
                msg.sequence_number,
                msg.publisher_gid
            ),
        }
    }
    Ok(0)
}
