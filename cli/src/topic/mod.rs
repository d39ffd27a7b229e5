//! `metrocell topic ...`: inspect and poke a running cell like `ros2 topic`, without a ROS install.
//!
//! Types are known at run time only, so messages travel as raw CDR payloads and are
//! decoded/encoded with the dynamic codec over the `.msg` registry of `metrocell-msgs`.

mod echo;
mod hz;
mod list;
mod publish;
mod qos_choice;

use std::time::Duration;

use metrocell_node::{MetrocellNode, NodeError};

pub use qos_choice::QosChoice;

#[derive(clap::Subcommand)]
pub enum TopicCommand {
    /// List the topics discovered on the DDS domain, with their types
    List(list::ListArgs),
    /// Print the messages published on a topic (YAML by default, JSON lines with --json)
    Echo(echo::EchoArgs),
    /// Publish a message given as YAML (or JSON) on a topic
    Pub(publish::PubArgs),
    /// Measure the publishing rate of a topic
    Hz(hz::HzArgs),
}

pub fn run(command: TopicCommand) -> i32 {
    let result = match command {
        TopicCommand::List(a) => list::run(a),
        TopicCommand::Echo(a) => echo::run(a),
        TopicCommand::Pub(a) => publish::run(a),
        TopicCommand::Hz(a) => hz::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("metrocell topic: {e:#}");
            2
        }
    }
}

/// A short-lived node for a CLI command: no heartbeat, no ROS arguments, stops on Ctrl-C.
fn cli_node(verb: &str) -> Result<MetrocellNode, NodeError> {
    MetrocellNode::builder(&format!("metrocell_{verb}_{}", std::process::id()))
        .diagnostics_period(None)
        .handle_signals(true)
        .build()
}

/// Looks a topic's type up in discovery, waiting up to `wait` for the topic to appear.
fn discover_type(node: &MetrocellNode, topic: &str, wait: Duration) -> anyhow::Result<String> {
    let topic = node.resolve_topic(topic)?;
    let deadline = std::time::Instant::now() + wait;
    let token = node.shutdown_token();
    loop {
        // The publishers' type is what arrives; a reader may declare another.
        let mut known = node
            .discovered_publications()
            .into_iter()
            .chain(node.discovered_topics());
        if let Some(t) = known.find(|t| t.name == topic) {
            return Ok(t.type_name);
        }
        if std::time::Instant::now() >= deadline || token.wait_timeout(Duration::from_millis(50)) {
            anyhow::bail!(
                "no publisher or subscriber of {topic} was discovered within {:.1} s; check the name with \
                 `metrocell topic list`, or give the type with --type pkg/msg/Type",
                wait.as_secs_f64()
            );
        }
    }
}

/// Accepts `pkg/msg/Type` or `pkg/Type` and checks metrocell knows it.
fn known_type(name: &str) -> anyhow::Result<String> {
    let registry = metrocell_msgs::registry();
    match registry.get(name) {
        Some(spec) => Ok(spec.type_name.ros_type()),
        None => {
            let known = metrocell_msgs::type_names();
            anyhow::bail!(
                "unknown message type '{name}'; metrocell knows {} types: {}",
                known.len(),
                known.join(", ")
            )
        }
    }
}
