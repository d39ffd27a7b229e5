//! A node set up without DDS, for offline replay (`--bag FILE`): the same command line, names,
//! remaps and parameters as a live [`crate::MetrocellNode`], but no participant is opened, so
//! the node can read its inputs from a bag and write its outputs to a bag as fast as it can.

use crate::error::NodeError;
use crate::logging::Logger;
use crate::names::{fully_qualified_node_name, resolve_topic_name};
use crate::params::{ParamError, ParamKind, Parameters};
use crate::ros_args::RosArgs;

/// Name, namespace, remaps and start-up parameters of a node that runs on a bag.
pub struct OfflineNode {
    pub(crate) name: String,
    pub(crate) namespace: String,
    pub(crate) ros_args: RosArgs,
    pub(crate) parameters: Parameters,
    pub(crate) logger: Logger,
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
        Ok(resolve_topic_name(topic, &self.namespace, &self.name, &self.ros_args.remaps)?)
    }

    pub fn param<T: ParamKind>(&self, name: &str) -> Result<T, ParamError> {
        self.parameters.get(name)
    }

    pub fn parameters(&self) -> &Parameters {
        &self.parameters
    }

    /// Console logger (no rosout: there is no DDS).
    pub fn logger(&self) -> &Logger {
        &self.logger
    }
}
