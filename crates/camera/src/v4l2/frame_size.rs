//! The frame size to ask the driver for, and what to say when VIDIOC_S_FMT gives another one.
//!
//! VIDIOC_S_FMT never fails for an unsupported size: the driver picks the nearest it supports
//! and reports it. So after S_FMT:
//! - driver size ≠ requested size (a non-zero `width`/`height` parameter): a warning naming both;
//!   the frames are still good, only not the size asked for (what v4l2-ctl and usb_cam do).
//! - driver size ≠ the size of the loaded camera_info: an error. A calibration (K, distortion)
//!   holds only at the resolution it was made at; publishing it with frames of another size
//!   gives every consumer wrong poses (or, in the fiducial node, silently none), which is worse
//!   than not starting. Fix: request the calibration's size, or calibrate at this one.
//!
//! With a camera_info loaded, a zero `width`/`height` requests the calibration's size, so the
//! usual case (calibrated camera, no explicit size) just works.

use super::{CaptureError, Result};

/// The size to request: each zero component of (`width`, `height`) takes the calibration's
/// value when there is one (else stays 0 = the driver's current).
pub fn requested_size(width: u32, height: u32, calibrated: Option<(u32, u32)>) -> (u32, u32) {
    match calibrated {
        Some((cw, ch)) => (
            if width == 0 { cw } else { width },
            if height == 0 { ch } else { height },
        ),
        None => (width, height),
    }
}

/// Compare the driver's size with the request and the calibration: `Ok(Some(warning))` when the
/// driver changed a requested dimension, `Err` when the calibration is for another size.
pub fn check_frame_size(
    device: &str,
    requested: (u32, u32),
    chosen: (u32, u32),
    calibrated: Option<(u32, u32)>,
) -> Result<Option<String>> {
    if let Some((cal_width, cal_height)) = calibrated {
        if (cal_width, cal_height) != chosen {
            return Err(CaptureError::CalibrationSize {
                device: device.into(),
                width: chosen.0,
                height: chosen.1,
                cal_width,
                cal_height,
            });
        }
    }
    let changed = |want: u32, got: u32| want != 0 && want != got;
    if changed(requested.0, chosen.0) || changed(requested.1, chosen.1) {
        let show = |v: u32| {
            if v == 0 {
                "any".to_string()
            } else {
                v.to_string()
            }
        };
        return Ok(Some(format!(
            "{device}: requested {}x{} but the driver chose {}x{} (the nearest size it supports; `v4l2-ctl -d {device} --list-formats-ext` lists them)",
            show(requested.0),
            show(requested.1),
            chosen.0,
            chosen.1
        )));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_size_takes_the_calibrations() {
        assert_eq!(requested_size(0, 0, None), (0, 0));
        assert_eq!(requested_size(0, 0, Some((1280, 720))), (1280, 720));
        assert_eq!(requested_size(640, 0, Some((1280, 720))), (640, 720));
        assert_eq!(requested_size(640, 480, Some((1280, 720))), (640, 480));
    }

    #[test]
    fn a_changed_size_is_named_and_a_calibration_for_another_size_is_an_error() {
        assert_eq!(
            check_frame_size("/dev/video0", (640, 480), (640, 480), None),
            Ok(None)
        );
        assert_eq!(
            check_frame_size("/dev/video0", (0, 0), (1280, 720), None),
            Ok(None),
            "0 = the driver's choice"
        );
        let w = check_frame_size("/dev/video0", (1920, 1080), (1280, 720), None)
            .unwrap()
            .unwrap();
        assert!(
            w.contains("/dev/video0") && w.contains("1920x1080") && w.contains("1280x720"),
            "{w}"
        );
        let w = check_frame_size("/dev/video0", (1920, 0), (1280, 720), None)
            .unwrap()
            .unwrap();
        assert!(w.contains("1920xany"), "{w}");
        // Driver matches the calibration but not an explicit request: still only a warning.
        assert!(
            check_frame_size("/dev/video0", (1920, 1080), (1280, 720), Some((1280, 720)))
                .unwrap()
                .is_some()
        );
        let e = check_frame_size("/dev/video2", (1280, 720), (640, 480), Some((1280, 720)))
            .unwrap_err();
        assert_eq!(
            e,
            CaptureError::CalibrationSize {
                device: "/dev/video2".into(),
                width: 640,
                height: 480,
                cal_width: 1280,
                cal_height: 720
            }
        );
        let m = e.to_string();
        assert!(
            m.contains("/dev/video2") && m.contains("640x480") && m.contains("1280x720"),
            "{m}"
        );
    }
}
