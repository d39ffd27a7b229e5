//! The node's own (non-ROS) arguments for offline replay, shared by every node that can run on a
//! bag: `--bag IN_BAG [--output OUT_BAG]`, given before `--ros-args`. Without `--bag` the node
//! runs live on DDS.

use std::path::PathBuf;

/// `--bag IN_BAG [--output OUT_BAG]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayArgs {
    pub bag: PathBuf,
    /// Output bag; `None` = JSON lines on stdout.
    pub output: Option<PathBuf>,
}

impl ReplayArgs {
    /// The flags and what they do, for the node's `--help` ([`crate::NodeBuilder::node_argument`]).
    pub const FLAG: &'static str = "--bag IN_BAG [--output OUT_BAG]";
    pub const HELP: &'static str = "run on a recorded bag instead of DDS, as fast as the CPU allows, with the outputs the live \
node would publish; they go to OUT_BAG (a rosbag2 MCAP directory) or, without --output, to stdout as JSON lines";

    /// Parse the arguments left over after the ROS command line (program name excluded).
    /// `Ok(None)` when `--bag` is absent (live run).
    pub fn parse(args: &[String]) -> Result<Option<ReplayArgs>, String> {
        let (mut bag, mut output) = (None, None);
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut value = |flag: &str| {
                it.next()
                    .map(PathBuf::from)
                    .ok_or_else(|| format!("{flag} needs a path"))
            };
            match a.as_str() {
                "--bag" => bag = Some(value("--bag")?),
                "--output" => output = Some(value("--output")?),
                other => return Err(format!("unknown argument '{other}' (expected --bag IN_BAG [--output OUT_BAG] before --ros-args)")),
            }
        }
        match (bag, output) {
            (Some(bag), output) => Ok(Some(ReplayArgs { bag, output })),
            (None, Some(_)) => Err("--output needs --bag".into()),
            (None, None) => Ok(None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(v: &[&str]) -> Result<Option<ReplayArgs>, String> {
        ReplayArgs::parse(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn bag_and_output_parse_and_mistakes_are_named() {
        assert_eq!(parse(&[]).unwrap(), None);
        assert_eq!(
            parse(&["--bag", "in"]).unwrap(),
            Some(ReplayArgs {
                bag: "in".into(),
                output: None
            })
        );
        assert_eq!(
            parse(&["--bag", "in", "--output", "out"])
                .unwrap()
                .unwrap()
                .output,
            Some(PathBuf::from("out"))
        );
        assert!(parse(&["--output", "out"])
            .unwrap_err()
            .contains("--output needs --bag"));
        assert!(parse(&["--bag"])
            .unwrap_err()
            .contains("--bag needs a path"));
        assert!(parse(&["--bags", "x"]).unwrap_err().contains("--bags"));
    }
}
