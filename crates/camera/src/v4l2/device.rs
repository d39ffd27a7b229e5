//! A V4L2 capture device streaming through memory-mapped buffers: open → VIDIOC_QUERYCAP (must
//! be a capture device with streaming I/O) → VIDIOC_S_FMT (GREY or YUYV at the requested size;
//! the driver may adjust the size, never accepted silently for the pixel format) → VIDIOC_REQBUFS
//! (mmap) → VIDIOC_QUERYBUF + mmap + VIDIOC_QBUF per buffer → VIDIOC_STREAMON; each
//! [`CaptureDevice::next_frame`] polls, dequeues, converts and re-queues one buffer (a buffer
//! the driver flags V4L2_BUF_FLAG_ERROR is re-queued without conversion: [`Dequeued::Corrupt`]).

use std::ffi::CString;
use std::time::Duration;

use super::ioctl::*;
use super::pixel_format::{convert_frame, PixelFormat};
use super::timestamp::{capture_stamp, ClockSample, StampOrigin};
use super::{CaptureError, Result};

/// One converted frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// sensor_msgs/Image encoding (`mono8` or `rgb8`), row stride and pixels.
    pub encoding: &'static str,
    pub step: u32,
    pub data: Vec<u8>,
    /// Capture instant on the system clock (ns since the epoch): the driver's timestamp moved
    /// from the monotonic clock, or the dequeue instant (see `stamp_origin`).
    pub stamp_ns: i64,
    pub stamp_origin: StampOrigin,
    /// The driver's frame counter (gaps = frames the driver dropped).
    pub sequence: u32,
}

/// One dequeued buffer.
#[derive(Debug, Clone, PartialEq)]
pub enum Dequeued {
    Frame(Frame),
    /// The driver flagged the buffer V4L2_BUF_FLAG_ERROR (data may be corrupt: lost packets, a
    /// broken transfer); it was re-queued and must not be published.
    Corrupt {
        sequence: u32,
        bytes_used: u32,
    },
}

/// Geometry of the negotiated format, what [`dequeued`] needs besides the buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    pub format: PixelFormat,
    pub width: u32,
    pub height: u32,
    pub bytes_per_line: u32,
}

/// What a dequeued buffer is: a converted frame with its stamp, or corrupt. Pure, so the error
/// and timestamp handling are tested without a camera. `data` = the first `bytesused` bytes.
pub fn dequeued(
    layout: &Layout,
    flags: u32,
    sequence: u32,
    driver_ns: i64,
    data: &[u8],
    clocks: ClockSample,
) -> Result<Dequeued> {
    if flags & BUF_FLAG_ERROR != 0 {
        return Ok(Dequeued::Corrupt {
            sequence,
            bytes_used: data.len() as u32,
        });
    }
    let data = convert_frame(
        layout.format,
        layout.width,
        layout.height,
        layout.bytes_per_line,
        data,
    )?;
    let (encoding, step) = (
        layout.format.ros_encoding(),
        layout.format.converted_step(layout.width),
    );
    let (stamp_ns, stamp_origin) = capture_stamp(flags, driver_ns, clocks);
    Ok(Dequeued::Frame(Frame {
        width: layout.width,
        height: layout.height,
        encoding,
        step,
        data,
        stamp_ns,
        stamp_origin,
        sequence,
    }))
}

struct Mapping {
    ptr: *mut libc::c_void,
    len: usize,
}

pub struct CaptureDevice {
    path: String,
    fd: libc::c_int,
    buffers: Vec<Mapping>,
    format: PixelFormat,
    width: u32,
    height: u32,
    bytes_per_line: u32,
    streaming: bool,
}

fn errno() -> String {
    std::io::Error::last_os_error().to_string()
}

fn c_str(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes.split(|&b| b == 0).next().unwrap_or(&[])).into_owned()
}

#[allow(clippy::unnecessary_cast)] // time_t is 32-bit on some targets
fn now_ns(clock: libc::clockid_t) -> i64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: ts is a valid out-pointer.
    unsafe { libc::clock_gettime(clock, &mut ts) };
    ts.tv_sec as i64 * 1_000_000_000 + ts.tv_nsec as i64
}

/// A `timeval` (the driver's buffer timestamp) in ns.
#[allow(clippy::unnecessary_cast)] // time_t and suseconds_t are 32-bit on some targets
fn timeval_ns(tv: libc::timeval) -> i64 {
    tv.tv_sec as i64 * 1_000_000_000 + tv.tv_usec as i64 * 1_000
}

