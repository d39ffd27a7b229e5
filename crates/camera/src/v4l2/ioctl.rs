//! The parts of `linux/videodev2.h` the capture uses: struct layouts (64-bit Linux, checked by
//! size tests against the kernel's sizes) and ioctl request numbers (`_IOC(dir, 'V', nr, size)`).

use std::mem::size_of;

pub const CAP_VIDEO_CAPTURE: u32 = 0x0000_0001;
pub const CAP_STREAMING: u32 = 0x0400_0000;
pub const CAP_DEVICE_CAPS: u32 = 0x8000_0000;
pub const BUF_TYPE_VIDEO_CAPTURE: u32 = 1;
pub const MEMORY_MMAP: u32 = 1;
pub const FIELD_NONE: u32 = 1;

/// `v4l2_buffer.flags`: the driver marks a buffer whose data may be corrupt (e.g. lost USB
/// packets) but hands it back anyway.
pub const BUF_FLAG_ERROR: u32 = 0x0000_0040;
/// `v4l2_buffer.flags & BUF_FLAG_TIMESTAMP_MASK`: the clock of `timestamp` (see timestamp.rs).
pub const BUF_FLAG_TIMESTAMP_MASK: u32 = 0x0000_e000;
pub const BUF_FLAG_TIMESTAMP_UNKNOWN: u32 = 0x0000_0000;
pub const BUF_FLAG_TIMESTAMP_MONOTONIC: u32 = 0x0000_2000;
pub const BUF_FLAG_TIMESTAMP_COPY: u32 = 0x0000_4000;

/// `v4l2_fourcc(a, b, c, d)`.
pub const fn fourcc(code: &[u8; 4]) -> u32 {
    code[0] as u32 | (code[1] as u32) << 8 | (code[2] as u32) << 16 | (code[3] as u32) << 24
}

pub const PIX_FMT_GREY: u32 = fourcc(b"GREY");
pub const PIX_FMT_YUYV: u32 = fourcc(b"YUYV");

/// A fourcc as its four characters, for messages.
pub fn fourcc_name(v: u32) -> String {
    v.to_le_bytes()
        .iter()
        .map(|&b| {
            if b.is_ascii_graphic() || b == b' ' {
                b as char
            } else {
                '?'
            }
        })
        .collect()
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct Capability {
    pub driver: [u8; 16],
    pub card: [u8; 32],
    pub bus_info: [u8; 32],
    pub version: u32,
    pub capabilities: u32,
    pub device_caps: u32,
    pub reserved: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Default, Debug)]
pub struct PixFormat {
    pub width: u32,
    pub height: u32,
    pub pixelformat: u32,
    pub field: u32,
    pub bytesperline: u32,
    pub sizeimage: u32,
    pub colorspace: u32,
    pub priv_: u32,
    pub flags: u32,
    pub ycbcr_enc: u32,
    pub quantization: u32,
    pub xfer_func: u32,
}

/// `struct v4l2_format`: the `fmt` union is 200 bytes and 8-byte aligned on 64-bit (it holds
/// pointers in `v4l2_window`), so it starts at offset 8.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Format {
    pub type_: u32,
    pub fmt: FormatUnion,
}

