//! A node set up without DDS, for offline replay (`--bag FILE`): the same command line, names,
//! remaps and parameters as a live [`crate::MetrocellNode`], but no participant is opened, so
//! the node can read its inputs from a bag and write its outputs to a bag as fast as it can.

use crate::error::NodeError;
use crate::logging::Logger;
use crate::names::{fully_qualified_node_name, resolve_topic_name};
use crate::params::{ParamError, ParamKind, Parameters};
use crate::ros_args::RosArgs;
use crate::shutdown::ShutdownToken;

/// A replay stopped by SIGINT/SIGTERM before the end of its bag.
#[derive(Debug, thiserror::Error)]
#[error("interrupted before the message at log time {log_time_ns} ns; the output holds everything before it and is finished (readable)")]
pub struct Interrupted {
    pub log_time_ns: u64,
}

/// Name, namespace, remaps and start-up parameters of a node that runs on a bag.
pub struct OfflineNode {
    pub(crate) name: String,
    pub(crate) namespace: String,
    pub(crate) ros_args: RosArgs,
    pub(crate) parameters: Parameters,
    pub(crate) logger: Logger,
    pub(crate) shutdown: ShutdownToken,
}

impl OfflineNode {
    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn namespace(&self) -> &str {
        &self.namespace
    }

    pub fn fully_qualified_name(&self) -> String {
        fully_qualified_node_name(&self.namespace, &self.name)
    }

    /// Expand a topic name exactly as the live node would (namespace, `~`, remaps), so a bag
    /// recorded from the live cell is read under the names the node subscribes.
    pub fn resolve_topic(&self, topic: &str) -> Result<String, NodeError> {
        Ok(resolve_topic_name(
            topic,
            &self.namespace,
            &self.name,
            &self.ros_args.remaps,
        )?)
    }

    pub fn param<T: ParamKind>(&self, name: &str) -> Result<T, ParamError> {
        self.parameters.get(name)
    }

    pub fn parameters(&self) -> &Parameters {
        &self.parameters
    }

    /// Triggered by SIGINT/SIGTERM (when the builder handles signals, as it does by default):
    /// a replay checks it between messages, stops, and still finishes its output bag, so what
    /// it has written stays readable.
    pub fn shutdown_token(&self) -> &ShutdownToken {
        &self.shutdown
    }

    /// Whether SIGINT/SIGTERM has asked the node to stop (the `stop` of a bag replay).
    pub fn interrupted(&self) -> bool {
        self.shutdown.is_triggered()
    }

    /// The end of a replay that stopped before the message at `stopped` (None: it read the
    /// whole bag), as the node's result; call it after finishing the output.
    pub fn finish_replay(&self, stopped: Option<u64>) -> Result<(), Interrupted> {
        match stopped {
            Some(log_time_ns) => Err(Interrupted { log_time_ns }),
            None => Ok(()),
        }
    }

    /// Console logger (no rosout: there is no DDS).
    pub fn logger(&self) -> &Logger {
        &self.logger
    }
}

#[cfg(test)]
mod tests {
    use crate::MetrocellNode;

    /// Once shutdown is triggered, an offline node says so, and a replay that stopped names the
    /// log time of the message it stopped before. (SIGINT/SIGTERM trigger the same token, see
    /// `shutdown`; a real signal to a replaying node is tested end to end in nodes/probe: a
    /// second signal here would end the test process, as the shutdown module's own signal test
    /// already sends one.)
    #[test]
    fn a_triggered_shutdown_interrupts_an_offline_node() {
        let node = MetrocellNode::builder("offline_interrupt_test")
            .handle_signals(false)
            .build_offline()
            .unwrap();
        assert!(!node.interrupted());
        node.shutdown_token().trigger();
        assert!(node.interrupted());
        assert!(node.finish_replay(None).is_ok());
        let e = node.finish_replay(Some(42)).unwrap_err();
        assert_eq!(e.log_time_ns, 42);
        assert!(
            e.to_string().contains("42 ns") && e.to_string().contains("finished"),
            "{e}"
        );
    }
}