impl CaptureDevice {
    /// Open `path` and start streaming `formats` (first the driver accepts) at about `width` ×
    /// `height` (0 × 0 = the driver's current size).
    pub fn open(
        path: &str,
        width: u32,
        height: u32,
        formats: &[PixelFormat],
    ) -> Result<CaptureDevice> {
        if !cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            return Err(CaptureError::Unsupported);
        }
        let c = CString::new(path).map_err(|_| CaptureError::Open {
            device: path.into(),
            reason: "path contains a NUL byte".into(),
        })?;
        // SAFETY: c is a valid C string.
        let fd = unsafe {
            libc::open(
                c.as_ptr(),
                libc::O_RDWR | libc::O_NONBLOCK | libc::O_CLOEXEC,
            )
        };
        if fd < 0 {
            return Err(CaptureError::Open {
                device: path.into(),
                reason: errno(),
            });
        }
        // From here on, Drop closes fd (and unmaps, stops streaming) on every error path.
        let mut dev = CaptureDevice {
            path: path.into(),
            fd,
            buffers: Vec::new(),
            format: PixelFormat::Grey,
            width: 0,
            height: 0,
            bytes_per_line: 0,
            streaming: false,
        };
        // SAFETY: all-zero is a valid v4l2_capability.
        let mut cap: Capability = unsafe { std::mem::zeroed() };
        if let Err(e) = dev.ioctl(VIDIOC_QUERYCAP, &mut cap) {
            return Err(CaptureError::NotV4l2 {
                device: path.into(),
                reason: format!("VIDIOC_QUERYCAP: {e}"),
            });
        }
        let caps = if cap.capabilities & CAP_DEVICE_CAPS != 0 {
            cap.device_caps
        } else {
            cap.capabilities
        };
        if caps & CAP_VIDEO_CAPTURE == 0 || caps & CAP_STREAMING == 0 {
            return Err(CaptureError::NotCapture {
                device: path.into(),
                card: c_str(&cap.card),
                caps,
            });
        }
        dev.set_format(width, height, formats)?;
        dev.start(4)?;
        Ok(dev)
    }

    pub fn format(&self) -> (PixelFormat, u32, u32) {
        (self.format, self.width, self.height)
    }

    fn ioctl<T>(&self, request: libc::c_ulong, arg: &mut T) -> std::io::Result<()> {
        loop {
            // SAFETY: arg is a live, correctly sized struct for `request` (see ioctl.rs).
            let r = unsafe { libc::ioctl(self.fd, request as _, arg as *mut T) };
            if r >= 0 {
                return Ok(());
            }
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
    }

    fn call<T>(&self, name: &'static str, request: libc::c_ulong, arg: &mut T) -> Result<()> {
        self.ioctl(request, arg).map_err(|e| CaptureError::Ioctl {
            device: self.path.clone(),
            call: name,
            reason: e.to_string(),
        })
    }

    /// The fourccs the device offers, for error messages.
    fn offered(&self) -> String {
        let mut names = Vec::new();
        for index in 0..64 {
            // SAFETY: all-zero is a valid v4l2_fmtdesc.
            let mut d: FmtDesc = unsafe { std::mem::zeroed() };
            d.index = index;
            d.type_ = BUF_TYPE_VIDEO_CAPTURE;
            if self.ioctl(VIDIOC_ENUM_FMT, &mut d).is_err() {
                break;
            }
            names.push(fourcc_name(d.pixelformat));
        }
        if names.is_empty() {
            "nothing it can enumerate".into()
        } else {
            names.join(", ")
        }
    }

    fn set_format(&mut self, width: u32, height: u32, formats: &[PixelFormat]) -> Result<()> {
        for &want in formats {
            let code = match want {
                PixelFormat::Grey => PIX_FMT_GREY,
                PixelFormat::Yuyv => PIX_FMT_YUYV,
            };
            // SAFETY: all-zero is a valid v4l2_format.
            let mut f: Format = unsafe { std::mem::zeroed() };
            f.type_ = BUF_TYPE_VIDEO_CAPTURE;
            f.fmt.pix = PixFormat {
                width,
                height,
                pixelformat: code,
                field: FIELD_NONE,
                ..Default::default()
            };
            self.call("VIDIOC_S_FMT", VIDIOC_S_FMT, &mut f)?;
            // S_FMT may substitute another format; only an exact match is usable.
            let pix = f.fmt.pix;
            if pix.pixelformat == code {
                self.format = want;
                (self.width, self.height) = (pix.width, pix.height);
                self.bytes_per_line = pix.bytesperline.max(pix.width * want.bytes_per_pixel());
                return Ok(());
            }
        }
        let wanted = formats
            .iter()
            .map(|f| format!("{f:?}").to_uppercase())
            .collect::<Vec<_>>()
            .join(" or ");
        Err(CaptureError::Format {
            device: self.path.clone(),
            wanted,
            offered: self.offered(),
        })
    }

    fn start(&mut self, count: u32) -> Result<()> {
        let mut req = RequestBuffers {
            count,
            type_: BUF_TYPE_VIDEO_CAPTURE,
            memory: MEMORY_MMAP,
            ..Default::default()
        };
        self.call("VIDIOC_REQBUFS", VIDIOC_REQBUFS, &mut req)?;
        if req.count == 0 {
            return Err(CaptureError::Ioctl {
                device: self.path.clone(),
                call: "VIDIOC_REQBUFS",
                reason: "driver granted no mmap buffers".into(),
            });
        }
        for index in 0..req.count {
            let mut b = Buffer::new(index);
            self.call("VIDIOC_QUERYBUF", VIDIOC_QUERYBUF, &mut b)?;
            // SAFETY: offset is the union member the driver fills for MEMORY_MMAP.
            let offset = unsafe { b.m.offset };
            // SAFETY: mapping a driver buffer of the length and offset QUERYBUF reported.
            let ptr = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    b.length as usize,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_SHARED,
                    self.fd,
                    offset as libc::off_t,
                )
            };
            if ptr == libc::MAP_FAILED {
                return Err(CaptureError::Ioctl {
                    device: self.path.clone(),
                    call: "mmap",
                    reason: errno(),
                });
            }
            self.buffers.push(Mapping {
                ptr,
                len: b.length as usize,
            });
            self.call("VIDIOC_QBUF", VIDIOC_QBUF, &mut b)?;
        }
        let mut t = BUF_TYPE_VIDEO_CAPTURE as i32;
        self.call("VIDIOC_STREAMON", VIDIOC_STREAMON, &mut t)?;
        self.streaming = true;
        Ok(())
    }

    /// Wait up to `timeout` for the next buffer; `Ok(None)` on timeout.
    pub fn next_frame(&mut self, timeout: Duration) -> Result<Option<Dequeued>> {
        let mut pfd = libc::pollfd {
            fd: self.fd,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd.
        let r = unsafe {
            libc::poll(
                &mut pfd,
                1,
                timeout.as_millis().min(i32::MAX as u128) as i32,
            )
        };
        if r < 0 {
            let e = std::io::Error::last_os_error();
            return if e.kind() == std::io::ErrorKind::Interrupted {
                Ok(None)
            } else {
                Err(CaptureError::Ioctl {
                    device: self.path.clone(),
                    call: "poll",
                    reason: e.to_string(),
                })
            };
        }
        if r == 0 {
            return Ok(None);
        }
        let mut b = Buffer::new(0);
        match self.ioctl(VIDIOC_DQBUF, &mut b) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return Ok(None),
            Err(e) => {
                return Err(CaptureError::Ioctl {
                    device: self.path.clone(),
                    call: "VIDIOC_DQBUF",
                    reason: e.to_string(),
                })
            }
        }
        // Both clocks right after DQBUF, back to back: their offset moves the driver's
        // monotonic timestamp to the system clock (an NTP step between them is not guarded).
        let clocks = ClockSample {
            realtime_ns: now_ns(libc::CLOCK_REALTIME),
            monotonic_ns: now_ns(libc::CLOCK_MONOTONIC),
        };
        let m = &self.buffers[b.index as usize];
        // SAFETY: the buffer is dequeued (the driver does not write it) and mapped with m.len bytes.
        let bytes = unsafe {
            std::slice::from_raw_parts(m.ptr as *const u8, (b.bytesused as usize).min(m.len))
        };
        let layout = Layout {
            format: self.format,
            width: self.width,
            height: self.height,
            bytes_per_line: self.bytes_per_line,
        };
        let driver_ns = timeval_ns(b.timestamp);
        let out = dequeued(&layout, b.flags, b.sequence, driver_ns, bytes, clocks);
        // Re-queue whatever happened (a corrupt or unconvertible buffer too), else the driver
        // runs out of buffers and the stream stalls.
        self.call("VIDIOC_QBUF", VIDIOC_QBUF, &mut b)?;
        out.map(Some)
    }
}

