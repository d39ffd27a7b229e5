//! QoS of a recorded topic, both ways: what the recorder stores in `offered_qos_profiles`
//! (from the QoS that discovered publishers announce) and what `bag play` offers on replay
//! (adapted from the stored profiles, as `ros2 bag play` does).
//!
//! Recording follows rosbag2: one profile per discovered publisher of the topic, with the
//! policies DDS discovery carries (reliability, durability, deadline, lifespan, liveliness and
//! its lease). Discovery does not carry the history, so it is stored as unknown (3), depth 0,
//! exactly what rosbag2 writes. A policy a publisher does not announce takes the DDS default of
//! a writer (reliable, volatile, automatic liveliness, infinite durations).
//!
//! Replay follows rosbag2's `adapt_offer_to_recorded_offers`: when every recorded profile of the
//! topic agrees on reliability and durability, those are offered; otherwise (or with no
//! profiles) the default publisher QoS (reliable, volatile). History is keep-last 10 as in
//! rosbag2, so a late transient-local subscriber gets up to the last 10 replayed messages.

use metrocell_bag::{
    OfferedQos, RmwDuration, DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE, LIVELINESS_AUTOMATIC,
    LIVELINESS_MANUAL_BY_TOPIC, RELIABILITY_BEST_EFFORT, RELIABILITY_RELIABLE,
};
use rustdds::discovery::PublicationBuiltinTopicData;
use rustdds::policy::{Durability, Liveliness, Reliability};

fn rmw_duration(d: rustdds::Duration) -> RmwDuration {
    if d == rustdds::Duration::INFINITE {
        RmwDuration::INFINITE
    } else {
        RmwDuration::from_nanos(d.to_nanoseconds().max(0) as u64)
    }
}

/// The offered QoS a discovered publisher announces, as rosbag2 stores it.
pub fn offered_qos_from_dds(p: &PublicationBuiltinTopicData) -> OfferedQos {
    let mut q = OfferedQos {
        reliability: match p.reliability {
            Some(Reliability::BestEffort) => RELIABILITY_BEST_EFFORT,
            _ => RELIABILITY_RELIABLE,
        },
        ..OfferedQos::default()
    };
    q.durability = match p.durability {
        // transient and persistent also deliver history to late joiners; rmw has no such kinds.
        Some(Durability::TransientLocal | Durability::Transient | Durability::Persistent) => {
            DURABILITY_TRANSIENT_LOCAL
        }
        _ => DURABILITY_VOLATILE,
    };
    if let Some(d) = p.deadline {
        q.deadline = rmw_duration(d.0);
    }
    if let Some(l) = p.lifespan {
        q.lifespan = rmw_duration(l.duration);
    }
    if let Some(l) = p.liveliness {
        let (kind, lease) = match l {
            Liveliness::Automatic { lease_duration } => (LIVELINESS_AUTOMATIC, lease_duration),
            // rmw dropped manual_by_node; DDS manual-by-participant maps to automatic in rmw.
            Liveliness::ManualByParticipant { lease_duration } => {
                (LIVELINESS_AUTOMATIC, lease_duration)
            }
            Liveliness::ManualByTopic { lease_duration } => {
                (LIVELINESS_MANUAL_BY_TOPIC, lease_duration)
            }
        };
        q.liveliness = kind;
        q.liveliness_lease_duration = rmw_duration(lease);
    }
    q
}

/// The offered QoS of every discovered publisher of DDS topic `dds_topic` (the ROS name mapped
/// by `metrocell_node::names::dds_topic_name`, e.g. `rt/scan`).
pub fn offered_qos_of_topic<'a>(
    publications: impl IntoIterator<Item = &'a PublicationBuiltinTopicData>,
    dds_topic: &str,
) -> Vec<OfferedQos> {
    publications
        .into_iter()
        .filter(|p| p.topic_name == dds_topic)
        .map(offered_qos_from_dds)
        .collect()
}

/// What the recorder's reader of a topic requests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordingQos {
    pub reliable: bool,
    pub transient_local: bool,
}

/// rosbag2's `adapt_request_to_offers`: reliable when every publisher offers reliable (so the
/// recorder gets retransmissions and loses nothing on the wire), else best effort (which matches
/// every publisher); transient-local when every publisher offers it (so latched samples sent
/// before the recorder came are recorded), else volatile. No publisher: reliable, volatile.
pub fn recording_qos(offers: &[OfferedQos]) -> RecordingQos {
    RecordingQos {
        reliable: offers
            .iter()
            .all(|q| q.reliability != RELIABILITY_BEST_EFFORT),
        transient_local: !offers.is_empty()
            && offers
                .iter()
                .all(|q| q.durability == DURABILITY_TRANSIENT_LOCAL),
    }
}

/// What a replay publisher offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplayQos {
    pub reliable: bool,
    pub transient_local: bool,
}

