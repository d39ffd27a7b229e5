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
        .reliability(Reliability::Reliable { when_full: WhenFull::DEFAULT })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

/// Latched (like `/robot_description` or `/tf_static`): reliable, transient local, keep last 1,
/// so a late subscriber still gets the current model. Subscribers must also use this profile.
pub fn latched() -> QosProfile {
    reliable().durability(Durability::TransientLocal).history(History::KeepLast { depth: 1 })
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
    profile.history(History::KeepLast { depth: STREAM_DEPTH })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_rclcpp() {
        let s = sensor_data();
        assert_eq!((s.reliability, s.durability, s.history), (Reliability::BestEffort, Durability::Volatile, History::KeepLast { depth: 5 }));
        let r = reliable();
        assert!(matches!(r.reliability, Reliability::Reliable { .. }));
        assert_eq!((r.durability, r.history), (Durability::Volatile, History::KeepLast { depth: 10 }));
        let l = latched();
        assert!(matches!(l.reliability, Reliability::Reliable { .. }));
        assert_eq!((l.durability, l.history), (Durability::TransientLocal, History::KeepLast { depth: 1 }));
    }

    #[test]
    fn a_stream_keeps_reliability_and_durability_and_deepens_the_queue() {
        let s = stream(sensor_data());
        assert_eq!((s.reliability, s.durability, s.history), (Reliability::BestEffort, Durability::Volatile, History::KeepLast { depth: STREAM_DEPTH }));
        let r = stream(reliable());
        assert!(matches!(r.reliability, Reliability::Reliable { .. }));
        assert_eq!(r.history, History::KeepLast { depth: STREAM_DEPTH });
    }
}
