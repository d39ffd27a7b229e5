//! QoS presets matching rclcpp's named profiles (rmw_qos_profile_*), as ros2-client profiles.

use ros2_client::qos::{Durability, History, QosProfile, Reliability, WhenFull};

/// `rclcpp::SensorDataQoS`: best effort, keep last 5, volatile. For camera frames and other
/// streams where the newest sample matters more than every sample.
pub fn sensor_data() -> QosProfile {
    QosProfile::subscription_default()
        .reliability(Reliability::BestEffort)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 5 })
}

/// rclcpp's default (`rmw_qos_profile_default`): reliable, keep last 10, volatile.
/// For measurements, diagnostics and anything a recorder must not miss.
pub fn reliable() -> QosProfile {
    QosProfile::subscription_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::DEFAULT,
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

/// Latched (like `/robot_description` or `/tf_static`): reliable, transient local, keep last 1,
/// so a late subscriber still gets the current model. Subscribers must also use this profile.
pub fn latched() -> QosProfile {
    reliable()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

/// Queue depth of [`stream`]: ten seconds of a 100 Hz stream, one second of a 1 kHz tracker.
pub const STREAM_DEPTH: usize = 1000;

/// `profile` with a keep-last queue of [`STREAM_DEPTH`] samples, for a node's inputs whose every
/// sample counts (tracker readings, commanded joint states, measured points, temperatures). With
/// the presets' 5 or 10, a node that stalls for a few milliseconds while a burst arrives (a twin
/// or a bag replayed faster than real time, a tracker publishing the points it held back until
/// registration) loses the oldest samples in its own reader queue — a dwell without a nominal,
/// a point never compensated. Reliability and durability stay as given, so a best-effort reader
/// still matches every publisher.
pub fn stream(profile: QosProfile) -> QosProfile {
    profile.history(History::KeepLast {
        depth: STREAM_DEPTH,
    })
}

/// The DDS QoS of an endpoint that holds no more than the profile's keep-last depth of samples:
/// the depth is also stated as its `ResourceLimits.max_samples`, which RustDDS (0.15) otherwise
/// fills in itself. A writer: RustDDS keeps a reliable writer's samples until every matched reader
/// has acknowledged them, best-effort readers included, which never acknowledge; so with one of
/// those matched (any SensorDataQoS subscriber: the fiducial node and the dashboard on the twin's
/// frames) it evicts nothing before `max_samples`, by default 8192 — 2.5 GB of 640 × 480 frames.
/// With the bound, a reliable reader that falls more than `depth` samples behind loses the
/// oldest, as DDS's keep-last means (it counts a sequence gap). Ordinary writers keep RustDDS's
/// default, which lets a lagging reliable reader (the recorder on a busy machine) still be
/// repaired from up to 8192 samples back. A reader (and its topic): RustDDS's topic cache keeps
/// max(`max_samples`, depth) samples, with `max_samples` 64 when unstated — 64 frames for a
/// reader that wanted 5.
pub fn bounded_qos(qos: &QosProfile) -> rustdds::QosPolicies {
    let dds = rustdds::QosPolicies::from(qos);
    match qos.history {
        History::KeepLast { depth } => {
            let depth = i32::try_from(depth).unwrap_or(i32::MAX);
            let limits = rustdds::policy::ResourceLimits {
                max_samples: depth,
                max_instances: 1,
                max_samples_per_instance: depth,
            };
            rustdds::QosPolicyBuilder::new()
                .resource_limits(limits)
                .build()
                .modify_by(&dds)
        }
        History::KeepAll => dds,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_rclcpp() {
        let s = sensor_data();
        assert_eq!(
            (s.reliability, s.durability, s.history),
            (
                Reliability::BestEffort,
                Durability::Volatile,
                History::KeepLast { depth: 5 }
            )
        );
        let r = reliable();
        assert!(matches!(r.reliability, Reliability::Reliable { .. }));
        assert_eq!(
            (r.durability, r.history),
            (Durability::Volatile, History::KeepLast { depth: 10 })
        );
        let l = latched();
        assert!(matches!(l.reliability, Reliability::Reliable { .. }));
        assert_eq!(
            (l.durability, l.history),
            (Durability::TransientLocal, History::KeepLast { depth: 1 })
        );
    }

    #[test]
    fn a_stream_keeps_reliability_and_durability_and_deepens_the_queue() {
        let s = stream(sensor_data());
        assert_eq!(
            (s.reliability, s.durability, s.history),
            (
                Reliability::BestEffort,
                Durability::Volatile,
                History::KeepLast {
                    depth: STREAM_DEPTH
                }
            )
        );
        let r = stream(reliable());
        assert!(matches!(r.reliability, Reliability::Reliable { .. }));
        assert_eq!(
            r.history,
            History::KeepLast {
                depth: STREAM_DEPTH
            }
        );
    }

    #[test]
    fn a_bounded_endpoint_states_its_depth_as_its_resource_limit_and_keeps_the_rest() {
        let q = bounded_qos(&reliable().history(History::KeepLast { depth: 109 }));
        assert_eq!(q.resource_limits().map(|r| r.max_samples), Some(109));
        assert_eq!(
            q.history(),
            Some(rustdds::policy::History::KeepLast { depth: 109 })
        );
        assert!(matches!(
            q.reliability(),
            Some(rustdds::policy::Reliability::Reliable { .. })
        ));
        assert_eq!(q.durability(), Some(rustdds::policy::Durability::Volatile));
        // keep-all has no depth to bound by: RustDDS's own backstop stays
        assert_eq!(
            bounded_qos(&reliable().history(History::KeepAll)).resource_limits(),
            None
        );
    }
}
