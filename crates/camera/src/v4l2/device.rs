//! A V4L2 capture device streaming through memory-mapped buffers: open → VIDIOC_QUERYCAP (must
//! be a capture device with streaming I/O) → VIDIOC_S_FMT (GREY or YUYV at the requested size;
//! the driver may adjust the size, never accepted silently for the pixel format) → VIDIOC_REQBUFS
//! (mmap) → VIDIOC_QUERYBUF + mmap + VIDIOC_QBUF per buffer → VIDIOC_STREAMON; each
//! [`CaptureDevice::next_frame`] polls, dequeues, converts and re-queues one buffer.

use std::ffi::CString;
use std::time::Duration;

use super::ioctl::*;
use super::pixel_format::{convert_frame, PixelFormat};
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
    /// from the monotonic clock.
    pub stamp_ns: i64,
    /// The driver's frame counter (gaps = frames the driver dropped).
    pub sequence: u32,
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

fn now_ns(clock: libc::clockid_t) -> i64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: ts is a valid out-pointer.
    unsafe { libc::clock_gettime(clock, &mut ts) };
    ts.tv_sec as i64 * 1_000_000_000 + ts.tv_nsec as i64
}

impl CaptureDevice {
    /// Open `path` and start streaming `formats` (first the driver accepts) at about `width` ×
    /// `height` (0 × 0 = the driver's current size).
    pub fn open(path: &str, width: u32, height: u32, formats: &[PixelFormat]) -> Result<CaptureDevice> {
        if !cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            return Err(CaptureError::Unsupported);
        }
        let c = CString::new(path).map_err(|_| CaptureError::Open { device: path.into(), reason: "path contains a NUL byte".into() })?;
        // SAFETY: c is a valid C string.
        let fd = unsafe { libc::open(c.as_ptr(), libc::O_RDWR | libc::O_NONBLOCK | libc::O_CLOEXEC) };
        if fd < 0 {
            return Err(CaptureError::Open { device: path.into(), reason: errno() });
        }
        // From here on, Drop closes fd (and unmaps, stops streaming) on every error path.
        let mut dev = CaptureDevice { path: path.into(), fd, buffers: Vec::new(), format: PixelFormat::Grey, width: 0, height: 0, bytes_per_line: 0, streaming: false };
        // SAFETY: all-zero is a valid v4l2_capability.
        let mut cap: Capability = unsafe { std::mem::zeroed() };
        if let Err(e) = dev.ioctl(VIDIOC_QUERYCAP, &mut cap) {
            return Err(CaptureError::NotV4l2 { device: path.into(), reason: format!("VIDIOC_QUERYCAP: {e}") });
        }
        let caps = if cap.capabilities & CAP_DEVICE_CAPS != 0 { cap.device_caps } else { cap.capabilities };
        if caps & CAP_VIDEO_CAPTURE == 0 || caps & CAP_STREAMING == 0 {
            return Err(CaptureError::NotCapture { device: path.into(), card: c_str(&cap.card), caps });
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
        self.ioctl(request, arg).map_err(|e| CaptureError::Ioctl { device: self.path.clone(), call: name, reason: e.to_string() })
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
        if names.is_empty() { "nothing it can enumerate".into() } else { names.join(", ") }
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
            f.fmt.pix = PixFormat { width, height, pixelformat: code, field: FIELD_NONE, ..Default::default() };
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
        let wanted = formats.iter().map(|f| format!("{f:?}").to_uppercase()).collect::<Vec<_>>().join(" or ");
        Err(CaptureError::Format { device: self.path.clone(), wanted, offered: self.offered() })
    }

