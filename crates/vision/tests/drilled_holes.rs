//! Seed 000 digest T8: a 6×6 grid of 1 mm holes drilled through a 10 mm checkerboard over an
//! inverse-contrast backing, imaged at 0.04 mm/px through a lens with barrel distortion. The hole
//! centres (true = nominal + a known "machine error" pattern of up to ±0.3 mm) are recovered in
//! board millimetres with RMS < 20 µm when the distortion is corrected; treating the same image as
//! distortion-free leaves a systematic radial bias far above that. A burr or dirt blob next to
//! every hole (and a neighbour-like blob reaching into every third window) leaves them there.

use metrocell_camera_model::{CameraModel, Distortion};
use metrocell_vision::hole_plate::measure_plate;
use metrocell_vision::holes::HoleSearch;
use metrocell_vision::{render_view, PlanarTarget, RenderSettings, TargetItem};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

const SQUARE: f64 = 0.010;
const N: usize = 6;

/// Hole positions in board metres: nominal square centres + a smooth known error field.
fn holes() -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let mut nominal = Vec::new();
    let mut truth = Vec::new();
    for j in 0..N {
        for i in 0..N {
            let (x, y) = ((i as f64 + 0.5) * SQUARE, (j as f64 + 0.5) * SQUARE);
            nominal.push([x, y]);
            // ±0.3 mm: scale error in x, squareness-like shear in y.
            truth.push([
                x + 0.004 * (x - 0.03) + 0.0001 * (j as f64 - 2.5) / 2.5,
                y + 0.003 * (x - 0.03) - 0.0001,
            ]);
        }
    }
    (nominal, truth)
}

/// The holes' board positions (m), row-major, through `vision::hole_plate` (the camera `cam`),
/// and the largest σ it states for one.
fn measure_with_sigma(
    image: &image::GrayImage,
    cam: &CameraModel,
    nominal: &[[f64; 2]],
) -> (Vec<[f64; 2]>, f64) {
    let plate = measure_plate(image, cam, N, N, SQUARE, &HoleSearch::default())
        .unwrap()
        .expect("the board is in the picture");
    assert!(plate.rejected.is_empty(), "{:?}", plate.rejected);
    assert!(
        (plate.mm_per_px - 0.04).abs() < 0.004,
        "{} mm/px",
        plate.mm_per_px
    );
    assert_eq!(plate.holes.len(), nominal.len());
    let mut largest: f64 = 0.0;
    let positions = plate
        .holes
        .iter()
        .zip(nominal)
        .map(|(h, n)| {
            assert_eq!(&h.nominal, n);
            largest = largest.max(h.covariance.trace().sqrt());
            h.measured
        })
        .collect();
    (positions, largest)
}

/// [`measure_with_sigma`] with a camera model that fits: every σ a few µm, not zero (a well-lit
/// 1 mm hole at 0.04 mm/px).
fn measure(image: &image::GrayImage, cam: &CameraModel, nominal: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let (positions, sigma) = measure_with_sigma(image, cam, nominal);
    assert!(sigma > 1e-7 && sigma < 20e-6, "σ {sigma} m");
    positions
}

/// The T8 plate seen at 0.04 mm/px (f = 2500 px at 0.1 m, barrel distortion), holes at `truth`,
/// with `extra` items painted over it (blur 0.8 px, noise 2 grey levels).
fn t8_view(truth: &[[f64; 2]], extra: Vec<TargetItem>) -> (CameraModel, image::GrayImage) {
    let dist = Distortion::BrownConrady([-0.25, 0.08, 0.0, 0.0, 0.0]);
    let cam = CameraModel::new(1700, 1700, 2500.0, 2500.0, 849.5, 849.5, dist).unwrap();
    let mut items = vec![TargetItem::Checkerboard {
        top_left: [0.0, 0.0],
        square: SQUARE,
        squares_x: N as u32,
        squares_y: N as u32,
        top_left_black: true,
    }];
    items.extend(truth.iter().map(|c| TargetItem::Hole {
        centre: *c,
        diameter: 0.001,
    }));
    items.extend(extra);
    let rot = UnitQuaternion::from_euler_angles(0.06, -0.05, 0.3);
    let t = Vector3::new(0.0, 0.0, 0.1) - rot * Vector3::new(0.03, 0.03, 0.0);
    let pose = Isometry3::from_parts(Translation3::from(t), rot);
    let settings = RenderSettings {
        blur_sigma_px: 0.8,
        noise_sigma: 2.0,
        supersampling: 8,
        ..Default::default()
    };
    (
        cam,
        render_view(&cam, &pose, &PlanarTarget { items }, &settings)
            .unwrap()
            .image,
    )
}

