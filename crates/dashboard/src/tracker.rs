//! Laser-tracker status from `tracker/measurements`: the newest status bits in words and how
//! often each condition occurred in the session (TrackerMeasurement STATUS_* bit set).

use metrocell_msgs::msg::TrackerMeasurement;
use serde::Serialize;

/// The flags the page shows, with their bit in `TrackerMeasurement::status`.
pub const FLAGS: [(&str, u8); 5] = [
    ("beam_break", TrackerMeasurement::STATUS_BEAM_BREAK),
    ("warming_up", TrackerMeasurement::STATUS_WARMING_UP),
    ("turbulence", TrackerMeasurement::STATUS_TURBULENCE),
    ("out_of_range", TrackerMeasurement::STATUS_OUT_OF_RANGE),
    ("rejected", TrackerMeasurement::STATUS_REJECTED),
];

#[derive(Clone, Debug, Default)]
pub struct TrackerStatus {
    latest: Option<(f64, u8, String)>,
    count: u64,
    flag_counts: [u64; FLAGS.len()],
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackerSummary {
    /// Stamp of the newest measurement [s since the epoch].
    pub stamp: f64,
    pub target_id: String,
    pub status_bits: u8,
    /// Names of the newest measurement's flags; empty when it is OK.
    pub active: Vec<&'static str>,
    pub measurements: u64,
    /// (flag, measurements that carried it since start).
    pub flag_counts: Vec<(&'static str, u64)>,
}

impl TrackerStatus {
    pub fn push(&mut self, m: &TrackerMeasurement) {
        let t = crate::stamp_seconds(&m.header.stamp);
        if self.latest.as_ref().is_none_or(|(t0, _, _)| t >= *t0) {
            self.latest = Some((t, m.status, m.target_id.clone()));
        }
        self.count += 1;
        for (k, (_, bit)) in FLAGS.iter().enumerate() {
            if m.status & bit != 0 {
                self.flag_counts[k] += 1;
            }
        }
    }

    pub fn summary(&self) -> Option<TrackerSummary> {
        let (stamp, bits, target) = self.latest.clone()?;
        Some(TrackerSummary {
            stamp,
            target_id: target,
            status_bits: bits,
            active: FLAGS
                .iter()
                .filter(|(_, b)| bits & b != 0)
                .map(|(n, _)| *n)
                .collect(),
            measurements: self.count,
            flag_counts: FLAGS
                .iter()
                .zip(self.flag_counts)
                .map(|((n, _), c)| (*n, c))
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newest_flags_in_words_and_session_counts() {
        let mut s = TrackerStatus::default();
        for (k, bits) in [2u8, 2, 2 | 4, 1, 0].iter().enumerate() {
            let mut m = TrackerMeasurement {
                status: *bits,
                target_id: "smr1".into(),
                ..Default::default()
            };
            m.header.stamp.sec = k as i32;
            s.push(&m);
        }
        let mut late = TrackerMeasurement {
            status: 1,
            ..Default::default()
        };
        late.header.stamp.sec = 1; // an old message arriving late does not replace the newest
        s.push(&late);
        let sum = s.summary().unwrap();
        assert_eq!(
            (
                sum.stamp,
                sum.status_bits,
                sum.active.len(),
                sum.measurements
            ),
            (4.0, 0, 0, 6)
        );
        assert_eq!(
            &sum.flag_counts[..3],
            &[("beam_break", 2), ("warming_up", 3), ("turbulence", 1)]
        );
        let mut w = TrackerStatus::default();
        w.push(&TrackerMeasurement {
            status: 2 | 4,
            ..Default::default()
        });
        assert_eq!(
            w.summary().unwrap().active,
            vec!["warming_up", "turbulence"]
        );
    }
}
