//! Raw camera buffers → the byte layouts of sensor_msgs/Image encodings `mono8` and `rgb8`.
//!
//! * GREY (V4L2 `V4L2_PIX_FMT_GREY`, 8-bit luma) → mono8: rows copied without the driver's
//!   line padding (`bytes_per_line` ≥ width).
//! * YUYV (`V4L2_PIX_FMT_YUYV`, 4:2:2, bytes Y0 U Y1 V per pixel pair) → rgb8 with ITU-R BT.601
//!   limited range (Y 16–235, Cb/Cr 16–240), the colorspace V4L2 webcams report for YUYV
//!   (SMPTE 170M) and what OpenCV's `COLOR_YUV2RGB_YUYV` assumes: 8-bit fixed point
//!   R = (298·(Y−16) + 409·(V−128) + 128) >> 8, G = (298·(Y−16) − 100·(U−128) − 208·(V−128) + 128) >> 8,
//!   B = (298·(Y−16) + 516·(U−128) + 128) >> 8, clamped to 0–255. Both pixels of a pair share U, V.

use super::{CaptureError, Result};

/// A buffer's pixel layout as the driver reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelFormat {
    Grey,
    Yuyv,
}

impl PixelFormat {
    /// Bytes per pixel in the buffer.
    pub fn bytes_per_pixel(self) -> u32 {
        match self {
            PixelFormat::Grey => 1,
            PixelFormat::Yuyv => 2,
        }
    }

    /// The sensor_msgs/Image encoding the conversion produces.
    pub fn ros_encoding(self) -> &'static str {
        match self {
            PixelFormat::Grey => "mono8",
            PixelFormat::Yuyv => "rgb8",
        }
    }

    /// Row length in bytes of the converted image (rows are packed: no padding).
    pub fn converted_step(self, width: u32) -> u32 {
        match self {
            PixelFormat::Grey => width,
            PixelFormat::Yuyv => 3 * width,
        }
    }
}

fn check(
    format: PixelFormat,
    width: u32,
    height: u32,
    bytes_per_line: u32,
    len: usize,
) -> Result<()> {
    let bad = |reason: String| CaptureError::Frame(format!("{format:?} frame: {reason}"));
    if width == 0 || height == 0 {
        return Err(bad(format!("empty frame {width}x{height}")));
    }
    if format == PixelFormat::Yuyv && width % 2 != 0 {
        return Err(bad(format!(
            "YUYV width {width} is odd (pixels come in pairs)"
        )));
    }
    if (bytes_per_line as u64) < width as u64 * format.bytes_per_pixel() as u64 {
        return Err(bad(format!(
            "bytes_per_line {bytes_per_line} < width {width} × {} B",
            format.bytes_per_pixel()
        )));
    }
    let need = bytes_per_line as usize * (height as usize - 1)
        + (width * format.bytes_per_pixel()) as usize;
    if len < need {
        return Err(bad(format!("buffer holds {len} B, {need} B needed for {width}x{height} with {bytes_per_line} B per line")));
    }
    Ok(())
}

/// Convert one frame to the packed rows of a sensor_msgs/Image with encoding
/// [`PixelFormat::ros_encoding`] and step [`PixelFormat::converted_step`].
pub fn convert_frame(
    format: PixelFormat,
    width: u32,
    height: u32,
    bytes_per_line: u32,
    buf: &[u8],
) -> Result<Vec<u8>> {
    check(format, width, height, bytes_per_line, buf.len())?;
    let row_bytes = (width * format.bytes_per_pixel()) as usize;
    let rows = || {
        buf.chunks(bytes_per_line as usize)
            .take(height as usize)
            .map(|r| &r[..row_bytes])
    };
    Ok(match format {
        // one copy when lines are unpadded, else one copy per line
        PixelFormat::Grey if bytes_per_line as usize == row_bytes => {
            buf[..row_bytes * height as usize].to_vec()
        }
        PixelFormat::Grey => {
            let mut out = Vec::with_capacity(row_bytes * height as usize);
            rows().for_each(|r| out.extend_from_slice(r));
            out
        }
        PixelFormat::Yuyv => {
            let mut out = Vec::with_capacity(width as usize * height as usize * 3);
            for r in rows() {
                for q in r.chunks_exact(4) {
                    let (d, e) = (q[1] as i32 - 128, q[3] as i32 - 128);
                    for luma in [q[0], q[2]] {
                        out.extend(yuv_to_rgb(luma as i32 - 16, d, e));
                    }
                }
            }
            out
        }
    })
}