/// rosbag2's adaptation of the recorded offers (see the module doc).
pub fn replay_qos(recorded: &[OfferedQos]) -> ReplayQos {
    let default = ReplayQos {
        reliable: true,
        transient_local: false,
    };
    let Some(first) = recorded.first() else {
        return default;
    };
    let agree = recorded
        .iter()
        .all(|q| q.reliability == first.reliability && q.durability == first.durability);
    if !agree {
        return default;
    }
    ReplayQos {
        reliable: first.reliability != RELIABILITY_BEST_EFFORT,
        transient_local: first.durability == DURABILITY_TRANSIENT_LOCAL,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustdds::policy::{Deadline, Lifespan};

    fn publication(topic: &str) -> PublicationBuiltinTopicData {
        PublicationBuiltinTopicData::new(
            rustdds::GUID::GUID_UNKNOWN,
            None,
            topic.into(),
            "x::msg::dds_::Y_".into(),
            None,
        )
    }

    #[test]
    fn dds_policies_map_to_rmw_values_and_absent_ones_to_writer_defaults() {
        let mut latched = publication("rt/robot_description");
        latched.durability = Some(Durability::TransientLocal);
        latched.deadline = Some(Deadline(rustdds::Duration::from_millis(250)));
        latched.lifespan = Some(Lifespan {
            duration: rustdds::Duration::INFINITE,
        });
        let mut sensor = publication("rt/scan");
        sensor.reliability = Some(Reliability::BestEffort);
        sensor.liveliness = Some(Liveliness::ManualByTopic {
            lease_duration: rustdds::Duration::from_secs(2),
        });
        let all = [latched, sensor, publication("rt/other")];

        let l = offered_qos_of_topic(&all, "rt/robot_description");
        assert_eq!(l.len(), 1);
        assert_eq!(
            (l[0].reliability, l[0].durability),
            (RELIABILITY_RELIABLE, DURABILITY_TRANSIENT_LOCAL)
        );
        assert_eq!(
            l[0].deadline,
            RmwDuration {
                sec: 0,
                nsec: 250_000_000
            }
        );
        assert_eq!(
            (l[0].lifespan, l[0].history, l[0].depth),
            (RmwDuration::INFINITE, metrocell_bag::HISTORY_UNKNOWN, 0)
        );

        let s = offered_qos_of_topic(&all, "rt/scan");
        assert_eq!(
            (s[0].reliability, s[0].durability, s[0].liveliness),
            (
                RELIABILITY_BEST_EFFORT,
                DURABILITY_VOLATILE,
                LIVELINESS_MANUAL_BY_TOPIC
            )
        );
        assert_eq!(
            s[0].liveliness_lease_duration,
            RmwDuration { sec: 2, nsec: 0 }
        );
        assert!(offered_qos_of_topic(&all, "rt/absent").is_empty());
    }

    #[test]
    fn recorder_requests_what_every_publisher_offers() {
        let latched = OfferedQos {
            durability: DURABILITY_TRANSIENT_LOCAL,
            ..OfferedQos::default()
        };
        let best_effort = OfferedQos {
            reliability: RELIABILITY_BEST_EFFORT,
            ..OfferedQos::default()
        };
        let plain = OfferedQos::default();
        assert_eq!(
            recording_qos(&[plain, plain]),
            RecordingQos {
                reliable: true,
                transient_local: false
            }
        );
        assert_eq!(
            recording_qos(&[latched]),
            RecordingQos {
                reliable: true,
                transient_local: true
            }
        );
        assert_eq!(
            recording_qos(&[latched, plain]),
            RecordingQos {
                reliable: true,
                transient_local: false
            }
        );
        assert_eq!(
            recording_qos(&[plain, best_effort]),
            RecordingQos {
                reliable: false,
                transient_local: false
            },
            "one best-effort publisher"
        );
        assert_eq!(
            recording_qos(&[]),
            RecordingQos {
                reliable: true,
                transient_local: false
            }
        );
    }

    #[test]
    fn replay_uses_agreeing_offers_else_the_default() {
        let latched = OfferedQos {
            durability: DURABILITY_TRANSIENT_LOCAL,
            ..OfferedQos::default()
        };
        let best_effort = OfferedQos {
            reliability: RELIABILITY_BEST_EFFORT,
            ..OfferedQos::default()
        };
        assert_eq!(
            replay_qos(&[latched, latched]),
            ReplayQos {
                reliable: true,
                transient_local: true
            }
        );
        assert_eq!(
            replay_qos(&[best_effort]),
            ReplayQos {
                reliable: false,
                transient_local: false
            }
        );
        let default = ReplayQos {
            reliable: true,
            transient_local: false,
        };
        assert_eq!(
            replay_qos(&[latched, best_effort]),
            default,
            "disagreeing publishers"
        );
        assert_eq!(replay_qos(&[]), default);
    }
}
