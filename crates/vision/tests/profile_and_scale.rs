//! Seed 002 figures: line-profile edges (eqs. 8–9) and the pixel scale from a checkerboard (eq. 4).
mod common;

use image::GrayImage;
use metrocell_vision::checkerboard::detect_checkerboard;
use metrocell_vision::edge_fit::normal_cdf;
use metrocell_vision::edge_profile::{find_profile_edges, sample_line_profile};
use metrocell_vision::scale::{plane_scale_from_checkerboard, scale_from_length};
use metrocell_vision::{
    render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem,
};
use nalgebra::{Isometry3, Point2};
use rand::{Rng, SeedableRng};

/// Vertical dark→bright edge at x = `e`, Gaussian blur σ_b, pixel-integrated, plus noise.
fn edge_image(e: f64, sigma_b: f64, noise: f64, seed: u64) -> GrayImage {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    GrayImage::from_fn(200, 100, |x, _| {
        let m = 32;
        let v: f64 = (0..m)
            .map(|k| normal_cdf((x as f64 - 0.5 + (k as f64 + 0.5) / m as f64 - e) / sigma_b))
            .sum::<f64>()
            / m as f64;
        let n: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
        image::Luma([(30.0 + 190.0 * v + noise * n).round().clamp(0.0, 255.0) as u8])
    })
}

/// Seed 002 eqs. 8–9: a blurred step at x = 100.3 px is located within 0.1 px, along a row and
/// along an oblique profile line.
#[test]
fn blurred_step_at_100_3_px_is_located_within_0_1_px() {
    let img = edge_image(100.3, 1.5, 2.0, 3);
    for (from, to) in [
        (Point2::new(60.0, 50.0), Point2::new(140.0, 50.0)),
        (Point2::new(62.0, 30.0), Point2::new(138.0, 72.0)),
    ] {
        let prof = sample_line_profile(&img, from, to).unwrap();
        let edges = find_profile_edges(&prof.values, 1.5, 10.0).unwrap();
        assert_eq!(edges.len(), 1, "{edges:?}");
        let x = prof.point_at(edges[0].position).x;
        eprintln!(
            "edge found at x = {x:.4} px (true 100.3), reported std {:.4} px",
            edges[0].std * prof.direction.x
        );
        assert!((x - 100.3).abs() < 0.1, "edge at {x}");
        assert!(
            edges[0].gradient > 0.0,
            "dark → bright is a positive gradient"
        );
    }
}

/// The reported std matches the scatter over 200 noise realisations within a factor 1.5.
#[test]
fn profile_edge_uncertainty_matches_scatter() {
    let mut pos = Vec::new();
    let mut stds = Vec::new();
    for seed in 0..200 {
        let img = edge_image(100.3, 1.2, 4.0, seed);
        let prof =
            sample_line_profile(&img, Point2::new(70.0, 50.0), Point2::new(130.0, 50.0)).unwrap();
        let e = find_profile_edges(&prof.values, 1.5, 10.0).unwrap();
        assert_eq!(e.len(), 1);
        pos.push(prof.point_at(e[0].position).x);
        stds.push(e[0].std);
    }
    let mean = pos.iter().sum::<f64>() / pos.len() as f64;
    let scatter =
        (pos.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (pos.len() - 1) as f64).sqrt();
    let reported = stds.iter().sum::<f64>() / stds.len() as f64;
    eprintln!(
        "profile edge: mean {mean:.4} px, scatter {scatter:.4} px, reported std {reported:.4} px"
    );
    assert!((mean - 100.3).abs() < 0.02);
    assert!(
        reported / scatter > 1.0 / 1.5 && reported / scatter < 1.5,
        "reported {reported} vs scatter {scatter}"
    );
}

/// Seed 002 eq. 4: 10 mm spanning 138.389 px gives 0.07226 mm/px; and the same scale is measured
/// on a rendered frontal 10 mm checkerboard imaged at exactly 138.389 px per square.
#[test]
fn checkerboard_scale_reproduces_0_07226_mm_per_px() {
    let s = scale_from_length(0.010, 138.389).unwrap();
    assert!((s * 1e3 - 0.07226).abs() < 5e-6, "{} mm/px", s * 1e3);
    assert!(scale_from_length(0.0, 1.0).is_err() && scale_from_length(0.01, f64::NAN).is_err());

    // f·square/Z = 1383.89 · 0.010 / 0.100 = 138.389 px per square.
    let cam = CameraModel::new(
        1280,
        960,
        1383.89,
        1383.89,
        639.5,
        479.5,
        Distortion::none(),
    )
    .unwrap();
    let target = PlanarTarget {
        items: vec![TargetItem::Checkerboard {
            top_left: [0.0, 0.0],
            square: 0.010,
            squares_x: 7,
            squares_y: 5,
            top_left_black: true,
        }],
    };
    let pose = Isometry3::translation(-0.035, -0.025, 0.100);
    let settings = RenderSettings {
        blur_sigma_px: 1.0,
        noise_sigma: 1.0,
        ..Default::default()
    };
    let view = render_view(&cam, &pose, &target, &settings).unwrap();
    let board = detect_checkerboard(&view.image, 6, 4).unwrap();
    let scale = plane_scale_from_checkerboard(&board, 0.010).unwrap();
    eprintln!(
        "checkerboard scale {:.6} mm/px ± {:.2e} (spread {:.2e}) over {} spacings",
        scale.metres_per_pixel * 1e3,
        scale.std * 1e3,
        scale.spread * 1e3,
        scale.spacings
    );
    assert_eq!(scale.spacings, 5 * 4 + 6 * 3);
    assert!((scale.metres_per_pixel * 1e3 - 0.07226).abs() < 5e-6);
    assert!(scale.std > 0.0 && scale.std * 1e3 < 5e-6);
}
