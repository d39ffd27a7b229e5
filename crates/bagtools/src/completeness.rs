//! Does a bag hold every message a publisher says it sent? The publisher's own per-topic
//! counts (the twin's `published/<topic>` diagnostics) against the bag's per-topic counts.

use std::collections::BTreeMap;

/// One topic whose bag count differs from what was published.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CountMismatch {
    pub topic: String,
    pub published: u64,
    pub recorded: u64,
}

impl std::fmt::Display for CountMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.recorded < self.published {
            write!(
                f,
                "{}: published {}, recorded {} ({} missing)",
                self.topic,
                self.published,
                self.recorded,
                self.published - self.recorded
            )
        } else {
            write!(
                f,
                "{}: published {}, recorded {} ({} more: another publisher on the topic?)",
                self.topic,
                self.published,
                self.recorded,
                self.recorded - self.published
            )
        }
    }
}

/// Every published topic whose recorded count differs (a topic absent from the bag counts 0).
/// Topics only in the bag (other publishers) are not the publisher's business and are ignored.
pub fn compare_counts(
    published: &BTreeMap<String, u64>,
    recorded: &BTreeMap<String, u64>,
) -> Vec<CountMismatch> {
    published
        .iter()
        .filter_map(|(topic, &p)| {
            let r = recorded.get(topic).copied().unwrap_or(0);
            (r != p).then(|| CountMismatch {
                topic: topic.clone(),
                published: p,
                recorded: r,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_extra_and_absent_topics_are_reported() {
        let published: BTreeMap<String, u64> = [("/a", 10), ("/b", 5), ("/c", 3), ("/d", 0)]
            .iter()
            .map(|(t, n)| (t.to_string(), *n))
            .collect();
        let recorded: BTreeMap<String, u64> = [("/a", 10), ("/b", 4), ("/d", 0), ("/rosout", 7)]
            .iter()
            .map(|(t, n)| (t.to_string(), *n))
            .collect();
        let m = compare_counts(&published, &recorded);
        assert_eq!(
            m,
            vec![
                CountMismatch {
                    topic: "/b".into(),
                    published: 5,
                    recorded: 4
                },
                CountMismatch {
                    topic: "/c".into(),
                    published: 3,
                    recorded: 0
                }
            ]
        );
        assert_eq!(m[0].to_string(), "/b: published 5, recorded 4 (1 missing)");
        assert!(compare_counts(&published, &published).is_empty());
    }
}
