//! `metrocell bag play BAG`: publish a bag's messages over DDS with the recorded spacing ÷ rate,
//! each topic offering the reliability and durability its recorded publishers offered.

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use metrocell_bag::{BagReader, MessageFilter};
use metrocell_bagtools::playback::{parse_remap, PlaybackClock};
use metrocell_bagtools::recorded_qos::replay_qos;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_node::{qos, MetrocellNode, RawPublisher};
use ros2_client::qos::{Durability, Reliability, WhenFull};

use super::keyboard::Keyboard;

#[derive(clap::Args)]
#[command(
    after_help = "Keys (when stdin is a terminal): space pauses/resumes, s publishes the next message while paused.\n\n\
Examples:\n  metrocell bag play run42 --rate 2 --topics /tracker/measurements\n  \
metrocell bag play run42 --start 30 --duration 10 --loop --remap /tracker/measurements:=/replay/points --clock 100"
)]
pub struct PlayArgs {
    /// Bag directory (or .mcap file)
    bag: PathBuf,
    /// Playback speed factor (2 = twice as fast)
    #[arg(short, long, default_value_t = 1.0)]
    rate: f64,
    /// Start this many seconds after the bag's first message
    #[arg(long)]
    start: Option<f64>,
    /// Play this many seconds of the bag
    #[arg(long)]
    duration: Option<f64>,
    /// Start over at the end, until Ctrl-C
    #[arg(short, long = "loop")]
    looping: bool,
    /// Play only these topics
    #[arg(long, num_args = 1..)]
    topics: Vec<String>,
    /// Publish topic FROM under the name TO (FROM:=TO); repeatable
    #[arg(long, value_parser = parse_remap)]
    remap: Vec<(String, String)>,
    /// Publish rosgraph_msgs/Clock on /clock at HZ (default 100 when given without a value)
    #[arg(long, num_args = 0..=1, default_missing_value = "100")]
    clock: Option<f64>,
    /// Seconds to wait after creating the publishers, so subscribers can match
    #[arg(long, default_value_t = 1.0)]
    delay: f64,
}

pub fn run(a: PlayArgs) -> anyhow::Result<i32> {
    if !(a.rate.is_finite() && a.rate > 0.0) {
        anyhow::bail!("--rate must be positive, got {}", a.rate);
    }
    if a.clock.is_some_and(|hz| !(hz.is_finite() && hz > 0.0)) {
        anyhow::bail!("--clock HZ must be positive");
    }
    let reader = BagReader::open(&a.bag)?;
    for t in &a.topics {
        if reader.topic(t).is_none() {
            anyhow::bail!("topic {t} is not in {}", a.bag.display());
        }
    }
    let topics: Vec<_> = reader
        .topics()
        .iter()
        .filter(|t| a.topics.is_empty() || a.topics.contains(&t.name))
        .collect();
    let bag_start = reader.info().start_ns.unwrap_or(0);
    let start_ns = super::offset_ns(bag_start, a.start)?;
    let end_ns = match a.duration {
        Some(d) => super::offset_ns(start_ns.unwrap_or(bag_start), Some(d))?,
        None => None,
    };
    let remaps: HashMap<String, String> = a.remap.into_iter().collect();

    let mut node = MetrocellNode::builder(&format!("metrocell_bag_play_{}", std::process::id()))
        .diagnostics_period(None)
        .handle_signals(true)
        .build()?;
    let mut publishers: HashMap<String, RawPublisher> = HashMap::new();
    for t in &topics {
        let name = remaps
            .get(&t.name)
            .cloned()
            .unwrap_or_else(|| t.name.clone());
        // Offer what the recorded publishers offered (rosbag2's rule, see recorded_qos).
        // A profile text that does not parse is reported and the topic played with the
        // default publisher QoS, as for a bag without profiles.
        let recorded = metrocell_bag::parse_offered_qos(&t.name, &t.offered_qos_profiles)
            .unwrap_or_else(|e| {
                eprintln!(
                    "warning: {e}; playing {} with the default QoS (reliable, volatile)",
                    t.name
                );
                Vec::new()
            });
        let r = replay_qos(&recorded);
        // keep-last 10, rosbag2's replay history, comes with qos::reliable()
        let offered = qos::reliable()
            .reliability(if r.reliable {
                Reliability::Reliable {
                    when_full: WhenFull::DEFAULT,
                }
            } else {
                Reliability::BestEffort
            })
            .durability(if r.transient_local {
                Durability::TransientLocal
            } else {
                Durability::Volatile
            });
        publishers.insert(
            t.name.clone(),
            node.raw_publisher(&name, &t.type_name, offered)?,
        );
    }
    let clock_pub = match a.clock {
        Some(_) => Some(node.publisher::<Clock>("/clock", qos::reliable())?),
        None => None,
    };
    let token = node.shutdown_token();
    if token.wait_timeout(Duration::from_secs_f64(a.delay.max(0.0))) {
        return Ok(130);
    }
    let keyboard = Keyboard::open();
    if keyboard.is_some() {
        eprintln!(
            "playing {} (space: pause/resume, s: step while paused)",
            a.bag.display()
        );
    }
    let clock_period = a.clock.map(|hz| Duration::from_secs_f64(1.0 / hz));
    let mut next_clock = Instant::now();
    let mut clock = PlaybackClock::new(a.rate);
    let filter = MessageFilter {
        topics: Some(topics.iter().map(|t| t.name.clone()).collect()),
        start_ns,
        end_ns,
    };
    let mut published = 0u64;
    'play: loop {
        for m in reader.messages(&filter)? {
            let m = m?;
            // Wait until the message is due, serving keys and /clock meanwhile.
            loop {
                if token.is_triggered() {
                    break 'play;
                }
                let mut step = false;
                if let Some(k) = &keyboard {
                    while let Ok(key) = k.keys.try_recv() {
                        match key {
                            b' ' => {
                                clock.toggle_pause(Instant::now());
                                eprintln!(
                                    "{}",
                                    if clock.is_paused() {
                                        "paused"
                                    } else {
                                        "resumed"
                                    }
                                );
                            }
                            b's' if clock.is_paused() => step = true,
                            _ => {}
                        }
                    }
                }
                let now = Instant::now();
                if let (Some(p), Some(period)) = (&clock_pub, clock_period) {
                    if now >= next_clock {
                        if let Some(t) = clock.bag_time_at(now) {
                            let _ = p.publish(Clock {
                                clock: Time::from_nanos(t as i64),
                            });
                        }
                        next_clock = now + period;
                    }
                }
                if step {
                    clock.stepped(m.log_time, now);
                    break;
                }
                match clock.wait_for(m.log_time, now) {
                    Some(d) if d.is_zero() => break,
                    Some(d) => std::thread::sleep(d.min(Duration::from_millis(5))),
                    None => std::thread::sleep(Duration::from_millis(10)),
                }
            }
            publishers[&m.topic].publish_stamped(&m.data, Some(m.publish_time as i64))?;
            published += 1;
        }
        if !a.looping {
            break;
        }
        clock.restart();
    }
    // Let reliable writers deliver their last samples before the participant goes away.
    token.wait_timeout(Duration::from_millis(500));
    eprintln!("published {published} messages");
    Ok(0)
}
