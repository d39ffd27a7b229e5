//! Naming the messages a recording lost by time, so that whoever reads the log can put a loss
//! next to what happened then (a cable pulled at 12:00:14, a node restarted): the gaps found
//! since the last report, one line per topic, and each topic's largest gaps in the final summary.

use std::collections::BTreeMap;

use metrocell_bagtools::SequenceGap;

/// "messages missing from the bag: /a: 30 messages between 12:00:14.2 and 12:01:14.5 UTC
/// (60.3 s); /b: 2 gaps, 45 messages between … (…)" — the gaps found since the last report,
/// joined per topic (their total, from the first gap's start to the last one's end). `None`
/// when there are none.
pub fn describe_new_gaps(gaps: &[(String, SequenceGap)]) -> Option<String> {
    if gaps.is_empty() {
        return None;
    }
    let mut by_topic: BTreeMap<&str, (usize, SequenceGap)> = BTreeMap::new();
    for (topic, g) in gaps {
        by_topic
            .entry(topic)
            .and_modify(|(n, joined)| {
                *n += 1;
                joined.missing += g.missing;
                joined.after_ns = joined.after_ns.min(g.after_ns);
                joined.until_ns = joined.until_ns.max(g.until_ns);
            })
            .or_insert((1, *g));
    }
    let parts: Vec<String> = by_topic
        .into_iter()
        .map(|(topic, (n, joined))| {
            if n == 1 {
                format!("{topic}: {}", joined.describe())
            } else {
                format!("{topic}: {n} gaps, {}", joined.describe())
            }
        })
        .collect();
    Some(format!(
        "messages missing from the bag (sequence gaps): {}",
        parts.join("; ")
    ))
}

/// A topic's largest gaps for the final summary: "largest: 30 messages between … (60.3 s), …",
/// at most `n` of them.
pub fn largest_gaps(gaps: &[SequenceGap], n: usize) -> String {
    let named: Vec<String> = gaps.iter().take(n).map(SequenceGap::describe).collect();
    format!("largest: {}", named.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;
    /// 2026-11-29 12:00:00 UTC in ns since the epoch.
    const NOON: u64 = 1_795_953_600 * S;

    fn gap(missing: u64, after_s: f64, until_s: f64) -> SequenceGap {
        SequenceGap {
            missing,
            after_ns: NOON + (after_s * 1e9) as u64,
            until_ns: NOON + (until_s * 1e9) as u64,
        }
    }

    #[test]
    fn the_gaps_of_a_report_are_joined_per_topic() {
        assert_eq!(describe_new_gaps(&[]), None);
        let gaps = vec![
            ("/b".to_string(), gap(20, 14.0, 40.0)),
            ("/a".to_string(), gap(30, 14.2, 74.5)),
            ("/b".to_string(), gap(25, 41.0, 75.0)),
        ];
        assert_eq!(
            describe_new_gaps(&gaps).unwrap(),
            "messages missing from the bag (sequence gaps): \
             /a: 30 messages between 12:00:14.2 and 12:01:14.5 UTC (60.3 s); \
             /b: 2 gaps, 45 messages between 12:00:14.0 and 12:01:15.0 UTC (61.0 s)"
        );
    }

    #[test]
    fn the_summary_names_at_most_n_gaps() {
        let gaps = vec![gap(30, 14.2, 74.5), gap(1, 80.0, 80.2), gap(1, 90.0, 90.2)];
        assert_eq!(
            largest_gaps(&gaps, 2),
            "largest: 30 messages between 12:00:14.2 and 12:01:14.5 UTC (60.3 s), \
             1 message between 12:01:20.0 and 12:01:20.2 UTC (0.2 s)"
        );
    }
}
