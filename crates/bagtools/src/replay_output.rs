//! Where a replaying node's outputs go: an output bag (`--output OUT_BAG`), or JSON lines on
//! stdout (`{"topic": ..., "time_ns": ..., "message": {...}}`, one per output) when no bag is
//! given. Both are written at bag time (the log time of the input that caused the output).

use std::io::Write;
use std::path::Path;

use metrocell_bag::WriterOptions;
use rosmsg::RosMessage;

use crate::bag_sink::BagSink;
use crate::error::{Result, ToolError};

pub enum ReplayOutput {
    // boxed: the sink holds the writer's buffers, the JSON arm a pointer
    Bag(Box<BagSink>),
    JsonLines(Box<dyn Write>),
}

impl ReplayOutput {
    /// A bag at `output`, or JSON lines on stdout for `None`.
    pub fn open(output: Option<&Path>) -> Result<Self> {
        Ok(match output {
            Some(dir) => {
                ReplayOutput::Bag(Box::new(BagSink::create(dir, WriterOptions::default())?))
            }
            None => ReplayOutput::JsonLines(Box::new(std::io::stdout().lock())),
        })
    }

    /// Declare output `topic` of type `T` (a no-op for JSON lines).
    pub fn advertise<T: RosMessage>(&mut self, topic: &str) -> Result<()> {
        match self {
            ReplayOutput::Bag(sink) => sink.advertise::<T>(topic),
            ReplayOutput::JsonLines(_) => Ok(()),
        }
    }

    pub fn write<T: RosMessage>(&mut self, topic: &str, m: &T, time_ns: u64) -> Result<()> {
        match self {
            ReplayOutput::Bag(sink) => sink.write(topic, m, time_ns),
            ReplayOutput::JsonLines(out) => {
                let line = serde_json::json!({ "topic": topic, "time_ns": time_ns, "message": m });
                writeln!(out, "{line}").map_err(|e| ToolError::Invalid(format!("stdout: {e}")))
            }
        }
    }

    /// Close the bag (writes its metadata) or flush stdout.
    pub fn finish(self) -> Result<()> {
        match self {
            ReplayOutput::Bag(sink) => sink.finish().map(|_| ()),
            ReplayOutput::JsonLines(mut out) => out
                .flush()
                .map_err(|e| ToolError::Invalid(format!("stdout: {e}"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BagSource;
    use metrocell_msgs::std_msgs::msg::Header;

    #[test]
    fn bag_output_reads_back_and_unadvertised_topics_are_refused() {
        let dir =
            std::env::temp_dir().join(format!("metrocell-replay-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut out = ReplayOutput::open(Some(&dir)).unwrap();
        out.advertise::<Header>("/out").unwrap();
        let h = Header {
            frame_id: "f".into(),
            ..Default::default()
        };
        out.write("/out", &h, 42).unwrap();
        assert!(out
            .write("/other", &h, 43)
            .unwrap_err()
            .to_string()
            .contains("/other"));
        out.finish().unwrap();
        let mut src = BagSource::open(&dir).unwrap();
        src.subscribe::<Header>("/out").unwrap();
        let got: Vec<_> = src.messages().unwrap().map(|m| m.unwrap()).collect();
        assert_eq!(got.len(), 1);
        assert_eq!(
            (got[0].log_time_ns, got[0].decode::<Header>().unwrap()),
            (42, h)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
