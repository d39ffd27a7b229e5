//! Which DDS participant hosts which ROS 2 node, from ROS 2's own `ros_discovery_info` topic
//! (`rmw_dds_common/msg/ParticipantEntitiesInfo`: every rmw and ros2-client publish, latched,
//! the node names each participant holds). DDS discovery alone names only participants and
//! endpoints; this is how a node is found by its name (`ros2 node list` reads the same topic).
//!
//! Identity convention: a participant is its 12-byte GUID prefix, the first 12 bytes of its
//! GID and of every endpoint GUID it owns, so an endpoint found by DDS discovery
//! (`discovered_readers`) is tied to its node by [`guid_prefix`].

use std::collections::BTreeMap;

use ros2_client::entities_info::ParticipantEntitiesInfo;
use rustdds::no_key::SimpleDataReader;
use rustdds::policy::{Durability, History, Reliability};
use rustdds::{CDRDeserializerAdapter, QosPolicyBuilder, TopicKind, GUID};

use crate::error::{create_error as fail, NodeError};

/// DDS topic and type of ROS 2's node ↔ participant map (not under `rt/`: it is no ROS topic).
const TOPIC: &str = "ros_discovery_info";
const TYPE: &str = "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_";

/// The 12-byte GUID prefix that names a participant.
pub type ParticipantPrefix = [u8; 12];

/// The participant part of an entity's GUID.
pub fn guid_prefix(guid: GUID) -> ParticipantPrefix {
    let bytes = guid.to_bytes();
    let mut prefix = [0u8; 12];
    prefix.copy_from_slice(&bytes[..12]);
    prefix
}

/// Node names per participant, kept current by [`NodeDirectory::refresh`].
pub struct NodeDirectory {
    reader:
        SimpleDataReader<ParticipantEntitiesInfo, CDRDeserializerAdapter<ParticipantEntitiesInfo>>,
    /// Participant → fully qualified names of its nodes (its latest announcement).
    nodes: BTreeMap<ParticipantPrefix, Vec<String>>,
}

impl NodeDirectory {
    /// Subscribe to `ros_discovery_info` on `participant` (transient-local: participants that
    /// announced before this call are known after the first refresh that sees their sample).
    pub fn new(participant: &rustdds::DomainParticipant) -> Result<NodeDirectory, NodeError> {
        let qos = QosPolicyBuilder::new()
            .durability(Durability::TransientLocal)
            .reliability(Reliability::Reliable {
                max_blocking_time: rustdds::Duration::ZERO,
            })
            .history(History::KeepLast { depth: 1 })
            .build();
        let topic = participant
            .create_topic(TOPIC.to_string(), TYPE.to_string(), &qos, TopicKind::NoKey)
            .map_err(|e| fail("topic ros_discovery_info", e))?;
        let subscriber = participant
            .create_subscriber(&qos)
            .map_err(|e| fail("ros_discovery_info subscriber", e))?;
        let reader = subscriber
            .create_simple_datareader_no_key(&topic, Some(qos))
            .map_err(|e| fail("ros_discovery_info reader", e))?;
        Ok(NodeDirectory {
            reader,
            nodes: BTreeMap::new(),
        })
    }

    /// Take every announcement waiting (a participant's latest replaces its previous one).
    pub fn refresh(&mut self) {
        self.reader.drain_read_notifications();
        while let Ok(Some(change)) = self.reader.try_take_one() {
            let info = change.into_value();
            let prefix = guid_prefix(GUID::from(info.gid()));
            self.nodes.insert(
                prefix,
                info.nodes()
                    .iter()
                    .map(|n| n.fully_qualified_name())
                    .collect(),
            );
        }
    }

    /// Participants holding a node called `name`: a fully qualified name (`/ns/recorder`) must
    /// match exactly, a bare name (`recorder`) matches in any namespace.
    pub fn participants_of(&self, name: &str) -> Vec<ParticipantPrefix> {
        self.nodes
            .iter()
            .filter(|(_, names)| names.iter().any(|fqn| node_name_matches(fqn, name)))
            .map(|(prefix, _)| *prefix)
            .collect()
    }

    /// Every known node, fully qualified, sorted (for messages that list what was found).
    pub fn node_names(&self) -> Vec<String> {
        let mut all: Vec<String> = self.nodes.values().flatten().cloned().collect();
        all.sort();
        all
    }
}

/// `wanted` is a fully qualified name (leading `/`) compared whole, or a bare node name compared
/// with the last path segment of `fqn`.
fn node_name_matches(fqn: &str, wanted: &str) -> bool {
    if wanted.starts_with('/') {
        fqn == wanted
    } else {
        fqn.rsplit('/').next() == Some(wanted)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bare_names_match_in_any_namespace_and_qualified_names_exactly() {
        assert!(node_name_matches("/recorder", "recorder"));
        assert!(node_name_matches("/cell1/recorder", "recorder"));
        assert!(!node_name_matches("/cell1/recorder2", "recorder"));
        assert!(!node_name_matches("/dashboard", "recorder"));
        assert!(node_name_matches("/cell1/recorder", "/cell1/recorder"));
        assert!(!node_name_matches("/cell2/recorder", "/cell1/recorder"));
    }

    #[test]
    fn the_prefix_is_the_first_twelve_bytes_of_the_guid() {
        let bytes: [u8; 16] = std::array::from_fn(|i| i as u8 + 1);
        assert_eq!(
            guid_prefix(GUID::from_bytes(bytes)),
            [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]
        );
    }
}
