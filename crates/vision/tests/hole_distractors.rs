//! `measure_holes` with other blobs in the search window: a burr or dirt speck next to a hole, a
//! neighbouring hole reaching into the window, a second hole-sized blob, a bright reflection.
//! The hole is the connected blob nearest the prediction; blobs clear of its measurement disc are
//! ignored, blobs that reach it or make the cell ambiguous reject the cell with a reason.
//! (Before, every blob in the window was merged into the hole: its centre moved towards the
//! distractor, or the cell was rejected because the merged blob touched the window border.)
//! The seed 000 T8 plate with a distractor next to every hole is in `drilled_holes.rs`.

use image::GrayImage;
use metrocell_vision::holes::{measure_holes, HoleRejection, HoleSearch};
use nalgebra::Point2;

/// A disc (centre, radius px, grey level) painted over `img` with exact-ish area coverage
/// (16 × 16 samples per pixel).
fn paint_disc(img: &mut GrayImage, c: [f64; 2], r: f64, level: f64) {
    let (x0, x1) = (
        (c[0] - r - 1.0).floor().max(0.0) as u32,
        ((c[0] + r + 1.0).ceil() as u32).min(img.width() - 1),
    );
    let (y0, y1) = (
        (c[1] - r - 1.0).floor().max(0.0) as u32,
        ((c[1] + r + 1.0).ceil() as u32).min(img.height() - 1),
    );
    for y in y0..=y1 {
        for x in x0..=x1 {
            let mut inside = 0;
            for j in 0..16 {
                for i in 0..16 {
                    let (sx, sy) = (
                        x as f64 - 0.5 + (i as f64 + 0.5) / 16.0,
                        y as f64 - 0.5 + (j as f64 + 0.5) / 16.0,
                    );
                    inside += ((sx - c[0]).powi(2) + (sy - c[1]).powi(2) <= r * r) as u32;
                }
            }
            let cover = inside as f64 / 256.0;
            let v = img.get_pixel(x, y)[0] as f64 * (1.0 - cover) + level * cover;
            img.put_pixel(x, y, image::Luma([v.round() as u8]));
        }
    }
}

const HOLE: [f64; 2] = [60.3, 59.6];
const R: f64 = 8.0;

/// A dark hole of radius 8 px at `HOLE` on a white background, plus `extra` discs.
fn scene(extra: &[([f64; 2], f64, f64)]) -> GrayImage {
    let mut img = GrayImage::from_pixel(120, 120, image::Luma([200]));
    paint_disc(&mut img, HOLE, R, 30.0);
    for &(c, r, level) in extra {
        paint_disc(&mut img, c, r, level);
    }
    img
}

fn search() -> HoleSearch {
    HoleSearch {
        window_half_px: 30,
        ..Default::default()
    }
}

fn measure(img: &GrayImage) -> Result<Point2<f64>, HoleRejection> {
    // Prediction 1.5 px off the true centre, as from a board pose.
    let r = measure_holes(img, &[Point2::new(HOLE[0] + 1.2, HOLE[1] - 0.9)], &search()).unwrap();
    r.into_iter().next().unwrap().map(|h| h.centre)
}

fn error_px(c: Point2<f64>) -> f64 {
    ((c.x - HOLE[0]).powi(2) + (c.y - HOLE[1]).powi(2)).sqrt()
}

#[test]
fn blobs_clear_of_the_hole_are_ignored() {
    let clean = error_px(measure(&scene(&[])).unwrap());
    assert!(clean < 0.02, "no distractor: error {clean:.4} px");
    let cases = [
        // Dirt speck (r 3 px, area 28 px² ≥ min_area) 20 px from the centre: its edge is 6 px
        // clear of the moment disc (radius 8 + 3 px margin).
        ("dark speck", [HOLE[0] + 20.0, HOLE[1] + 3.0], 3.0, 10.0),
        // A burr: larger than min_area, below half the hole's area, same polarity.
        ("burr", [HOLE[0] - 13.0, HOLE[1] - 15.0], 4.0, 40.0),
        // A neighbouring hole reaching into the window from outside it (touches the border).
        ("neighbour", [HOLE[0] + 36.0, HOLE[1]], R, 30.0),
        // A bright reflection stronger than the hole's contrast: must not flip the polarity.
        ("bright burr", [HOLE[0] - 18.0, HOLE[1] + 10.0], 4.0, 255.0),
    ];
    for (what, c, r, level) in cases {
        let got =
            measure(&scene(&[(c, r, level)])).unwrap_or_else(|e| panic!("{what}: rejected ({e})"));
        let e = error_px(got);
        println!("{what}: centre error {e:.4} px");
        assert!(
            e < 0.02,
            "{what}: centre error {e:.4} px (clean image {clean:.4} px)"
        );
    }
}

#[test]
fn blobs_that_reach_the_measurement_or_compete_reject_the_cell() {
    // A speck 2 px from the hole's edge: inside the moment disc (radius 8 + 3 px margin).
    let e = measure(&scene(&[([HOLE[0] + R + 4.0, HOLE[1]], 2.0, 10.0)])).unwrap_err();
    assert!(
        matches!(e, HoleRejection::BlobTooClose { gap_px } if gap_px < 3.0),
        "{e:?}"
    );
    // A bright reflection touching the disc: opposite polarity, still too close.
    let e = measure(&scene(&[([HOLE[0], HOLE[1] + R + 3.0], 2.0, 255.0)])).unwrap_err();
    assert!(matches!(e, HoleRejection::BlobTooClose { .. }), "{e:?}");
    // A second hole of the same size wholly inside the window: which one is the cell's hole?
    let e = measure(&scene(&[([HOLE[0] - 19.0, HOLE[1] + 2.0], R, 30.0)])).unwrap_err();
    assert_eq!(e, HoleRejection::SeveralBlobs { blobs: 2 });
    assert!(e.to_string().contains("ambiguous"), "{e}");
}
