//! Marker images identical to OpenCV's `cv::aruco::generateImageMarker`.

use super::dictionary::Dictionary;
use crate::error::{invalid, Result};
use image::GrayImage;

/// Render marker `id` as a `side_pixels`² image with a black border `border_bits` cells wide,
/// pixel-identical to `cv::aruco::generateImageMarker(dict, id, side_pixels, img, border_bits)`:
/// a one-pixel-per-cell tiny marker resized with nearest-neighbour (source index =
/// ⌊x · src/dst⌋, as OpenCV's INTER_NEAREST).
pub fn generate_marker_image(
    dict: &Dictionary,
    id: usize,
    side_pixels: u32,
    border_bits: u32,
) -> Result<GrayImage> {
    let bits = dict.bits(id)?;
    let cells = dict.marker_size as u32 + 2 * border_bits;
    if border_bits == 0 {
        return Err(invalid("border_bits", "must be at least 1"));
    }
    if side_pixels < cells {
        return Err(invalid(
            "side_pixels",
            format!("{side_pixels} is smaller than the {cells} cells of the marker"),
        ));
    }
    let cell_black = |r: u32, c: u32| -> bool {
        let inner = |v: u32| v >= border_bits && v < cells - border_bits;
        if inner(r) && inner(c) {
            !bits[(r - border_bits) as usize][(c - border_bits) as usize]
        } else {
            true
        }
    };
    // OpenCV resizeNN: ifx = 1 / (dst/src); sx = floor(x * ifx), clamped to src-1.
    let ifx = 1.0 / (side_pixels as f64 / cells as f64);
    let src_index: Vec<u32> = (0..side_pixels)
        .map(|x| ((x as f64 * ifx).floor() as u32).min(cells - 1))
        .collect();
    Ok(GrayImage::from_fn(side_pixels, side_pixels, |x, y| {
        let black = cell_black(src_index[y as usize], src_index[x as usize]);
        image::Luma([if black { 0 } else { 255 }])
    }))
}
