//! Video4Linux2 capture without a V4L2 crate: the handful of ioctls a streaming capture needs
//! ([`ioctl`]: layouts and request numbers of `linux/videodev2.h`), a memory-mapped streaming
//! [`device::CaptureDevice`], and the [`pixel_format`] conversions to sensor_msgs/Image layouts.
//!
//! Supported: single-planar video capture devices (`V4L2_CAP_VIDEO_CAPTURE` + streaming) in
//! GREY (→ mono8) or YUYV (→ rgb8), on 64-bit Linux. Multi-planar devices, compressed formats
//! (MJPEG, H.264) and other pixel formats are refused with an error naming the device and what it
//! offers. Frame stamps ([`timestamp`]): the driver's capture timestamp moved from
//! CLOCK_MONOTONIC to the system clock, so a frame is stamped when it was exposed, not when it
//! was dequeued; drivers whose timestamps are on no known clock get the dequeue instant, flagged.
//! Buffers the driver flags V4L2_BUF_FLAG_ERROR are re-queued and reported, never converted.
//! [`frame_size`]: the size to request and what to do when the driver picks another.

pub mod device;
pub mod frame_size;
pub mod ioctl;
pub mod pixel_format;
pub mod timestamp;

pub use device::{CaptureDevice, Dequeued, Frame};
pub use frame_size::{check_frame_size, requested_size};
pub use pixel_format::{convert_frame, PixelFormat};
pub use timestamp::{capture_stamp, ClockSample, StampOrigin};

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum CaptureError {
    #[error("{device}: cannot open ({reason}); is the camera connected and is the path right (ls /dev/video*)?")]
    Open { device: String, reason: String },
    #[error("{device}: not a V4L2 device ({reason})")]
    NotV4l2 { device: String, reason: String },
    #[error("{device} ({card}): not a video capture device with streaming I/O (device caps {caps:#010x})")]
    NotCapture {
        device: String,
        card: String,
        caps: u32,
    },
    #[error("{device}: pixel format {wanted} not supported by the driver (it offers {offered}); supported here: GREY, YUYV")]
    Format {
        device: String,
        wanted: String,
        offered: String,
    },
    #[error("{device}: {call} failed ({reason})")]
    Ioctl {
        device: String,
        call: &'static str,
        reason: String,
    },
    #[error("{0}")]
    Frame(String),
    #[error("{device}: the driver delivers {width}x{height} frames but camera_info is calibrated for {cal_width}x{cal_height}; a calibration only holds at its own resolution: request {cal_width}x{cal_height} (-p width:={cal_width} -p height:={cal_height}) or use a camera_info made at {width}x{height}")]
    CalibrationSize {
        device: String,
        width: u32,
        height: u32,
        cal_width: u32,
        cal_height: u32,
    },
    #[error("V4L2 capture needs 64-bit Linux")]
    Unsupported,
}

pub type Result<T> = std::result::Result<T, CaptureError>;
