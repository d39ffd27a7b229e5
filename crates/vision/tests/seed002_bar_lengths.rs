//! Seed 002's measurement fixtures: T3 (the paper's ±0.578 mm error budget, and the standard
//! uncertainty it implies), T19 (the length filter) and T20 (the sign of the adaptive
//! threshold's constant: OpenCV's T = mean − C, where the paper's eqs. 5–6 print + C).

use image::GrayImage;
use metrocell_vision::bar_lengths::{
    filter_lengths, length_standard_uncertainty, worst_case_length_error,
};
use metrocell_vision::threshold::adaptive_threshold_mean;

#[test]
fn t3_error_budget() {
    let scale = 0.07226; // mm/px (T2: a 10 mm square over 138.389 px)
    assert!((worst_case_length_error(4.0, scale) - 0.57808).abs() < 5e-6);
    // the bound as a GUM standard uncertainty: two independent ends, uniform within ±4 px
    assert!((length_standard_uncertainty(4.0, scale) - 0.23600).abs() < 5e-6);
}

#[test]
fn t19_length_filter() {
    let f = filter_lengths(&[100.9, 101.2, 150.0, 100.8, 12.0, 101.0], 90.0, 110.0).unwrap();
    assert_eq!(f.kept.len(), 4);
    assert_eq!(f.rejected, [(2, 150.0), (4, 12.0)]);
    assert!((f.mean.unwrap() - 100.975).abs() < 1e-12);
}

#[test]
fn t20_adaptive_threshold_constant_is_subtracted() {
    // a uniform patch of 100 with C = 5: T = 100 − 5 = 95 (OpenCV), so every pixel (100) is
    // above T — OpenCV's THRESH_BINARY makes it foreground (white print on black); this crate's
    // mask marks dark ink (THRESH_BINARY_INV: I ≤ T), so it is 0 everywhere
    let patch = GrayImage::from_pixel(21, 21, image::Luma([100]));
    assert!(adaptive_threshold_mean(&patch, 11, 5.0)
        .iter()
        .all(|&m| m == 0));
    // with the paper's printed sign (T = mean + C = 105) the same patch would be all ink
    assert!(adaptive_threshold_mean(&patch, 11, -5.0)
        .iter()
        .all(|&m| m == 1));
    // a pixel at 94 on the 100 patch is at or below T ≈ 95 (its 11×11 mean is 99.95): ink
    let mut dot = patch.clone();
    dot.put_pixel(10, 10, image::Luma([94]));
    let mask = adaptive_threshold_mean(&dot, 11, 5.0);
    assert_eq!(mask[10 * 21 + 10], 1);
    assert_eq!(mask.iter().map(|&m| m as usize).sum::<usize>(), 1);
}
