//! sensor_msgs/Image → 8-bit grey image for the detectors.
//!
//! Supported encodings: mono8, mono16 (scaled so the frame's brightest pixel maps to 255, which keeps
//! 10/12-bit sensors usable), rgb8, bgr8, rgba8, bgra8 (grey = 0.299 R + 0.587 G + 0.114 B, as
//! OpenCV's cvtColor). Anything else, an empty frame or data shorter than step × height is a
//! [`FrameError`] naming the frame's problem; the node logs it and keeps running.
//!
//! mono8 (what the camera node publishes for GREY sensors) takes a fast path: a buffer copy, or
//! one row copy per line when `step` has padding; the other encodings one pixel at a time.

use image::GrayImage;
use metrocell_msgs::sensor_msgs::msg::Image;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum FrameError {
    #[error("empty frame ({width}x{height})")]
    Empty { width: u32, height: u32 },
    #[error("unsupported encoding `{0}` (supported: mono8, mono16, rgb8, bgr8, rgba8, bgra8)")]
    Encoding(String),
    #[error(
        "encoding {encoding}: step {step} B is smaller than width {width} × {bytes_per_pixel} B"
    )]
    Step {
        encoding: String,
        step: u32,
        width: u32,
        bytes_per_pixel: u32,
    },
    #[error(
        "truncated frame: {got} B of data, {expected} B expected (step {step} × height {height})"
    )]
    Truncated {
        got: usize,
        expected: usize,
        step: u32,
        height: u32,
    },
}

/// Convert one frame to grey.
pub fn gray_from_image(msg: &Image) -> Result<GrayImage, FrameError> {
    let (w, h) = (msg.width, msg.height);
    if w == 0 || h == 0 {
        return Err(FrameError::Empty {
            width: w,
            height: h,
        });
    }
    let bpp: u32 = match msg.encoding.as_str() {
        "mono8" | "8UC1" => 1,
        "mono16" | "16UC1" => 2,
        "rgb8" | "bgr8" => 3,
        "rgba8" | "bgra8" => 4,
        other => return Err(FrameError::Encoding(other.to_string())),
    };
    if (msg.step as u64) < w as u64 * bpp as u64 {
        return Err(FrameError::Step {
            encoding: msg.encoding.clone(),
            step: msg.step,
            width: w,
            bytes_per_pixel: bpp,
        });
    }
    // The last row only needs width × bpp bytes, but ROS requires step × height; insist on it.
    let expected = msg.step as usize * h as usize;
    if msg.data.len() < expected {
        return Err(FrameError::Truncated {
            got: msg.data.len(),
            expected,
            step: msg.step,
            height: h,
        });
    }
    Ok(match msg.encoding.as_str() {
        "mono8" | "8UC1" => mono8_rows(msg),
        _ => gray_per_pixel(msg, bpp),
    })
}

/// mono8 fast path: the pixels already are the grey image; copy the buffer in one piece when
/// rows are unpadded (step = width), else row by row without the `step − width` padding.
/// Requires the checks of [`gray_from_image`].
fn mono8_rows(msg: &Image) -> GrayImage {
    let (w, h, step) = (msg.width as usize, msg.height as usize, msg.step as usize);
    let data = if step == w {
        msg.data[..w * h].to_vec()
    } else {
        let mut data = Vec::with_capacity(w * h);
        for row in msg.data.chunks(step).take(h) {
            data.extend_from_slice(&row[..w]);
        }
        data
    };
    GrayImage::from_raw(msg.width, msg.height, data).expect("width × height bytes")
}

