//! Benchmark load for the recorder: a cell-like set of publishers for `--seconds S` (default 60):
//! 1 kHz tracker (metrocell_msgs/TrackerMeasurement, reliable), 100 Hz joint states (reliable),
//! 30 Hz 1920x1080 mono8 images (sensor_msgs/Image, best effort), 1 Hz temperatures (reliable).
//! Prints the number of messages published per topic. Run inside `tests/isolated`
//! together with `metrocell-recorder` (see nodes/recorder/bench_cell_load.sh).

use std::time::{Duration, Instant};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::{Image, JointState, Temperature};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};

fn cdr<T: RosMessage>(m: &T) -> Vec<u8> {
    metrocell_bagtools::encode_cdr(m).expect("generated types serialise")
}

fn header(frame: &str) -> Header {
    let ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64;
    Header {
        stamp: Time::from_nanos(ns as i64),
        frame_id: frame.into(),
    }
}

fn main() {
    let seconds: f64 = std::env::args()
        .skip_while(|a| a != "--seconds")
        .nth(1)
        .map_or(60.0, |s| s.parse().unwrap());
    let mut node = MetrocellNode::builder("cell_load")
        .diagnostics_period(None)
        .build()
        .unwrap();
    let tracker = node
        .raw_publisher(
            "/tracker/measurements",
            TrackerMeasurement::ROS_TYPE,
            qos::reliable().history(ros2_client::qos::History::KeepLast { depth: 1000 }),
        )
        .unwrap();
    let joints = node
        .raw_publisher(
            "/joint_states",
            JointState::ROS_TYPE,
            qos::reliable().history(ros2_client::qos::History::KeepLast { depth: 100 }),
        )
        .unwrap();
    let camera = node
        .raw_publisher("/camera/image_raw", Image::ROS_TYPE, qos::sensor_data())
        .unwrap();
    let temps = node
        .raw_publisher(
            "/temperature/x_left",
            Temperature::ROS_TYPE,
            qos::reliable(),
        )
        .unwrap();
    // wait for the recorder to match every writer
    let t = Instant::now();
    while [&tracker, &joints, &camera, &temps]
        .iter()
        .any(|p| p.matched_subscriptions() == 0)
        && t.elapsed() < Duration::from_secs(30)
    {
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(500));
    // a fixed noise frame (not compressible to nothing), restamped each time
    let mut state = 0x2545F4914F6CDD1Du64;
    let pixels: Vec<u8> = (0..1920 * 1080)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 56) as u8
        })
        .collect();
    let mut image = Image {
        height: 1080,
        width: 1920,
        encoding: "mono8".into(),
        is_bigendian: 0,
        step: 1920,
        data: pixels,
        ..Default::default()
    };
    let mut counts = [0u64; 4];
    let start = Instant::now();
    let mut tick = 0u64; // 1 ms ticks
    let mut images_attempted = 0u64; // 30 Hz: one image whenever tick·30/1000 advances
    while start.elapsed().as_secs_f64() < seconds {
        let m = TrackerMeasurement {
            header: header("tracker"),
            target_id: "smr1".into(),
            range: 2.0 + tick as f64 * 1e-6,
            ..Default::default()
        };
        if tracker.publish(&cdr(&m)).is_ok() {
            counts[0] += 1;
        }
        if tick.is_multiple_of(10) {
            let j = JointState {
                header: header("robot"),
                name: (1..=6).map(|i| format!("joint_{i}")).collect(),
                position: vec![tick as f64 * 1e-4; 6],
                ..Default::default()
            };
            if joints.publish(&cdr(&j)).is_ok() {
                counts[1] += 1;
            }
        }
        if tick * 30 / 1000 + 1 > images_attempted {
            images_attempted += 1;
            image.header = header("camera");
            if camera.publish(&cdr(&image)).is_ok() {
                counts[2] += 1;
            }
        }
        if tick.is_multiple_of(1000) {
            let tm = Temperature {
                header: header("x_left"),
                temperature: 20.0,
                variance: 1e-4,
            };
            if temps.publish(&cdr(&tm)).is_ok() {
                counts[3] += 1;
            }
        }
        tick += 1;
        let due = start + Duration::from_millis(tick);
        if let Some(d) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    std::thread::sleep(Duration::from_secs(2));
    println!("published /tracker/measurements {} /joint_states {} /camera/image_raw {} /temperature/x_left {} in {:.1} s",
        counts[0], counts[1], counts[2], counts[3], start.elapsed().as_secs_f64());
}