#[repr(C, align(8))]
#[derive(Clone, Copy)]
pub struct FormatUnion {
    pub pix: PixFormat,
    pub raw: [u8; 200 - size_of::<PixFormat>()],
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RequestBuffers {
    pub count: u32,
    pub type_: u32,
    pub memory: u32,
    pub capabilities: u32,
    pub flags: u8,
    pub reserved: [u8; 3],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub union BufferM {
    pub offset: u32,
    pub userptr: libc::c_ulong,
    pub fd: i32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct Buffer {
    pub index: u32,
    pub type_: u32,
    pub bytesused: u32,
    pub flags: u32,
    pub field: u32,
    pub timestamp: libc::timeval,
    pub timecode: [u32; 4],
    pub sequence: u32,
    pub memory: u32,
    pub m: BufferM,
    pub length: u32,
    pub reserved2: u32,
    pub request_fd: i32,
}

impl Buffer {
    pub fn new(index: u32) -> Buffer {
        // SAFETY: all-zero is a valid value of this plain C struct.
        let mut b: Buffer = unsafe { std::mem::zeroed() };
        b.index = index;
        b.type_ = BUF_TYPE_VIDEO_CAPTURE;
        b.memory = MEMORY_MMAP;
        b
    }
}

/// `struct v4l2_fmtdesc` (VIDIOC_ENUM_FMT), to name what a device offers.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct FmtDesc {
    pub index: u32,
    pub type_: u32,
    pub flags: u32,
    pub description: [u8; 32],
    pub pixelformat: u32,
    pub mbus_code: u32,
    pub reserved: [u32; 3],
}

const fn ioc(dir: u32, nr: u32, size: usize) -> libc::c_ulong {
    ((dir << 30) | ((size as u32) << 16) | ((b'V' as u32) << 8) | nr) as libc::c_ulong
}
const WRITE: u32 = 1;
const READ: u32 = 2;

pub const VIDIOC_QUERYCAP: libc::c_ulong = ioc(READ, 0, size_of::<Capability>());
pub const VIDIOC_ENUM_FMT: libc::c_ulong = ioc(READ | WRITE, 2, size_of::<FmtDesc>());
pub const VIDIOC_S_FMT: libc::c_ulong = ioc(READ | WRITE, 5, size_of::<Format>());
pub const VIDIOC_REQBUFS: libc::c_ulong = ioc(READ | WRITE, 8, size_of::<RequestBuffers>());
pub const VIDIOC_QUERYBUF: libc::c_ulong = ioc(READ | WRITE, 9, size_of::<Buffer>());
pub const VIDIOC_QBUF: libc::c_ulong = ioc(READ | WRITE, 15, size_of::<Buffer>());
pub const VIDIOC_DQBUF: libc::c_ulong = ioc(READ | WRITE, 17, size_of::<Buffer>());
pub const VIDIOC_STREAMON: libc::c_ulong = ioc(WRITE, 18, size_of::<i32>());
pub const VIDIOC_STREAMOFF: libc::c_ulong = ioc(WRITE, 19, size_of::<i32>());

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_and_request_numbers_match_the_kernel_header() {
        // sizeof() and the request numbers from <linux/videodev2.h> on x86_64 Linux (a C program
        // printing them, run when this was written).
        assert_eq!(size_of::<Capability>(), 104);
        assert_eq!(size_of::<Format>(), 208);
        assert_eq!(size_of::<RequestBuffers>(), 20);
        assert_eq!(size_of::<Buffer>(), 88);
        assert_eq!(size_of::<FmtDesc>(), 64);
        assert_eq!(VIDIOC_QUERYCAP, 0x8068_5600);
        assert_eq!(VIDIOC_S_FMT, 0xc0d0_5605);
        assert_eq!(VIDIOC_REQBUFS, 0xc014_5608);
        assert_eq!(VIDIOC_QUERYBUF, 0xc058_5609);
        assert_eq!(VIDIOC_QBUF, 0xc058_560f);
        assert_eq!(VIDIOC_DQBUF, 0xc058_5611);
        assert_eq!(VIDIOC_STREAMON, 0x4004_5612);
        assert_eq!(VIDIOC_ENUM_FMT, 0xc040_5602);
        assert_eq!(PIX_FMT_YUYV, 0x5659_5559);
        assert_eq!(fourcc_name(PIX_FMT_GREY), "GREY");
        // Buffer flags, as #defined in /usr/include/linux/videodev2.h (Linux 6.x uapi).
        assert_eq!(BUF_FLAG_ERROR, 0x40);
        assert_eq!(BUF_FLAG_TIMESTAMP_MASK, 0xe000);
        assert_eq!(
            (
                BUF_FLAG_TIMESTAMP_UNKNOWN,
                BUF_FLAG_TIMESTAMP_MONOTONIC,
                BUF_FLAG_TIMESTAMP_COPY
            ),
            (0, 0x2000, 0x4000)
        );
    }
}
