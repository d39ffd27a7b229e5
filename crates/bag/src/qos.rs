//! The `offered_qos_profiles` YAML string that rosbag2 stores per topic (in the MCAP channel
//! metadata and in metadata.yaml).
//!
//! Format: a YAML sequence of QoS mappings with the rosbag2 metadata-version-8 encoding
//! (integer enums, durations as `{sec, nsec}`), which rosbag2 (Humble..Jazzy) and the Python
//! `rosbags` library both parse. Integer enum values are those of `rmw_qos_*_policy_t`:
//! history 1 = keep_last, 2 = keep_all; reliability 1 = reliable, 2 = best_effort;
//! durability 1 = transient_local, 2 = volatile; liveliness 1 = automatic, 3 = manual_by_topic;
//! 0 = system_default and 3 (liveliness 4) = unknown for each. rosbag2 records the QoS of
//! discovered publishers, where DDS does not tell the history: `history: 3` (unknown), `depth: 0`.
//! Version-9 bags written by `rosbags` use lower-case names (`keep_last`, `reliable`) instead
//! of integers; [`parse_offered_qos`] reads both.

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
        Self {
            keep_last: true,
            depth: 10,
            reliable: true,
            transient_local: false,
        }
    }
    /// ROS 2 sensor-data QoS: keep_last 5, best effort, volatile.
    pub const fn sensor_data() -> Self {
        Self {
            keep_last: true,
            depth: 5,
            reliable: false,
            transient_local: false,
        }
    }

    /// The full profile: these four policies, infinite durations, automatic liveliness.
    pub fn offered(self) -> OfferedQos {
        OfferedQos {
            history: if self.keep_last {
                HISTORY_KEEP_LAST
            } else {
                HISTORY_KEEP_ALL
            },
            depth: self.depth,
            reliability: if self.reliable {
                RELIABILITY_RELIABLE
            } else {
                RELIABILITY_BEST_EFFORT
            },
            durability: if self.transient_local {
                DURABILITY_TRANSIENT_LOCAL
            } else {
                DURABILITY_VOLATILE
            },
            ..OfferedQos::default()
        }
    }
}

/// Serialise a list of profiles into the `offered_qos_profiles` string.
pub fn qos_profiles_yaml(profiles: &[QosProfile]) -> String {
    offered_qos_yaml(&profiles.iter().map(|p| p.offered()).collect::<Vec<_>>())
}

pub const HISTORY_KEEP_LAST: u8 = 1;
pub const HISTORY_KEEP_ALL: u8 = 2;
pub const HISTORY_UNKNOWN: u8 = 3;
pub const RELIABILITY_RELIABLE: u8 = 1;
pub const RELIABILITY_BEST_EFFORT: u8 = 2;
pub const DURABILITY_TRANSIENT_LOCAL: u8 = 1;
pub const DURABILITY_VOLATILE: u8 = 2;
pub const LIVELINESS_AUTOMATIC: u8 = 1;
pub const LIVELINESS_MANUAL_BY_TOPIC: u8 = 3;

/// A duration as rmw stores it; [`RmwDuration::INFINITE`] is `RMW_DURATION_INFINITE`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RmwDuration {
    pub sec: u64,
    pub nsec: u64,
}

impl RmwDuration {
    pub const INFINITE: Self = Self {
        sec: DURATION_INFINITE_SEC,
        nsec: DURATION_INFINITE_NSEC,
    };
    pub fn from_nanos(ns: u64) -> Self {
        Self {
            sec: ns / 1_000_000_000,
            nsec: ns % 1_000_000_000,
        }
    }
}

/// One entry of `offered_qos_profiles`, every field rosbag2 writes, enums as rmw integers
/// (constants above).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OfferedQos {
    pub history: u8,
    pub depth: u32,
    pub reliability: u8,
    pub durability: u8,
    pub deadline: RmwDuration,
    pub lifespan: RmwDuration,
    pub liveliness: u8,
    pub liveliness_lease_duration: RmwDuration,
    pub avoid_ros_namespace_conventions: bool,
}

impl Default for OfferedQos {
    /// What rosbag2 stores for a discovered default publisher: history unknown, depth 0,
    /// reliable, volatile, automatic liveliness, infinite durations.
    fn default() -> Self {
        Self {
            history: HISTORY_UNKNOWN,
            depth: 0,
            reliability: RELIABILITY_RELIABLE,
            durability: DURABILITY_VOLATILE,
            deadline: RmwDuration::INFINITE,
            lifespan: RmwDuration::INFINITE,
            liveliness: LIVELINESS_AUTOMATIC,
            liveliness_lease_duration: RmwDuration::INFINITE,
            avoid_ros_namespace_conventions: false,
        }
    }
}

impl OfferedQos {
    /// YAML mapping (as a block-sequence item) in the version-8 encoding.
    fn to_yaml_item(self) -> String {
        let d = |d: RmwDuration| format!("\n    sec: {}\n    nsec: {}", d.sec, d.nsec);
        format!(
            "- history: {}\n  depth: {}\n  reliability: {}\n  durability: {}\n  deadline:{}\n  \
             lifespan:{}\n  liveliness: {}\n  liveliness_lease_duration:{}\n  \
             avoid_ros_namespace_conventions: {}\n",
            self.history,
            self.depth,
            self.reliability,
            self.durability,
            d(self.deadline),
            d(self.lifespan),
            self.liveliness,
            d(self.liveliness_lease_duration),
            self.avoid_ros_namespace_conventions,
        )
    }
}

/// Serialise full profiles into the `offered_qos_profiles` string (rosbag2's block layout).
pub fn offered_qos_yaml(profiles: &[OfferedQos]) -> String {
    let s: String = profiles.iter().map(|p| p.to_yaml_item()).collect();
    s.trim_end().to_string()
}

