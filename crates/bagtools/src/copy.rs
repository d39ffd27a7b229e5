//! `bag filter` and `bag merge`: copy messages (bytes, log and publish times unchanged) into a
//! new bag, keeping each topic's type, definition and offered QoS.

use std::collections::BTreeMap;
use std::path::Path;

use metrocell_bag::{BagMessage, BagReader, BagWriter, MessageFilter, TopicInfo, WriterOptions};

use crate::error::{Result, ToolError};
use crate::topic_selection::TopicSelection;

/// What a copy wrote.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CopyReport {
    /// Messages written per topic.
    pub per_topic: BTreeMap<String, u64>,
}

impl CopyReport {
    pub fn total(&self) -> u64 {
        self.per_topic.values().sum()
    }
}

fn add_topic(writer: &mut BagWriter, t: &TopicInfo) -> Result<()> {
    // A topic recorded without its type's definition (empty schema encoding) stays so.
    if t.schema_encoding.is_empty() {
        writer.add_topic_without_definition(&t.name, &t.type_name, &t.offered_qos_profiles)?;
    } else {
        writer.add_topic(
            &t.name,
            &t.type_name,
            &t.definition,
            &t.offered_qos_profiles,
        )?;
    }
    Ok(())
}

/// Copy the messages of the open bag `input` whose topic is selected and whose log time lies in
/// `[start_ns, end_ns)` (end excluded, ns since the epoch) into the new bag `output`. The caller
/// opens the bag, so it can read its start time (`input.info()`) without a second scan.
pub fn filter_bag(
    input: &BagReader,
    output: &Path,
    selection: &TopicSelection,
    start_ns: Option<u64>,
    end_ns: Option<u64>,
    options: WriterOptions,
) -> Result<CopyReport> {
    let reader = input;
    let known = || {
        reader
            .topics()
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(missing) = selection.topics.iter().find(|t| reader.topic(t).is_none()) {
        return Err(ToolError::Topic {
            topic: missing.clone(),
            reason: format!("not in {} (topics: {})", reader.path().display(), known()),
        });
    }
    let topics: Vec<&TopicInfo> = reader
        .topics()
        .iter()
        .filter(|t| selection.matches(&t.name))
        .collect();
    if topics.is_empty() {
        return Err(ToolError::Invalid(format!(
            "no topic of {} matches {}; its topics: {} (a regex must match the whole name, e.g. '/temperature/.*')",
            reader.path().display(),
            selection.describe(),
            known()
        )));
    }
    let filter = MessageFilter {
        topics: Some(topics.iter().map(|t| t.name.clone()).collect()),
        start_ns,
        end_ns,
    };
    // An empty result is a mistake in the window, not a bag to write: say so before creating it.
    if reader.messages(&filter)?.next().transpose()?.is_none() {
        let info = reader.info();
        let start = info.start_ns.unwrap_or(0);
        let after_start = |t: u64| format!("{:.3} s", t.saturating_sub(start) as f64 * 1e-9);
        return Err(ToolError::Invalid(format!(
            "no message of {} lies in the window from {} to {} after the start of {}, which spans 0 s to {}",
            selection.describe(),
            start_ns.map_or("its start".to_string(), after_start),
            end_ns.map_or("its end".to_string(), after_start),
            reader.path().display(),
            after_start(info.end_ns.unwrap_or(start))
        )));
    }
    let mut writer = BagWriter::create(output, options)?;
    for t in &topics {
        add_topic(&mut writer, t)?;
    }
    let mut report = CopyReport::default();
    for m in reader.messages(&filter)? {
        let m = m?;
        writer.write(&m.topic, m.log_time, m.publish_time, &m.data)?;
        *report.per_topic.entry(m.topic).or_default() += 1;
    }
    writer.finish()?;
    Ok(report)
}

/// Merge `inputs` into the new bag `output`, interleaved by log time. A topic present in
/// several inputs must have the same type in each.
pub fn merge_bags(output: &Path, inputs: &[&Path], options: WriterOptions) -> Result<CopyReport> {
    let readers = inputs
        .iter()
        .map(BagReader::open)
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let mut writer = BagWriter::create(output, options)?;
    let mut types: BTreeMap<String, (String, &Path)> = BTreeMap::new();
    for (r, path) in readers.iter().zip(inputs) {
        for t in r.topics() {
            match types.get(&t.name) {
                Some((ty, first)) if ty != &t.type_name => {
                    return Err(ToolError::Topic {
                        topic: t.name.clone(),
                        reason: format!(
                            "type {} in {} but {} in {}",
                            ty,
                            first.display(),
                            t.type_name,
                            path.display()
                        ),
                    })
                }
                Some(_) => {}
                None => {
                    add_topic(&mut writer, t)?;
                    types.insert(t.name.clone(), (t.type_name.clone(), path));
                }
            }
        }
    }
    let all = MessageFilter::default();
    let mut iters = readers
        .iter()
        .map(|r| r.messages(&all))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let mut heads: Vec<Option<BagMessage>> = Vec::with_capacity(iters.len());
    for it in iters.iter_mut() {
        heads.push(it.next().transpose()?);
    }
    let mut report = CopyReport::default();
    // k-way merge by log time; ties keep input order.
    while let Some(i) = (0..heads.len())
        .filter(|&i| heads[i].is_some())
        .min_by_key(|&i| heads[i].as_ref().map(|m| m.log_time))
    {
        let m = heads[i].take().expect("filtered on is_some");
        writer.write(&m.topic, m.log_time, m.publish_time, &m.data)?;
        *report.per_topic.entry(m.topic).or_default() += 1;
        heads[i] = iters[i].next().transpose()?;
    }
    writer.finish()?;
    Ok(report)
}
