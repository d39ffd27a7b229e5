//! Frames from a V4L2 capture device (`device:=/dev/videoN`), published with the driver's
//! capture stamp. Capture and conversion live in `metrocell_camera::v4l2`.

use std::time::Duration;

use metrocell_camera::v4l2::{CaptureDevice, PixelFormat};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{MetrocellNode, Publisher};

/// `pixel_format` parameter → the formats to try, in order.
pub fn formats(name: &str) -> Result<Vec<PixelFormat>, String> {
    match name.trim().to_ascii_uppercase().as_str() {
        "AUTO" | "" => Ok(vec![PixelFormat::Grey, PixelFormat::Yuyv]),
        "GREY" | "GRAY" => Ok(vec![PixelFormat::Grey]),
        "YUYV" => Ok(vec![PixelFormat::Yuyv]),
        other => Err(format!("parameter pixel_format: `{other}` is not one of auto, GREY, YUYV")),
    }
}

pub struct Outputs<'a> {
    pub images: &'a Publisher<Image>,
    pub infos: &'a Publisher<CameraInfo>,
    pub info: Option<CameraInfo>,
    pub frame_id: String,
}

pub fn run(node: &MetrocellNode, device: &str, out: Outputs<'_>) -> Result<(), Box<dyn std::error::Error>> {
    let (w, h) = (node.param::<i64>("width")?.max(0) as u32, node.param::<i64>("height")?.max(0) as u32);
    let mut cam = CaptureDevice::open(device, w, h, &formats(&node.param::<String>("pixel_format")?)?)?;
    let (format, width, height) = cam.format();
    node.info(format!("{device}: streaming {format:?} {width}x{height} as {}", format.ros_encoding()));
    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut last_sequence: Option<u32> = None;
    while !token.is_triggered() {
        let Some(f) = cam.next_frame(Duration::from_millis(200))? else { continue };
        if let Some(prev) = last_sequence {
            diagnostics.add_count("frames_dropped_by_driver", f.sequence.wrapping_sub(prev).saturating_sub(1) as u64);
        }
        last_sequence = Some(f.sequence);
        let header = Header { stamp: Time::from_nanos(f.stamp_ns), frame_id: out.frame_id.clone() };
        if let Some(info) = &out.info {
            let _ = out.infos.publish(CameraInfo { header: header.clone(), ..info.clone() });
        }
        let img = Image { header, height: f.height, width: f.width, encoding: f.encoding.into(), is_bigendian: 0, step: f.step, data: f.data };
        if out.images.publish(img).is_ok() {
            diagnostics.add_count("frames_published", 1);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_format_parameter() {
        assert_eq!(formats("auto").unwrap(), [PixelFormat::Grey, PixelFormat::Yuyv]);
        assert_eq!(formats("yuyv").unwrap(), [PixelFormat::Yuyv]);
        assert!(formats("MJPG").unwrap_err().contains("MJPG"));
    }
}