/// Any supported encoding, one pixel at a time into a preallocated buffer (the general path;
/// mono8 goes through it only in tests, as the reference for the fast path).
/// Requires the checks of [`gray_from_image`].
fn gray_per_pixel(msg: &Image, bpp: u32) -> GrayImage {
    let (w, h) = (msg.width, msg.height);
    let row = |y: u32| &msg.data[y as usize * msg.step as usize..][..(w * bpp) as usize];
    let mut data = Vec::with_capacity(w as usize * h as usize);
    match msg.encoding.as_str() {
        "mono8" | "8UC1" => {
            for y in 0..h {
                data.extend(row(y).iter().copied());
            }
        }
        "mono16" | "16UC1" => {
            let read = |b: &[u8]| {
                if msg.is_bigendian != 0 {
                    u16::from_be_bytes([b[0], b[1]])
                } else {
                    u16::from_le_bytes([b[0], b[1]])
                }
            };
            let max = (0..h)
                .flat_map(|y| row(y).chunks_exact(2).map(read))
                .max()
                .unwrap_or(0)
                .max(1) as f64;
            for y in 0..h {
                data.extend(
                    row(y)
                        .chunks_exact(2)
                        .map(|b| (read(b) as f64 * 255.0 / max).round() as u8),
                );
            }
        }
        enc => {
            let (ri, bi) = if enc.starts_with("rgb") {
                (0, 2)
            } else {
                (2, 0)
            };
            for y in 0..h {
                data.extend(row(y).chunks_exact(bpp as usize).map(|p| {
                    (0.299 * p[ri] as f64 + 0.587 * p[1] as f64 + 0.114 * p[bi] as f64).round()
                        as u8
                }));
            }
        }
    }
    GrayImage::from_raw(w, h, data).expect("width × height bytes")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(encoding: &str, w: u32, h: u32, step: u32, data: Vec<u8>) -> Image {
        Image {
            encoding: encoding.into(),
            width: w,
            height: h,
            step,
            data,
            ..Default::default()
        }
    }

    #[test]
    fn encodings_convert_and_bad_frames_name_the_problem() {
        let g = gray_from_image(&msg("mono8", 2, 2, 3, vec![1, 2, 99, 3, 4, 99])).unwrap();
        assert_eq!(g.as_raw(), &vec![1, 2, 3, 4]);
        let g = gray_from_image(&msg("rgb8", 1, 1, 3, vec![255, 0, 0])).unwrap();
        assert_eq!(g.as_raw(), &vec![76]);
        let g = gray_from_image(&msg("bgr8", 1, 1, 3, vec![255, 0, 0])).unwrap();
        assert_eq!(g.as_raw(), &vec![29]);
        let g = gray_from_image(&msg("mono16", 2, 1, 4, vec![0x00, 0x08, 0x00, 0x10])).unwrap();
        assert_eq!(g.as_raw(), &vec![128, 255]);
        let mut be = msg("mono16", 2, 1, 4, vec![0x08, 0x00, 0x10, 0x00]);
        be.is_bigendian = 1;
        assert_eq!(gray_from_image(&be).unwrap().as_raw(), &vec![128, 255]);

        assert_eq!(
            gray_from_image(&msg("mono8", 0, 0, 0, vec![])),
            Err(FrameError::Empty {
                width: 0,
                height: 0
            })
        );
        let e = gray_from_image(&msg("yuv422", 2, 2, 4, vec![0; 8])).unwrap_err();
        assert!(e.to_string().contains("yuv422"), "{e}");
        let e = gray_from_image(&msg("mono8", 4, 4, 4, vec![0; 15])).unwrap_err();
        assert_eq!(
            e,
            FrameError::Truncated {
                got: 15,
                expected: 16,
                step: 4,
                height: 4
            }
        );
        assert!(matches!(
            gray_from_image(&msg("rgb8", 4, 1, 4, vec![0; 4])),
            Err(FrameError::Step { .. })
        ));
    }

    /// Deterministic "random" bytes (an LCG), so padding bytes differ from pixels.
    fn bytes(n: usize, seed: u32) -> Vec<u8> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 24) as u8
            })
            .collect()
    }

    #[test]
    fn mono8_fast_path_equals_the_per_pixel_path() {
        // Unpadded, padded rows (step > width, as V4L2 drivers and ROS publishers with aligned
        // rows produce), one row, one column, and data longer than step × height.
        for (w, h, step, extra) in [
            (37, 23, 37, 0),
            (37, 23, 64, 0),
            (1, 5, 4, 0),
            (50, 1, 50, 0),
            (640, 480, 640, 0),
            (641, 7, 704, 13),
        ] {
            let m = msg(
                "mono8",
                w,
                h,
                step,
                bytes((step * h) as usize + extra, w * 31 + step),
            );
            let fast = gray_from_image(&m).unwrap();
            let general = gray_per_pixel(&m, 1);
            assert_eq!(fast, general, "{w}x{h} step {step}");
            // And both are the right pixels: row y starts at y · step.
            assert_eq!(
                fast.get_pixel(w - 1, h - 1)[0],
                m.data[((h - 1) * step + w - 1) as usize],
                "{w}x{h} step {step}"
            );
        }
    }

    /// Benchmark (ignored; prints ratios, asserts only equality): 1920×1080 mono8, unpadded and
    /// with 64-byte-aligned rows, fast path against two peers in the same run: the per-pixel
    /// path and the former `put_pixel` loop.
    /// Run: `cargo test --release -p metrocell-fiducial-node --lib mono8_speed -- --ignored --nocapture`
    #[test]
    #[ignore]
    fn mono8_speed() {
        let time = |f: &dyn Fn() -> GrayImage| {
            let start = std::time::Instant::now();
            let mut last = f();
            for _ in 0..19 {
                last = f();
            }
            (start.elapsed().as_secs_f64() / 20.0, last)
        };
        for step in [1920u32, 1984] {
            let m = msg("mono8", 1920, 1080, step, bytes((step * 1080) as usize, 7));
            let (fast, a) = time(&|| gray_from_image(&m).unwrap());
            let (general, b) = time(&|| gray_per_pixel(&m, 1));
            let (put, c) = time(&|| {
                let mut out = GrayImage::new(m.width, m.height);
                for y in 0..m.height {
                    for (x, &v) in m.data[(y * m.step) as usize..][..m.width as usize]
                        .iter()
                        .enumerate()
                    {
                        out.put_pixel(x as u32, y, image::Luma([v]));
                    }
                }
                out
            });
            assert!(a == b && b == c);
            println!("1920x1080 mono8 step {step}: fast {:.3} ms; per-pixel {:.3} ms ({:.1}x); put_pixel {:.3} ms ({:.1}x)", fast * 1e3, general * 1e3, general / fast, put * 1e3, put / fast);
        }
    }

    #[test]
    fn colour_and_mono16_rows_with_padding_convert_per_pixel() {
        // Every supported encoding with step > width × bpp: the padding is never read as pixels.
        for (enc, bpp) in [
            ("rgb8", 3u32),
            ("bgr8", 3),
            ("rgba8", 4),
            ("bgra8", 4),
            ("mono16", 2),
        ] {
            let (w, h) = (5u32, 3u32);
            let step = w * bpp + 3;
            let mut m = msg(enc, w, h, step, bytes((step * h) as usize, bpp));
            let padded = gray_from_image(&m).unwrap();
            // The same pixels without padding give the same image.
            m.data = (0..h)
                .flat_map(|y| m.data[(y * step) as usize..][..(w * bpp) as usize].to_vec())
                .collect();
            m.step = w * bpp;
            assert_eq!(padded, gray_from_image(&m).unwrap(), "{enc}");
        }
    }
}