    fn start(&mut self, count: u32) -> Result<()> {
        let mut req = RequestBuffers { count, type_: BUF_TYPE_VIDEO_CAPTURE, memory: MEMORY_MMAP, ..Default::default() };
        self.call("VIDIOC_REQBUFS", VIDIOC_REQBUFS, &mut req)?;
        if req.count == 0 {
            return Err(CaptureError::Ioctl { device: self.path.clone(), call: "VIDIOC_REQBUFS", reason: "driver granted no mmap buffers".into() });
        }
        for index in 0..req.count {
            let mut b = Buffer::new(index);
            self.call("VIDIOC_QUERYBUF", VIDIOC_QUERYBUF, &mut b)?;
            // SAFETY: offset is the union member the driver fills for MEMORY_MMAP.
            let offset = unsafe { b.m.offset };
            // SAFETY: mapping a driver buffer of the length and offset QUERYBUF reported.
            let ptr = unsafe { libc::mmap(std::ptr::null_mut(), b.length as usize, libc::PROT_READ | libc::PROT_WRITE, libc::MAP_SHARED, self.fd, offset as libc::off_t) };
            if ptr == libc::MAP_FAILED {
                return Err(CaptureError::Ioctl { device: self.path.clone(), call: "mmap", reason: errno() });
            }
            self.buffers.push(Mapping { ptr, len: b.length as usize });
            self.call("VIDIOC_QBUF", VIDIOC_QBUF, &mut b)?;
        }
        let mut t = BUF_TYPE_VIDEO_CAPTURE as i32;
        self.call("VIDIOC_STREAMON", VIDIOC_STREAMON, &mut t)?;
        self.streaming = true;
        Ok(())
    }

    /// Wait up to `timeout` for the next frame; `Ok(None)` on timeout.
    pub fn next_frame(&mut self, timeout: Duration) -> Result<Option<Frame>> {
        let mut pfd = libc::pollfd { fd: self.fd, events: libc::POLLIN, revents: 0 };
        // SAFETY: one valid pollfd.
        let r = unsafe { libc::poll(&mut pfd, 1, timeout.as_millis().min(i32::MAX as u128) as i32) };
        if r < 0 {
            let e = std::io::Error::last_os_error();
            return if e.kind() == std::io::ErrorKind::Interrupted { Ok(None) } else { Err(CaptureError::Ioctl { device: self.path.clone(), call: "poll", reason: e.to_string() }) };
        }
        if r == 0 {
            return Ok(None);
        }
        let mut b = Buffer::new(0);
        match self.ioctl(VIDIOC_DQBUF, &mut b) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return Ok(None),
            Err(e) => return Err(CaptureError::Ioctl { device: self.path.clone(), call: "VIDIOC_DQBUF", reason: e.to_string() }),
        }
        let m = &self.buffers[b.index as usize];
        // SAFETY: the buffer is dequeued (the driver does not write it) and mapped with m.len bytes.
        let bytes = unsafe { std::slice::from_raw_parts(m.ptr as *const u8, (b.bytesused as usize).min(m.len)) };
        let converted = convert_frame(self.format, self.width, self.height, self.bytes_per_line, bytes);
        let ts = b.timestamp.tv_sec as i64 * 1_000_000_000 + b.timestamp.tv_usec as i64 * 1_000;
        let stamp_ns = now_ns(libc::CLOCK_REALTIME) - (now_ns(libc::CLOCK_MONOTONIC) - ts);
        let sequence = b.sequence;
        self.call("VIDIOC_QBUF", VIDIOC_QBUF, &mut b)?;
        let (encoding, step, data) = converted?;
        Ok(Some(Frame { width: self.width, height: self.height, encoding, step, data, stamp_ns, sequence }))
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
        let e = CaptureDevice::open("/dev/video_metrocell_missing", 640, 480, &[PixelFormat::Grey]).err().unwrap();
        assert!(matches!(e, CaptureError::Open { .. }), "{e}");
        assert!(e.to_string().contains("/dev/video_metrocell_missing") && e.to_string().contains("No such file"), "{e}");
        let e = CaptureDevice::open("/dev/null", 640, 480, &[PixelFormat::Grey]).err().unwrap();
        assert!(matches!(e, CaptureError::NotV4l2 { .. }), "{e}");
        assert!(e.to_string().contains("/dev/null") && e.to_string().contains("VIDIOC_QUERYCAP"), "{e}");
        let file = std::env::temp_dir().join(format!("metrocell-v4l2-{}", std::process::id()));
        std::fs::write(&file, b"not a camera").unwrap();
        let e = CaptureDevice::open(file.to_str().unwrap(), 0, 0, &[PixelFormat::Yuyv]).err().unwrap();
        assert!(matches!(e, CaptureError::NotV4l2 { .. }), "{e}");
        std::fs::remove_file(&file).unwrap();
    }
}
