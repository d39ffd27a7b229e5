//! The QoS of the recorder's reader of one topic: rosbag2's adaptation to the publishers'
//! offers, the configured queue depth, then the user's override for the topic, if any.

use metrocell_bagtools::qos_overrides::{HistoryOverride, QosOverride};
use metrocell_bagtools::recorded_qos::RecordingQos;
use ros2_client::qos::{Durability, History, QosProfile, Reliability, WhenFull};

pub fn reader_qos(adapted: RecordingQos, depth: usize, over: Option<&QosOverride>) -> QosProfile {
    let reliable = over.and_then(|o| o.reliable).unwrap_or(adapted.reliable);
    let transient_local = over
        .and_then(|o| o.transient_local)
        .unwrap_or(adapted.transient_local);
    let history = match over.and_then(|o| o.history) {
        Some(HistoryOverride::KeepAll) => History::KeepAll,
        Some(HistoryOverride::KeepLast(d)) => History::KeepLast { depth: d },
        None => History::KeepLast { depth },
    };
    QosProfile::subscription_default()
        .reliability(if reliable {
            Reliability::Reliable {
                when_full: WhenFull::DEFAULT,
            }
        } else {
            Reliability::BestEffort
        })
        .durability(if transient_local {
            Durability::TransientLocal
        } else {
            Durability::Volatile
        })
        .history(history)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn override_wins_over_adaptation_policy_by_policy() {
        let adapted = RecordingQos {
            reliable: true,
            transient_local: false,
        };
        let q = reader_qos(adapted, 1000, None);
        assert!(matches!(q.reliability, Reliability::Reliable { .. }));
        assert_eq!(
            (q.durability, q.history),
            (Durability::Volatile, History::KeepLast { depth: 1000 })
        );
        let o = QosOverride {
            reliable: Some(false),
            history: Some(HistoryOverride::KeepLast(7)),
            ..Default::default()
        };
        let q = reader_qos(adapted, 1000, Some(&o));
        assert_eq!(
            (q.reliability, q.durability, q.history),
            (
                Reliability::BestEffort,
                Durability::Volatile,
                History::KeepLast { depth: 7 }
            )
        );
        let o = QosOverride {
            transient_local: Some(true),
            history: Some(HistoryOverride::KeepAll),
            ..Default::default()
        };
        let q = reader_qos(adapted, 1000, Some(&o));
        assert!(matches!(q.reliability, Reliability::Reliable { .. }));
        assert_eq!(
            (q.durability, q.history),
            (Durability::TransientLocal, History::KeepAll)
        );
    }
}
