//! The `offered_qos_profiles` YAML string that rosbag2 stores per topic (in the MCAP channel
//! metadata and in metadata.yaml).
//!
//! Format: a YAML sequence of QoS mappings with the rosbag2 metadata-version-8 encoding
//! (integer enums, durations as `{sec, nsec}`), which rosbag2 (Humble..Jazzy) and the Python
//! `rosbags` library both parse. Integer enum values are those of `rmw_qos_*_policy_t`:
//! history 1 = keep_last, 2 = keep_all; reliability 1 = reliable, 2 = best_effort;
//! durability 1 = transient_local, 2 = volatile; liveliness 1 = automatic, 3 = manual_by_topic.

use crate::error::{BagError, Result};

/// "Infinite" duration as rmw writes it (`RMW_DURATION_INFINITE` split into sec/nsec).
pub const DURATION_INFINITE_SEC: u64 = 9_223_372_036;
pub const DURATION_INFINITE_NSEC: u64 = 854_775_807;

/// One offered QoS profile of a publisher.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QosProfile {
    /// true: keep_last(depth); false: keep_all.
    pub keep_last: bool,
    pub depth: u32,
    pub reliable: bool,
    pub transient_local: bool,
}

impl QosProfile {
    /// ROS 2 default publisher QoS: keep_last 10, reliable, volatile, automatic liveliness.
    pub const fn default_publisher() -> Self {
        Self { keep_last: true, depth: 10, reliable: true, transient_local: false }
    }
    /// ROS 2 sensor-data QoS: keep_last 5, best effort, volatile.
    pub const fn sensor_data() -> Self {
        Self { keep_last: true, depth: 5, reliable: false, transient_local: false }
    }

    /// YAML mapping (as a block-sequence item) in the version-8 encoding.
    fn to_yaml_item(self) -> String {
        let inf = format!("{{sec: {DURATION_INFINITE_SEC}, nsec: {DURATION_INFINITE_NSEC}}}");
        format!(
            "- history: {}\n  depth: {}\n  reliability: {}\n  durability: {}\n  deadline: {inf}\n  \
             lifespan: {inf}\n  liveliness: 1\n  liveliness_lease_duration: {inf}\n  \
             avoid_ros_namespace_conventions: false\n",
            if self.keep_last { 1 } else { 2 },
            self.depth,
            if self.reliable { 1 } else { 2 },
            if self.transient_local { 1 } else { 2 },
        )
    }
}

/// Serialise a list of profiles into the `offered_qos_profiles` string.
pub fn qos_profiles_yaml(profiles: &[QosProfile]) -> String {
    let s: String = profiles.iter().map(|p| p.to_yaml_item()).collect();
    s.trim_end().to_string()
}

/// Check that a caller-supplied `offered_qos_profiles` string is empty or a YAML sequence of
/// mappings (what rosbag2 and rosbags expect); returns it unchanged.
pub fn validate_qos_yaml(topic: &str, yaml: &str) -> Result<()> {
    if yaml.trim().is_empty() {
        return Ok(());
    }
    let value: serde_yaml::Value = serde_yaml::from_str(yaml).map_err(|e| {
        BagError::InvalidArgument(format!("offered_qos_profiles of topic {topic} is not YAML: {e}"))
    })?;
    match value {
        serde_yaml::Value::Sequence(items) if items.iter().all(|i| i.is_mapping()) => Ok(()),
        _ => Err(BagError::InvalidArgument(format!(
            "offered_qos_profiles of topic {topic} must be a YAML sequence of QoS mappings"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_profile_round_trips_through_yaml() {
        let y = qos_profiles_yaml(&[QosProfile::default_publisher()]);
        validate_qos_yaml("/t", &y).unwrap();
        let v: serde_yaml::Value = serde_yaml::from_str(&y).unwrap();
        let item = &v[0];
        assert_eq!(item["history"].as_u64(), Some(1));
        assert_eq!(item["depth"].as_u64(), Some(10));
        assert_eq!(item["reliability"].as_u64(), Some(1));
        assert_eq!(item["durability"].as_u64(), Some(2));
        assert_eq!(item["deadline"]["nsec"].as_u64(), Some(DURATION_INFINITE_NSEC));
    }

    #[test]
    fn scalar_qos_is_rejected() {
        assert!(validate_qos_yaml("/t", "just text").is_err());
        assert!(validate_qos_yaml("/t", "").is_ok());
    }
}
