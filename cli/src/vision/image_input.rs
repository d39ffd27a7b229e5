//! Image files → 8-bit grey for the detectors, with errors naming the file.

use metrocell_physics::units::{parse_quantity, split_quantity};
use std::path::Path;

/// Decode `path` (PNG, JPEG, TIFF; 8 or 16 bit; grey or colour) to 8-bit grey. 16-bit images are
/// scaled so their brightest pixel maps to 255 (as the fiducial node does for mono16).
pub fn load_gray(path: &Path) -> anyhow::Result<image::GrayImage> {
    let img = image::ImageReader::open(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot open ({e})", path.display()))?
        .with_guessed_format()
        .map_err(|e| anyhow::anyhow!("{}: cannot read ({e})", path.display()))?
        .decode()
        .map_err(|e| anyhow::anyhow!("{}: cannot decode ({e})", path.display()))?;
    let is16 = matches!(
        img.color().bytes_per_pixel() / img.color().channel_count(),
        2
    );
    if is16 {
        let g = img.to_luma16();
        let max = g.as_raw().iter().copied().max().unwrap_or(0).max(1) as f64;
        let raw = g
            .as_raw()
            .iter()
            .map(|&v| (v as f64 * 255.0 / max).round() as u8)
            .collect();
        return Ok(image::GrayImage::from_raw(g.width(), g.height(), raw).expect("same size"));
    }
    Ok(img.to_luma8())
}

/// A calibrated camera for measuring in photos: its calibration file read, and every photo
/// checked to be at the resolution it was calibrated at.
pub struct CalibratedCamera {
    pub model: metrocell_camera_model::CameraModel,
    size: (u32, u32),
}

impl CalibratedCamera {
    /// Reads `path` (ROS camera_info YAML), saying how to make one when it cannot.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        use anyhow::Context;
        let info = metrocell_camera_model::CameraInfo::load(path).with_context(|| {
            format!(
                "reading the camera calibration {} (make it with `metrocell camera calibrate`)",
                path.display()
            )
        })?;
        let model = info
            .to_model()
            .with_context(|| format!("the camera calibration {}", path.display()))?;
        Ok(Self {
            model,
            size: (info.image_width, info.image_height),
        })
    }

    /// The camera of a recorded `sensor_msgs/CameraInfo` (the camera node publishes the
    /// calibration file's; the file's parameter covariance does not travel).
    pub fn from_msg(info: &metrocell_msgs::sensor_msgs::msg::CameraInfo) -> anyhow::Result<Self> {
        Ok(Self {
            model: metrocell_camera_model::camera_model_from_msg(info)?,
            size: (info.width, info.height),
        })
    }

    /// The photo at `path` in 8-bit grey, refused when its size is not the calibration's.
    pub fn photo(&self, path: &Path) -> anyhow::Result<image::GrayImage> {
        let img = load_gray(path)?;
        self.check_size(&img, &path.display().to_string())?;
        Ok(img)
    }

    /// Refuses a photo (named `what`) whose size is not the calibration's.
    pub fn check_size(&self, img: &image::GrayImage, what: &str) -> anyhow::Result<()> {
        if (img.width(), img.height()) != self.size {
            anyhow::bail!(
                "{what}: {}×{} px, but the camera was calibrated at {}×{} px: photograph at the \
                 calibrated resolution (or calibrate at this one)",
                img.width(),
                img.height(),
                self.size.0,
                self.size.1
            );
        }
        Ok(())
    }
}

/// "10mm", "0.01m", "1cm", "25.4 mm" → metres, through the workspace's unit table
/// (`metrocell_physics::units`); a bare number is millimetres.
pub fn parse_length(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let text = if split_quantity(t).1.is_empty() {
        format!("{t} mm")
    } else {
        t.to_string()
    };
    let v = parse_quantity(&text, "m")
        .map_err(|_| format!("`{s}` is not a length (e.g. 10mm, 0.01m)"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("`{s}` must be a positive length"));
    }
    Ok(v)
}

/// "9x6" → (9, 6) inner corners.
pub fn parse_board(s: &str) -> Result<(usize, usize), String> {
    parse_grid(s, "inner corners", "9x6", 2)
}

/// "6x6" → (6, 6) squares (a hole plate: one hole per square).
pub fn parse_squares(s: &str) -> Result<(usize, usize), String> {
    parse_grid(s, "squares", "6x6", 3)
}

fn parse_grid(s: &str, what: &str, example: &str, least: usize) -> Result<(usize, usize), String> {
    let (a, b) = s
        .to_ascii_lowercase()
        .split_once('x')
        .map(|(a, b)| (a.trim().to_string(), b.trim().to_string()))
        .ok_or_else(|| format!("`{s}`: expected COLSxROWS {what}, e.g. {example}"))?;
    let (c, r) = (
        a.parse::<usize>()
            .map_err(|_| format!("`{s}`: bad column count"))?,
        b.parse::<usize>()
            .map_err(|_| format!("`{s}`: bad row count"))?,
    );
    if c < least || r < least {
        return Err(format!("`{s}`: need at least {least}x{least} {what}"));
    }
    Ok((c, r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_and_boards_parse() {
        assert_eq!(parse_length("10mm").unwrap(), 0.01);
        assert_eq!(parse_length("0.025m").unwrap(), 0.025);
        assert_eq!(parse_length("2.5cm").unwrap(), 0.025);
        assert_eq!(parse_length("12").unwrap(), 0.012);
        assert!(parse_length("-1mm").is_err() && parse_length("ten").is_err());
        assert_eq!(parse_length("25 um").unwrap(), 25e-6);
        // m is metres and min minutes in the one unit table: a duration is not a length
        assert!(parse_length("5min").is_err() && parse_length("3 mrad").is_err());
        assert_eq!(parse_board("9x6").unwrap(), (9, 6));
        assert!(parse_board("9").is_err() && parse_board("1x6").is_err());
    }
}