/// Parse an `offered_qos_profiles` string (integers as rosbag2 writes, or the lower-case names
/// of rosbags' version 9). Empty text → no profiles. Missing or unrecognised entries take the
/// [`OfferedQos::default`] value, as rosbags does.
pub fn parse_offered_qos(topic: &str, yaml: &str) -> Result<Vec<OfferedQos>> {
    if yaml.trim().is_empty() {
        return Ok(Vec::new());
    }
    let bad = |why: String| {
        BagError::InvalidArgument(format!("offered_qos_profiles of topic {topic}: {why}"))
    };
    let value: serde_yaml::Value =
        serde_yaml::from_str(yaml).map_err(|e| bad(format!("not YAML: {e}")))?;
    let serde_yaml::Value::Sequence(items) = value else {
        return Err(bad("not a YAML sequence".into()));
    };
    let policy = |item: &serde_yaml::Value, key: &str, names: &[(&str, u8)], default: u8| -> u8 {
        match &item[key] {
            serde_yaml::Value::Number(n) => n.as_u64().map_or(default, |v| v as u8),
            serde_yaml::Value::String(s) => names
                .iter()
                .find(|(n, _)| n.eq_ignore_ascii_case(s))
                .map_or(default, |(_, v)| *v),
            _ => default,
        }
    };
    let duration = |item: &serde_yaml::Value, key: &str| -> RmwDuration {
        let v = &item[key];
        match (v["sec"].as_u64(), v["nsec"].as_u64()) {
            (Some(sec), Some(nsec)) => RmwDuration { sec, nsec },
            _ => RmwDuration::INFINITE,
        }
    };
    let mut out = Vec::new();
    for item in &items {
        if !item.is_mapping() {
            return Err(bad("an entry is not a mapping".into()));
        }
        let d = OfferedQos::default();
        out.push(OfferedQos {
            history: policy(
                item,
                "history",
                &[
                    ("system_default", 0),
                    ("keep_last", 1),
                    ("keep_all", 2),
                    ("unknown", 3),
                ],
                d.history,
            ),
            depth: item["depth"].as_u64().map_or(d.depth, |v| v as u32),
            reliability: policy(
                item,
                "reliability",
                &[
                    ("system_default", 0),
                    ("reliable", 1),
                    ("best_effort", 2),
                    ("unknown", 3),
                    ("best_available", 4),
                ],
                d.reliability,
            ),
            durability: policy(
                item,
                "durability",
                &[
                    ("system_default", 0),
                    ("transient_local", 1),
                    ("volatile", 2),
                    ("unknown", 3),
                    ("best_available", 4),
                ],
                d.durability,
            ),
            deadline: duration(item, "deadline"),
            lifespan: duration(item, "lifespan"),
            liveliness: policy(
                item,
                "liveliness",
                &[
                    ("system_default", 0),
                    ("automatic", 1),
                    ("manual_by_node", 2),
                    ("manual_by_topic", 3),
                    ("unknown", 4),
                    ("best_available", 5),
                ],
                d.liveliness,
            ),
            liveliness_lease_duration: duration(item, "liveliness_lease_duration"),
            avoid_ros_namespace_conventions: item["avoid_ros_namespace_conventions"]
                .as_bool()
                .unwrap_or(false),
        });
    }
    Ok(out)
}

/// Check that a caller-supplied `offered_qos_profiles` string is empty or a YAML sequence of
/// mappings (what rosbag2 and rosbags expect): it must parse as [`parse_offered_qos`] reads it.
pub fn validate_qos_yaml(topic: &str, yaml: &str) -> Result<()> {
    parse_offered_qos(topic, yaml).map(|_| ())
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
        assert_eq!(
            item["deadline"]["nsec"].as_u64(),
            Some(DURATION_INFINITE_NSEC)
        );
    }

    #[test]
    fn offered_qos_round_trips_and_reads_rosbags_names() {
        let p = OfferedQos {
            durability: DURABILITY_TRANSIENT_LOCAL,
            deadline: RmwDuration::from_nanos(1_500_000_000),
            ..OfferedQos::default()
        };
        let q = OfferedQos {
            reliability: RELIABILITY_BEST_EFFORT,
            history: HISTORY_KEEP_LAST,
            depth: 5,
            ..OfferedQos::default()
        };
        let y = offered_qos_yaml(&[p, q]);
        assert!(y.starts_with("- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 1\n    nsec: 500000000"), "{y}");
        assert_eq!(parse_offered_qos("/t", &y).unwrap(), vec![p, q]);
        let v9 = "- history: keep_last\n  depth: 1\n  reliability: best_effort\n  durability: transient_local\n  \
                  deadline: {sec: 0, nsec: 0}\n  liveliness: automatic";
        let got = parse_offered_qos("/t", v9).unwrap();
        assert_eq!(
            (
                got[0].history,
                got[0].depth,
                got[0].reliability,
                got[0].durability
            ),
            (1, 1, 2, 1)
        );
        assert_eq!(
            (got[0].deadline, got[0].lifespan),
            (RmwDuration { sec: 0, nsec: 0 }, RmwDuration::INFINITE)
        );
        assert!(parse_offered_qos("/t", "").unwrap().is_empty());
        assert!(parse_offered_qos("/t", "{a: 1}")
            .unwrap_err()
            .to_string()
            .contains("/t"));
    }

    #[test]
    fn scalar_qos_is_rejected() {
        assert!(validate_qos_yaml("/t", "just text").is_err());
        assert!(validate_qos_yaml("/t", "").is_ok());
    }
}