/// RMS and largest distance (m) of measured board positions from the truth.
fn errors(measured: &[[f64; 2]], truth: &[[f64; 2]]) -> (f64, f64) {
    let d: Vec<f64> = measured
        .iter()
        .zip(truth)
        .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
        .collect();
    (
        (d.iter().map(|e| e * e).sum::<f64>() / d.len() as f64).sqrt(),
        d.iter().cloned().fold(0.0, f64::max),
    )
}

#[test]
fn hole_centres_recovered_below_20_um_and_uncorrected_image_is_biased() {
    let (nominal, truth) = holes();
    let (cam, image) = t8_view(&truth, Vec::new());

    let corrected = measure(&image, &cam, &nominal);
    let rms_c = errors(&corrected, &truth).0;
    println!(
        "corrected: RMS {:.2} µm over {} holes",
        rms_c * 1e6,
        corrected.len()
    );
    assert!(rms_c < 20e-6, "corrected RMS {:.2} µm ≥ 20 µm", rms_c * 1e6);

    // Same image, distortion ignored (K only).
    let naive = CameraModel {
        distortion: Distortion::none(),
        ..cam
    };
    let (biased, naive_sigma) = measure_with_sigma(&image, &naive, &nominal);
    let rms_u = errors(&biased, &truth).0;
    // Systematic: the error grows with distance from the board centre (radial pattern), it is
    // not noise: correlation of |error| with radius.
    let c = [0.03, 0.03];
    let (r, e): (Vec<f64>, Vec<f64>) = biased
        .iter()
        .zip(&truth)
        .map(|(a, b)| {
            (
                ((b[0] - c[0]).powi(2) + (b[1] - c[1]).powi(2)).sqrt(),
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt(),
            )
        })
        .unzip();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mr, me) = (mean(&r), mean(&e));
    let cov: f64 = r.iter().zip(&e).map(|(a, b)| (a - mr) * (b - me)).sum();
    let corr = cov
        / (r.iter().map(|a| (a - mr).powi(2)).sum::<f64>()
            * e.iter().map(|b| (b - me).powi(2)).sum::<f64>())
        .sqrt();
    println!(
        "uncorrected: RMS {:.1} µm, correlation of |error| with radius {:.2}",
        rms_u * 1e6,
        corr
    );
    assert!(
        rms_u > 10.0 * rms_c && rms_u > 100e-6,
        "uncorrected RMS {:.1} µm should show the distortion bias",
        rms_u * 1e6
    );
    assert!(corr > 0.5, "bias is radial: correlation {corr:.2}");
    // and the measurement says so: with the wrong lens model the board's corners do not fit,
    // and the holes' σ (floored at the corners' reprojection RMS) grows to the bias's size
    assert!(
        naive_sigma > 0.5 * rms_u,
        "σ {:.1} µm stated against a {:.1} µm bias",
        naive_sigma * 1e6,
        rms_u * 1e6
    );
}

/// The same plate with a distractor next to every hole (0.04 mm/px, search window ±40 px =
/// ±1.6 mm): a 0.5 mm burr/dirt blob 1.1 mm from its centre (0.35 mm = 9 px clear of the 1 mm
/// hole, inside the window), in a different direction for each hole; every third hole also has a
/// 1 mm blob 2.0 mm away, reaching into the window from outside like a neighbouring hole would.
/// Merged into the hole (as the measurement once did), the burr alone moves the rough centre by
/// ≈ 5 px, enough to pull it into the moment disc: 25 µm RMS.
#[test]
fn hole_centres_stay_below_20_um_with_burrs_and_dirt_next_to_every_hole() {
    let (nominal, truth) = holes();
    let mut extra = Vec::new();
    for (k, c) in truth.iter().enumerate() {
        let a = k as f64 * 2.399_963; // golden angle: directions spread over the circle
        extra.push(TargetItem::Hole {
            centre: [c[0] + 0.0011 * a.cos(), c[1] + 0.0011 * a.sin()],
            diameter: 0.0005,
        });
        if k % 3 == 0 {
            let b = a + std::f64::consts::PI;
            extra.push(TargetItem::Hole {
                centre: [c[0] + 0.0020 * b.cos(), c[1] + 0.0020 * b.sin()],
                diameter: 0.001,
            });
        }
    }
    let (cam, image) = t8_view(&truth, extra);
    let (rms, worst) = errors(&measure(&image, &cam, &nominal), &truth);
    println!(
        "with distractors: RMS {:.2} µm, worst {:.2} µm over {} holes",
        rms * 1e6,
        worst * 1e6,
        truth.len()
    );
    assert!(rms < 20e-6, "RMS {:.2} µm ≥ 20 µm", rms * 1e6);
}
