//! One image file → sensor_msgs/Image. Grey 8-bit → mono8, grey 16-bit → mono16 (little-endian),
//! 8-bit colour → rgb8 (alpha dropped), 16-bit colour → mono16 (luma). Header left for the caller.

use image::DynamicImage;
use metrocell_msgs::sensor_msgs::msg::Image;
use std::path::Path;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
#[error("{path}: {reason}")]
pub struct ImageFileError {
    pub path: String,
    pub reason: String,
}

/// Decode `path` (format from its content) into an Image message.
pub fn read_image_file(path: &Path) -> Result<Image, ImageFileError> {
    let err = |reason: String| ImageFileError {
        path: path.display().to_string(),
        reason,
    };
    let reader = image::ImageReader::open(path).map_err(|e| err(format!("cannot open ({e})")))?;
    let reader = reader
        .with_guessed_format()
        .map_err(|e| err(format!("cannot read ({e})")))?;
    let img = reader
        .decode()
        .map_err(|e| err(format!("cannot decode ({e})")))?;
    if img.width() == 0 || img.height() == 0 {
        return Err(err("empty image".into()));
    }
    Ok(image_message(img))
}

/// Convert a decoded image (see the module doc for the encodings).
pub fn image_message(img: DynamicImage) -> Image {
    let (width, height) = (img.width(), img.height());
    let (encoding, step, data) = match img {
        DynamicImage::ImageLuma8(g) => ("mono8", width, g.into_raw()),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA16(_)
        | DynamicImage::ImageRgb16(_)
        | DynamicImage::ImageRgba16(_) => {
            let g = img.to_luma16();
            (
                "mono16",
                2 * width,
                g.into_raw().iter().flat_map(|v| v.to_le_bytes()).collect(),
            )
        }
        DynamicImage::ImageLumaA8(_) => ("mono8", width, img.to_luma8().into_raw()),
        other => ("rgb8", 3 * width, other.to_rgb8().into_raw()),
    };
    Image {
        height,
        width,
        encoding: encoding.into(),
        is_bigendian: 0,
        step,
        data,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_decode_to_the_right_encodings_and_bad_files_are_named() {
        let dir =
            std::env::temp_dir().join(format!("metrocell-camera-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let g16 = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(3, 2, |x, y| {
            image::Luma([(x * 1000 + y) as u16])
        });
        let p16 = dir.join("g16.tiff");
        g16.save(&p16).unwrap();
        let m = read_image_file(&p16).unwrap();
        assert_eq!(
            (m.encoding.as_str(), m.width, m.height, m.step),
            ("mono16", 3, 2, 6)
        );
        assert_eq!(&m.data[..6], &[0, 0, 0xe8, 0x03, 0xd0, 0x07]);
        let rgb = image::RgbImage::from_fn(2, 2, |x, _| image::Rgb([x as u8, 7, 9]));
        let prgb = dir.join("c.png");
        rgb.save(&prgb).unwrap();
        let m = read_image_file(&prgb).unwrap();
        assert_eq!((m.encoding.as_str(), m.step, m.data.len()), ("rgb8", 6, 12));
        let pj = dir.join("g.jpg");
        image::GrayImage::from_pixel(8, 8, image::Luma([128]))
            .save(&pj)
            .unwrap();
        assert_eq!(read_image_file(&pj).unwrap().encoding, "mono8");
        // Truncated PNG: an error naming the file.
        let bytes = std::fs::read(&prgb).unwrap();
        let pt = dir.join("truncated.png");
        std::fs::write(&pt, &bytes[..bytes.len() / 2]).unwrap();
        let e = read_image_file(&pt).unwrap_err();
        assert!(e.to_string().contains("truncated.png"), "{e}");
        let e = read_image_file(&dir.join("missing.png")).unwrap_err();
        assert!(
            e.to_string().contains("missing.png") && e.to_string().contains("cannot open"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
