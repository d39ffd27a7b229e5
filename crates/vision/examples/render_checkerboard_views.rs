//! Writes twin-rendered checkerboard views (10×7 squares of 10 mm → 9×6 inner corners) seen by a
//! known distorted camera, for trying `metrocell camera calibrate` and `metrocell detect`:
//!
//!   cargo run -p metrocell-vision --example render_checkerboard_views -- OUT_DIR [N_VIEWS]
//!
//! True camera: 800×600, fx 900, fy 905, cx 401.3, cy 297.8, Brown–Conrady (−0.12, 0.05, 8e-4, −6e-4, 0).

use metrocell_vision::{
    render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem,
};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(out) = args.next() else {
        eprintln!("usage: render_checkerboard_views OUT_DIR [N_VIEWS]");
        std::process::exit(2);
    };
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(12);
    std::fs::create_dir_all(&out).expect("create OUT_DIR");
    let d = Distortion::BrownConrady([-0.12, 0.05, 0.0008, -0.0006, 0.0]);
    let cam = CameraModel::new(800, 600, 900.0, 905.0, 401.3, 297.8, d).unwrap();
    let target = PlanarTarget {
        items: vec![TargetItem::Checkerboard {
            top_left: [0.0, 0.0],
            square: 0.01,
            squares_x: 10,
            squares_y: 7,
            top_left_black: true,
        }],
    };
    let settings = RenderSettings {
        noise_sigma: 1.0,
        blur_sigma_px: 0.5,
        ..Default::default()
    };
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        let rot = UnitQuaternion::from_euler_angles(
            0.35 * a.cos(),
            0.35 * a.sin(),
            0.2 * (2.0 * a).sin(),
        );
        let c = Vector3::new(0.05, 0.035, 0.0);
        let t = Vector3::new(
            0.02 * a.sin(),
            0.015 * a.cos(),
            0.16 + 0.03 * (3.0 * a).cos(),
        ) - rot * c;
        let pose = Isometry3::from_parts(Translation3::from(t), rot);
        let view = render_view(
            &cam,
            &pose,
            &target,
            &RenderSettings {
                seed: k as u64 + 1,
                ..settings
            },
        )
        .unwrap();
        let p = std::path::Path::new(&out).join(format!("view_{k:02}.png"));
        view.image.save(&p).unwrap();
    }
    println!("wrote {n} views to {out}");
}
