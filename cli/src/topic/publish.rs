//! `metrocell topic pub TOPIC TYPE VALUES`

use std::time::{Duration, Instant};

use super::QosChoice;

#[derive(clap::Args)]
#[command(
    after_help = "VALUES is YAML (JSON is YAML too); missing fields take their .msg defaults.\n\n\
Examples:\n  metrocell topic pub /temperature/x sensor_msgs/msg/Temperature '{temperature: 21.5, variance: 0.0025}' --count 1\n  \
metrocell topic pub /cell/status std_msgs/msg/String '{data: running}' --rate 2"
)]
pub struct PubArgs {
    /// Topic name, e.g. /temperature/x
    topic: String,
    /// Message type, e.g. sensor_msgs/msg/Temperature
    type_name: String,
    /// The message as YAML, e.g. '{temperature: 21.5}'
    #[arg(default_value = "{}")]
    values: String,
    /// Publishing rate in Hz
    #[arg(short, long, default_value_t = 1.0)]
    rate: f64,
    /// Publish this many messages, then exit (default: until Ctrl-C)
    #[arg(short = 't', long = "times", alias = "count")]
    count: Option<u64>,
    /// Publish once and exit (same as --count 1)
    #[arg(short = '1', long)]
    once: bool,
    /// Wait until this many subscribers match before publishing (default 1 with --once/--count, else 0)
    #[arg(short = 'w', long)]
    wait_matching_subscriptions: Option<usize>,
    /// QoS of the writer
    #[arg(long, value_enum, default_value = "reliable")]
    qos: QosChoice,
    /// Seconds to wait for matching subscribers
    #[arg(long, default_value_t = 10.0)]
    wait_timeout: f64,
}

pub fn run(args: PubArgs) -> anyhow::Result<i32> {
    if !(args.rate.is_finite() && args.rate > 0.0) {
        anyhow::bail!("--rate must be a positive number of Hz, got {}", args.rate);
    }
    let type_name = super::known_type(&args.type_name)?;
    let registry = metrocell_msgs::registry();
    // Encode before touching DDS: a YAML mistake is reported without side effects.
    let value = rosmsg::from_yaml_str(registry, &type_name, &args.values)
        .map_err(|e| anyhow::anyhow!("the message does not fit {type_name}: {e}"))?;
    let payload = rosmsg::encode(registry, &type_name, &value)?;
    let count = if args.once { Some(1) } else { args.count };

    let mut node = super::cli_node("topic_pub")?;
    let publisher = node.raw_publisher(&args.topic, &type_name, args.qos.profile())?;
    let token = node.shutdown_token();
    let want = args
        .wait_matching_subscriptions
        .unwrap_or(if count.is_some() { 1 } else { 0 });
    let deadline = Instant::now() + Duration::from_secs_f64(args.wait_timeout);
    while publisher.matched_subscriptions() < want {
        if Instant::now() >= deadline {
            anyhow::bail!(
                "{} subscriber(s) of {} wanted, {} matched after {:.1} s (use -w 0 to publish anyway)",
                want,
                publisher.topic(),
                publisher.matched_subscriptions(),
                args.wait_timeout
            );
        }
        if token.wait_timeout(Duration::from_millis(20)) {
            return Ok(130);
        }
    }
    let period = Duration::from_secs_f64(1.0 / args.rate);
    let mut sent = 0u64;
    let mut next = Instant::now();
    while count.is_none_or(|n| sent < n) {
        publisher.publish(&payload)?;
        sent += 1;
        eprintln!("publishing #{sent}: {}", rosmsg::to_json(&value));
        next += period;
        if count.is_some_and(|n| sent >= n) {
            break;
        }
        if token.wait_timeout(next.saturating_duration_since(Instant::now())) {
            return Ok(0);
        }
    }
    // Give reliable delivery (acknowledgements, resends) a moment before the writer goes away.
    token.wait_timeout(Duration::from_millis(500));
    Ok(0)
}
