//! Frames from a V4L2 capture device (`device:=/dev/videoN`), published with the driver's
//! capture stamp. Capture and conversion live in `metrocell_camera_model::v4l2`.

use std::time::Duration;

use metrocell_camera_model::v4l2::{
    check_frame_size, requested_size, CaptureDevice, Dequeued, PixelFormat, StampOrigin,
};
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
        other => Err(format!(
            "parameter pixel_format: `{other}` is not one of auto, GREY, YUYV"
        )),
    }
}

pub struct Outputs<'a> {
    pub images: &'a Publisher<Image>,
    pub infos: &'a Publisher<CameraInfo>,
    pub info: Option<CameraInfo>,
    pub frame_id: String,
}

pub fn run(
    node: &MetrocellNode,
    device: &str,
    out: Outputs<'_>,
) -> Result<(), Box<dyn std::error::Error>> {
    let calibrated = out.info.as_ref().map(|i| (i.width, i.height));
    // In [0, MAX_FRAME_SIDE_PX] by the declared range, so the conversion cannot fail.
    let side = |name: &str| -> Result<u32, Box<dyn std::error::Error>> {
        Ok(u32::try_from(node.param::<i64>(name)?)?)
    };
    let requested = requested_size(side("width")?, side("height")?, calibrated);
    let mut cam = CaptureDevice::open(
        device,
        requested.0,
        requested.1,
        &formats(&node.param::<String>("pixel_format")?)?,
    )?;
    let (format, width, height) = cam.format();
    let diagnostics = node.diagnostics();
    if let Some(warning) = check_frame_size(device, requested, (width, height), calibrated)? {
        diagnostics.set_value(
            "size_changed_by_driver",
            format!("{}x{} → {width}x{height}", requested.0, requested.1),
        );
        node.warn(warning);
    }
    node.info(format!(
        "{device}: streaming {format:?} {width}x{height} as {}",
        format.ros_encoding()
    ));
    let token = node.shutdown_token();
    let mut last_sequence: Option<u32> = None;
    let (mut corrupt, mut warned_stamps) = (0u64, false);
    while !token.is_triggered() {
        let Some(dequeued) = cam.next_frame(Duration::from_millis(200))? else {
            continue;
        };
        let sequence = match &dequeued {
            Dequeued::Frame(f) => f.sequence,
            Dequeued::Corrupt { sequence, .. } => *sequence,
        };
        if let Some(prev) = last_sequence {
            diagnostics.add_count(
                "frames_dropped_by_driver",
                sequence.wrapping_sub(prev).saturating_sub(1) as u64,
            );
        }
        last_sequence = Some(sequence);
        let f = match dequeued {
            Dequeued::Frame(f) => f,
            Dequeued::Corrupt {
                sequence,
                bytes_used,
            } => {
                corrupt += 1;
                diagnostics.add_count("corrupt_buffers", 1);
                if let Some(w) = corrupt_buffer_warning(device, sequence, bytes_used, corrupt) {
                    node.warn(w);
                }
                continue;
            }
        };
        if let StampOrigin::Dequeue { reason } = f.stamp_origin {
            diagnostics.add_count("frames_stamped_at_dequeue", 1);
            if !std::mem::replace(&mut warned_stamps, true) {
                node.warn(format!("{device}: driver timestamps are not usable ({reason}); frames are stamped when dequeued, late by the driver's latency (about one frame period)"));
            }
        }
        let header = Header {
            stamp: Time::from_nanos(f.stamp_ns),
            frame_id: out.frame_id.clone(),
        };
        if let Some(info) = &out.info {
            let _ = out.infos.publish(CameraInfo {
                header: header.clone(),
                ..info.clone()
            });
        }
        let img = Image {
            header,
            height: f.height,
            width: f.width,
            encoding: f.encoding.into(),
            is_bigendian: 0,
            step: f.step,
            data: f.data,
        };
        if out.images.publish(img).is_ok() {
            diagnostics.add_count("frames_published", 1);
        }
    }
    Ok(())
}

/// The warning for the `count`-th corrupt buffer, or `None`: the 1st, 10th, 100th, ... are
/// logged (a flaky USB link can flag every frame; the diagnostics counter has the exact count).
pub fn corrupt_buffer_warning(
    device: &str,
    sequence: u32,
    bytes_used: u32,
    count: u64,
) -> Option<String> {
    let decade = count > 0 && 10u64.pow(count.ilog10()) == count;
    decade.then(|| {
        format!("{device}: frame {sequence} ({bytes_used} B) flagged corrupt by the driver (V4L2_BUF_FLAG_ERROR); skipped, not published; {count} corrupt so far (check the cable/USB bandwidth)")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_format_parameter() {
        assert_eq!(
            formats("auto").unwrap(),
            [PixelFormat::Grey, PixelFormat::Yuyv]
        );
        assert_eq!(formats("yuyv").unwrap(), [PixelFormat::Yuyv]);
        assert!(formats("MJPG").unwrap_err().contains("MJPG"));
    }

    #[test]
    fn corrupt_buffers_are_reported_naming_the_device_without_flooding() {
        let w = corrupt_buffer_warning("/dev/video3", 1234, 4096, 1).unwrap();
        assert!(
            w.contains("/dev/video3")
                && w.contains("1234")
                && w.contains("V4L2_BUF_FLAG_ERROR")
                && w.contains("not published"),
            "{w}"
        );
        let logged: Vec<u64> = (1..=1000)
            .filter(|&n| corrupt_buffer_warning("/dev/video3", 0, 0, n).is_some())
            .collect();
        assert_eq!(logged, [1, 10, 100, 1000]);
        assert!(corrupt_buffer_warning("/dev/video3", 0, 0, 0).is_none());
    }
}