impl Drop for CaptureDevice {
    fn drop(&mut self) {
        if self.streaming {
            let mut t = BUF_TYPE_VIDEO_CAPTURE as i32;
            let _ = self.ioctl(VIDIOC_STREAMOFF, &mut t);
        }
        for m in &self.buffers {
            // SAFETY: unmapping what start() mapped.
            unsafe { libc::munmap(m.ptr, m.len) };
        }
        // SAFETY: fd was opened by us and is closed once.
        unsafe { libc::close(self.fd) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // No camera on the build machines: these check the error paths; the streaming path is
    // untested on hardware.
    #[test]
    fn missing_and_non_v4l2_devices_are_named() {
        let e = CaptureDevice::open(
            "/dev/video_metrocell_missing",
            640,
            480,
            &[PixelFormat::Grey],
        )
        .err()
        .unwrap();
        assert!(matches!(e, CaptureError::Open { .. }), "{e}");
        assert!(
            e.to_string().contains("/dev/video_metrocell_missing")
                && e.to_string().contains("No such file"),
            "{e}"
        );
        let e = CaptureDevice::open("/dev/null", 640, 480, &[PixelFormat::Grey])
            .err()
            .unwrap();
        assert!(matches!(e, CaptureError::NotV4l2 { .. }), "{e}");
        assert!(
            e.to_string().contains("/dev/null") && e.to_string().contains("VIDIOC_QUERYCAP"),
            "{e}"
        );
        let file = std::env::temp_dir().join(format!("metrocell-v4l2-{}", std::process::id()));
        std::fs::write(&file, b"not a camera").unwrap();
        let e = CaptureDevice::open(file.to_str().unwrap(), 0, 0, &[PixelFormat::Yuyv])
            .err()
            .unwrap();
        assert!(matches!(e, CaptureError::NotV4l2 { .. }), "{e}");
        std::fs::remove_file(&file).unwrap();
    }

    const CLOCKS: ClockSample = ClockSample {
        realtime_ns: 1_700_000_000_000_000_000,
        monotonic_ns: 9_000_000_000,
    };
    const GREY_3X2: Layout = Layout {
        format: PixelFormat::Grey,
        width: 3,
        height: 2,
        bytes_per_line: 4,
    };

    #[test]
    fn error_flagged_buffers_are_corrupt_not_frames() {
        // A short (aborted) transfer flagged ERROR: reported as corrupt, not converted (the old
        // code converted it, and the size error then ended the node).
        let short = [1u8, 2, 3];
        let flags = BUF_FLAG_ERROR | BUF_FLAG_TIMESTAMP_MONOTONIC;
        assert_eq!(
            dequeued(&GREY_3X2, flags, 17, 8_000_000_000, &short, CLOCKS),
            Ok(Dequeued::Corrupt {
                sequence: 17,
                bytes_used: 3
            })
        );
        // A full-size buffer flagged ERROR is not published either (its pixels may be garbage).
        let full = [1u8, 2, 3, 0, 4, 5, 6, 0];
        assert!(matches!(
            dequeued(&GREY_3X2, flags, 18, 8_000_000_000, &full, CLOCKS),
            Ok(Dequeued::Corrupt { sequence: 18, .. })
        ));
        // The same buffer without the flag is a frame, stamped from the monotonic timestamp.
        let Ok(Dequeued::Frame(f)) = dequeued(
            &GREY_3X2,
            BUF_FLAG_TIMESTAMP_MONOTONIC,
            19,
            8_000_000_000,
            &full,
            CLOCKS,
        ) else {
            panic!("not a frame")
        };
        assert_eq!(
            (f.data, f.sequence, f.stamp_ns, f.stamp_origin),
            (
                vec![1, 2, 3, 4, 5, 6],
                19,
                CLOCKS.realtime_ns - 1_000_000_000,
                StampOrigin::DriverMonotonic
            )
        );
        // Without the flag a short buffer is still an error naming the sizes.
        assert!(dequeued(
            &GREY_3X2,
            BUF_FLAG_TIMESTAMP_MONOTONIC,
            20,
            1,
            &short,
            CLOCKS
        )
        .is_err());
    }

    #[test]
    fn frames_with_a_copied_timestamp_are_stamped_at_dequeue() {
        let full = [1u8, 2, 3, 0, 4, 5, 6, 0];
        let Ok(Dequeued::Frame(f)) =
            dequeued(&GREY_3X2, BUF_FLAG_TIMESTAMP_COPY, 1, 123, &full, CLOCKS)
        else {
            panic!("not a frame")
        };
        assert_eq!(f.stamp_ns, CLOCKS.realtime_ns);
        assert!(matches!(f.stamp_origin, StampOrigin::Dequeue { .. }));
    }
}
