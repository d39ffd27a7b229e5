//! `metrocell topic list`

use std::time::Duration;

#[derive(clap::Args)]
pub struct ListArgs {
    /// Show each topic's type
    #[arg(short = 't', long)]
    show_types: bool,
    /// Seconds to listen for discovery before printing
    #[arg(long, default_value_t = 2.0)]
    wait: f64,
}

pub fn run(args: ListArgs) -> anyhow::Result<i32> {
    let node = super::cli_node("topic_list")?;
    let mut topics = node.discovered_topics_settled(
        Duration::from_millis(500),
        Duration::from_secs_f64(args.wait.max(0.1)),
    );
    topics.sort_by(|a, b| a.name.cmp(&b.name));
    topics.dedup_by(|a, b| a.name == b.name && a.type_name == b.type_name);
    for t in topics {
        if args.show_types {
            println!("{} [{}]", t.name, t.type_name);
        } else {
            println!("{}", t.name);
        }
    }
    Ok(0)
}
