//! `metrocell-camera`: publishes frames read from image files.
//!
//! Publishes `image` (sensor_msgs/Image: mono8, mono16 or rgb8) and `camera_info`
//! (sensor_msgs/CameraInfo from the ROS camera_info YAML given by `camera_info_url`), both with
//! the same header: stamp = the frame's capture time per `stamp_source` (default: the file's
//! modification time; `filename` parses it from the name; `now` = the publication instant on the
//! node clock — see `metrocell_camera_node::capture_stamp`), frame_id = `frame_id`. An unreadable
//! or truncated file, or one without a usable stamp, is a warning naming it; the node moves on.
//! With `device:=/dev/videoN` frames come from a V4L2 capture device instead (GREY → mono8,
//! YUYV → rgb8, stamped with the driver's capture time; `width`, `height`, `pixel_format`);
//! the capture path is untested on hardware (no camera on the build machines). With a
//! camera_info, width/height 0 request the calibration's size and a driver that delivers
//! another size is an error (the calibration would be wrong); buffers the driver flags as
//! corrupt are skipped with a warning (`corrupt_buffers` in diagnostics).
//!
//!   metrocell-camera --ros-args -p path:="views/*.png" -p rate:=10.0 -p loop:=true \
//!       -p camera_info_url:=camera_info.yaml -p frame_id:=camera_optical
//!   metrocell-camera --ros-args -p path:="plate/*.png" -p wait_for_subscribers:=1 -p rate:=1.0   # into a recording
//!   metrocell-camera --ros-args -p path:=shots -p stamp_source:=filename -p stamp_pattern:="cam0_{ns}.tiff"
//!   metrocell-camera --ros-args -p device:=/dev/video0 -p width:=1920 -p height:=1080 -p pixel_format:=YUYV

mod device;

use std::time::{Duration, Instant};

use metrocell_camera_model::CameraInfo as CameraInfoYaml;
use metrocell_camera_node::capture_stamp::StampSource;
use metrocell_camera_node::parameters::declarations;
use metrocell_camera_node::{file_list, image_file};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};

use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, MetrocellNode};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-camera: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("camera", declarations())?;
    let rate = node.param::<f64>("rate")?;
    let looping = node.param::<bool>("loop")?;
    let frame_id = node.param::<String>("frame_id")?;
    let url = node.param::<String>("camera_info_url")?;
    let stamps = StampSource::parse(
        &node.param::<String>("stamp_source")?,
        &node.param::<String>("stamp_pattern")?,
    )?;
    let info = if url.is_empty() {
        None
    } else {
        Some(CameraInfoYaml::load(std::path::Path::new(
            url.trim_start_matches("file://"),
        ))?)
    };
    let device = node.param::<String>("device")?;
    if !device.is_empty() {
        let images = node.publisher::<Image>("image", qos::sensor_data())?;
        let infos = node.publisher::<CameraInfo>("camera_info", qos::sensor_data())?;
        let info = info.as_ref().map(CameraInfoYaml::to_msg);
        return device::run(
            &node,
            &device,
            device::Outputs {
                images: &images,
                infos: &infos,
                info,
                frame_id,
            },
        );
    }
    let path = node.param::<String>("path")?;
    if path.is_empty() {
        return Err("no source: set -p path:=DIR_OR_GLOB (image files) or -p device:=/dev/videoN (V4L2); --help lists the parameters".into());
    }
    let files = file_list::list_image_files(&path)?;
    node.info(format!(
        "{} files, {} fps, loop {looping}, camera_info {}",
        files.len(),
        rate,
        if url.is_empty() { "none" } else { &url }
    ));

    let images = node.publisher::<Image>("image", qos::sensor_data())?;
    let infos = node.publisher::<CameraInfo>("camera_info", qos::sensor_data())?;
    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let wanted = node.param::<i64>("wait_for_subscribers")? as usize;
    if wanted > 0 {
        // Best-effort frames published before a reader matches are gone: a folder of photos
        // ingested into a recording waits for the recorder.
        node.info(format!("waiting for {wanted} subscriber(s) of the images"));
        let mut said = Instant::now();
        loop {
            let ros = node.ros_node();
            let matched = images.get_subscription_count(ros).min(if info.is_some() {
                infos.get_subscription_count(ros)
            } else {
                usize::MAX
            });
            if matched >= wanted || token.is_triggered() {
                break;
            }
            if said.elapsed() > Duration::from_secs(10) {
                node.info(format!(
                    "still waiting: {matched} of {wanted} subscriber(s) matched"
                ));
                said = Instant::now();
            }
            token.wait_timeout(Duration::from_millis(20));
        }
    }
    let period = (rate > 0.0).then(|| Duration::from_secs_f64(1.0 / rate));
    let mut next = Instant::now();
    'outer: loop {
        let mut published_any = false;
        for path in &files {
            if token.is_triggered() {
                break 'outer;
            }
            let mut img = match image_file::read_image_file(path) {
                Ok(m) => m,
                Err(e) => {
                    diagnostics.add_count("files_unreadable", 1);
                    node.warn(e.to_string());
                    continue;
                }
            };
            let capture_ns = match stamps.file_stamp_ns(path) {
                Ok(t) => t,
                Err(e) => {
                    diagnostics.add_count("files_without_stamp", 1);
                    node.warn(e.to_string());
                    continue;
                }
            };
            if let Some(p) = period {
                let now = Instant::now();
                if next > now {
                    token.wait_timeout(next - now);
                }
                next = next.max(now) + p;
            }
            let ns = capture_ns.unwrap_or_else(|| node.now().to_nanos());
            let header = Header {
                stamp: Time::from_nanos(ns),
                frame_id: frame_id.clone(),
            };
            img.header = header.clone();
            if let Some(info) = &info {
                if info.image_width != img.width || info.image_height != img.height {
                    diagnostics.add_count("size_mismatch", 1);
                    node.warn(format!(
                        "{}: {}x{} but camera_info is {}x{}",
                        path.display(),
                        img.width,
                        img.height,
                        info.image_width,
                        info.image_height
                    ));
                }
                let mut ci = info.to_msg();
                ci.header = header;
                let _ = infos.publish(ci);
            }
            if images.publish(img).is_ok() {
                published_any = true;
                diagnostics.add_count("frames_published", 1);
            }
        }
        if !looping {
            break;
        }
        if !published_any {
            return Err("no file could be read; stopping instead of looping on nothing".into());
        }
    }
    diagnostics.ok("all files published");
    // Give reliable late joiners' readers a moment before the participant goes away.
    token.wait_timeout(Duration::from_millis(500));
    Ok(())
}
