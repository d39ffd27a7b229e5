//! How thin a metrocell node is: parse the ROS 2 command line, declare parameters, publish,
//! stop on Ctrl-C / SIGTERM.
//!
//!   tests/isolated cargo run -p metrocell-node --example talker -- \
//!       --ros-args -p rate_hz:=5 -r chatter:=/cell/chatter

use std::time::Duration;

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, MetrocellNode, ParamDecl};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("talker: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), metrocell_node::NodeError> {
    let (mut node, _own_args) = MetrocellNode::from_env_args(
        "talker",
        vec![
            ParamDecl::new("rate_hz", 2.0, "messages per second").with_range(0.1, 1000.0),
            ParamDecl::new("frame_id", "base", "frame written into each header"),
        ],
    )?;
    let publisher = node.publisher::<Header>("chatter", qos::reliable())?;
    // Declared above with these types, so reading them cannot fail.
    let period = Duration::from_secs_f64(1.0 / node.param::<f64>("rate_hz")?);
    let frame_id = node.param::<String>("frame_id")?;
    node.info(format!(
        "publishing on {} every {:?}",
        node.resolve_topic("chatter")?,
        period
    ));

    let diagnostics = node.diagnostics();
    while !node.shutdown_token().wait_timeout(period) {
        let now = node.now().to_nanos();
        let stamp = Time::from_nanos(now);
        match publisher.publish(Header {
            stamp,
            frame_id: frame_id.clone(),
        }) {
            Ok(()) => {
                diagnostics.add_count("messages_published", 1);
            }
            Err(e) => diagnostics.warn(format!("publish failed: {e:?}")),
        }
    }
    node.info("shutting down");
    Ok(())
}