fn yuv_to_rgb(c: i32, d: i32, e: i32) -> [u8; 3] {
    let clamp = |v: i32| (v >> 8).clamp(0, 255) as u8;
    [
        clamp(298 * c + 409 * e + 128),
        clamp(298 * c - 100 * d - 208 * e + 128),
        clamp(298 * c + 516 * d + 128),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BT.601 limited range in floating point, the definition the fixed-point code approximates.
    fn reference(y: f64, u: f64, v: f64) -> [f64; 3] {
        let (c, d, e) = (y - 16.0, u - 128.0, v - 128.0);
        let k = 255.0 / 219.0;
        [
            k * c + 1.402 * 255.0 / 224.0 * e,
            k * c - 0.344136 * 255.0 / 224.0 * d - 0.714136 * 255.0 / 224.0 * e,
            k * c + 1.772 * 255.0 / 224.0 * d,
        ]
        .map(|x| x.clamp(0.0, 255.0))
    }

    #[test]
    fn yuyv_matches_bt601_and_known_colours() {
        // Black, white and the BT.601 limited-range primaries.
        for (yuv, rgb) in [
            ([16, 128, 128], [0, 0, 0]),
            ([235, 128, 128], [255, 255, 255]),
            ([81, 90, 240], [255, 0, 0]),
            ([145, 54, 34], [0, 255, 0]),
            ([41, 240, 110], [0, 0, 255]),
        ] {
            let data = convert_frame(
                PixelFormat::Yuyv,
                2,
                1,
                4,
                &[yuv[0], yuv[1], yuv[0], yuv[2]],
            )
            .unwrap();
            assert_eq!((data.len(), PixelFormat::Yuyv.converted_step(2)), (6, 6));
            for (got, want) in data[..3].iter().zip(rgb) {
                assert!(
                    (*got as i32 - want).abs() <= 2,
                    "YUV {yuv:?} → {:?}, expected ≈ {rgb:?}",
                    &data[..3]
                );
            }
            assert_eq!(data[..3], data[3..], "both pixels of a pair share U, V");
        }
        // Every 8th code value against the floating-point definition: within 1 level.
        for y in (0..=255).step_by(8) {
            for u in (0..=255).step_by(8) {
                for v in (0..=255).step_by(8) {
                    let got = yuv_to_rgb(y - 16, u - 128, v - 128);
                    let want = reference(y as f64, u as f64, v as f64);
                    for k in 0..3 {
                        assert!(
                            (got[k] as f64 - want[k]).abs() <= 1.0,
                            "YUV ({y}, {u}, {v}) channel {k}: {} vs {:.2}",
                            got[k],
                            want[k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn grey_drops_line_padding_and_bad_buffers_are_named() {
        let buf = [1, 2, 3, 0xee, 4, 5, 6, 0xee];
        assert_eq!(
            convert_frame(PixelFormat::Grey, 3, 2, 4, &buf).unwrap(),
            [1, 2, 3, 4, 5, 6]
        );
        assert_eq!(
            convert_frame(PixelFormat::Grey, 4, 2, 4, &buf).unwrap(),
            buf,
            "unpadded lines: the buffer as is"
        );
        // The last line needs no padding.
        assert!(convert_frame(PixelFormat::Grey, 3, 2, 4, &buf[..7]).is_ok());
        let e = convert_frame(PixelFormat::Grey, 3, 2, 4, &buf[..6]).unwrap_err();
        assert!(
            e.to_string().contains("6 B") && e.to_string().contains("7 B"),
            "{e}"
        );
        assert!(convert_frame(PixelFormat::Yuyv, 3, 1, 6, &[0; 6])
            .unwrap_err()
            .to_string()
            .contains("odd"));
        assert!(convert_frame(PixelFormat::Yuyv, 2, 1, 2, &[0; 4])
            .unwrap_err()
            .to_string()
            .contains("bytes_per_line"));
        assert!(convert_frame(PixelFormat::Grey, 0, 1, 1, &[]).is_err());
    }
}
