//! A marker seen square-on repeats its depth within the σ its pose states while it slides
//! across the renderer's supersampling grid.
//!
//! The scene is the demo's tool camera (`demo_shift.yaml`: 640×480, f = 800 px, 20 mm markers
//! 150 mm in front of it, 15 mm off-axis, ≈ 107 px wide) rendered as the twin renders its
//! frames (crates/sim `FrameRendering::default()`: supersampling 4, 0.8 px blur, 1 grey level
//! of noise). The plate slides sideways in its own plane by 0–48 µm, which is 0–0.26 px: every
//! edge of the marker crosses a column (or row) of an s = 4 sample grid somewhere in that
//! range, while the marker's depth stays 150 mm. A renderer that rounds an edge square to its
//! pixel grid to the grid's 1/s px showed the depth jumping ≈ 250 µm between neighbouring
//! positions (the bimodal depth of the demo's camera summary); an exact one leaves only the
//! noise, which the stated σ covers.

use metrocell_vision::aruco::{DetectorParams, Dictionary};
use metrocell_vision::{
    detect_targets, render_view, CameraModel, Distortion, PlanarTarget, PoseInputs, RenderSettings,
    TargetFamily, TargetItem,
};
use nalgebra::Isometry3;

const SIDE: f64 = 0.020;
const STANDOFF: f64 = 0.150;
/// Allowed sample standard deviation of the depth over the frames, in stated σ (a few tens of
/// frames estimate a standard deviation to ~15 %).
const STD_IN_SIGMAS: f64 = 1.5;
/// Allowed range (max − min) of the depth over the frames, in stated σ.
const RANGE_IN_SIGMAS: f64 = 6.0;

#[test]
fn depth_repeats_within_the_stated_sigma_as_the_marker_crosses_the_sample_grid() {
    let camera = CameraModel::new(
        640,
        480,
        800.0,
        800.0,
        319.5,
        239.5,
        Distortion::BrownConrady([0.0; 5]),
    )
    .unwrap();
    let dictionary = Dictionary::predefined("DICT_4X4_50").unwrap();
    // The demo plate's marker 0: top-left at (−25, −25) mm, so its centre is 15 mm off-axis in x and y.
    let target = PlanarTarget {
        items: vec![TargetItem::Marker {
            dictionary,
            id: 0,
            top_left: [-0.025, -0.025],
            side: SIDE,
            border_bits: 1,
        }],
    };
    let family = TargetFamily::parse("DICT_4X4_50", None, None).unwrap();
    let params = DetectorParams {
        threads: 1,
        ..Default::default()
    };
    let (mut depths, mut sigmas) = (Vec::new(), Vec::new());
    for step in 0..13 {
        let shift = 4e-6 * step as f64;
        let pose = Isometry3::translation(shift, 0.5 * shift, STANDOFF);
        for seed in 1..=3 {
            let settings = RenderSettings {
                supersampling: 4,
                blur_sigma_px: 0.8,
                noise_sigma: 1.0,
                seed,
                ..RenderSettings::default()
            };
            let view = render_view(&camera, &pose, &target, &settings).unwrap();
            let found = detect_targets(
                &view.image,
                &family,
                &params,
                Some(PoseInputs {
                    camera: &camera,
                    marker_side: Some(SIDE),
                    fallback_sigma_px: 0.1,
                    intrinsics_covariance: None,
                }),
            )
            .unwrap();
            let marker = found
                .iter()
                .find(|t| t.id == 0)
                .expect("the marker is found");
            let p = marker.pose.as_ref().expect("the marker has a pose");
            depths.push(p.position[2]);
            sigmas.push(p.covariance[14].sqrt());
        }
    }
    let n = depths.len() as f64;
    let mean = depths.iter().sum::<f64>() / n;
    let std = (depths.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let range = depths.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - depths.iter().cloned().fold(f64::INFINITY, f64::min);
    sigmas.sort_by(f64::total_cmp);
    let sigma = sigmas[sigmas.len() / 2];
    println!("{} frames: depth {:.1} µm from the truth on average, std {:.1} µm, range {:.1} µm; stated σ {:.1} µm", depths.len(), (mean - STANDOFF) * 1e6, std * 1e6, range * 1e6, sigma * 1e6);
    assert!(
        std < STD_IN_SIGMAS * sigma,
        "depth std {:.1} µm against a stated σ of {:.1} µm",
        std * 1e6,
        sigma * 1e6
    );
    assert!(
        range < RANGE_IN_SIGMAS * sigma,
        "depth range {:.1} µm against a stated σ of {:.1} µm",
        range * 1e6,
        sigma * 1e6
    );
}
