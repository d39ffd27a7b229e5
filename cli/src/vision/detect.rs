//! `metrocell detect IMAGE... --family F [--json]`: find fiducials in image files.

use std::path::PathBuf;

use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets_explained, PoseInputs, Target, TargetFamily};

use super::image_input::{load_gray, parse_board, parse_length};

#[derive(clap::Args)]
#[command(
    after_help = "Examples:\n  metrocell detect frame.png --family DICT_4X4_50\n  metrocell detect views/*.png --family checkerboard --board 9x6 --square 10mm --json\n  metrocell detect frame.png --family DICT_6X6_250 --camera-info camera_info.yaml --marker-size 20mm"
)]
pub struct DetectArgs {
    /// Image files (PNG, JPEG, TIFF; 8/16-bit)
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
    /// OpenCV dictionary (DICT_4X4_50, DICT_APRILTAG_36h11, ...) or `checkerboard`
    #[arg(long)]
    pub family: String,
    /// Checkerboard inner corners, COLSxROWS
    #[arg(long, value_parser = parse_board)]
    pub board: Option<(usize, usize)>,
    /// Checkerboard square side (e.g. 10mm)
    #[arg(long, value_parser = parse_length)]
    pub square: Option<f64>,
    /// Marker side (e.g. 20mm), for marker poses
    #[arg(long, value_parser = parse_length)]
    pub marker_size: Option<f64>,
    /// ROS camera_info YAML; with it, poses with covariance are reported (including the
    /// calibration's own uncertainty when the file states it, as `camera calibrate` writes it)
    #[arg(long)]
    pub camera_info: Option<PathBuf>,
    /// One JSON object per image instead of text (SI units: px, m, rad)
    #[arg(long)]
    pub json: bool,
}

fn target_json(t: &Target) -> serde_json::Value {
    serde_json::json!({
        "id": t.id,
        "corners": t.corners.iter().map(|c| [c.x, c.y]).collect::<Vec<_>>(),
        "corner_std_px": t.corner_covariance.iter().map(|c| [c[(0, 0)].sqrt(), c[(1, 1)].sqrt()]).collect::<Vec<_>>(),
        "decision_margin": t.decision_margin,
        "pose": t.pose.as_ref().map(|p| serde_json::json!({
            "position_m": p.position, "orientation_xyzw": p.orientation,
            "covariance": p.covariance.to_vec(), "reprojection_rms_px": p.reprojection_rms_px,
        })),
    })
}

/// Exit code 0 when every image was read (with or without targets), 1 when some could not be, 2 on bad arguments.
pub fn run(args: DetectArgs) -> i32 {
    let family = match TargetFamily::parse(&args.family, args.board, args.square) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("metrocell detect: --family: {e}");
            return 2;
        }
    };
    let (camera, intrinsics_covariance) = match &args.camera_info {
        None => (None, None),
        Some(p) => match metrocell_camera_model::CameraInfo::load(p)
            .and_then(|c| Ok((c.to_model()?, c.intrinsics_covariance()?)))
        {
            Ok((c, cov)) => {
                if cov.is_none() {
                    eprintln!("{}: states no intrinsics_covariance; pose σ count the corner noise only (write the file with `metrocell camera calibrate` to include the calibration's uncertainty)", p.display());
                }
                (Some(c), cov)
            }
            Err(e) => {
                eprintln!("metrocell detect: --camera-info: {e}");
                return 2;
            }
        },
    };
    let name = family.message_name();
    let params = DetectorParams::default();
    let mut failed = 0;
    for path in &args.images {
        let result = load_gray(path).and_then(|img| {
            let pose = camera
                .as_ref()
                .filter(|c| c.width == img.width() && c.height == img.height())
                .map(|c| PoseInputs {
                    camera: c,
                    marker_side: args.marker_size,
                    fallback_sigma_px: 0.1,
                    intrinsics_covariance: intrinsics_covariance.as_ref(),
                });
            if camera.is_some() && pose.is_none() {
                eprintln!(
                    "{}: image size {}x{} differs from camera_info; no poses",
                    path.display(),
                    img.width(),
                    img.height()
                );
            }
            Ok((
                img.width(),
                img.height(),
                detect_targets_explained(&img, &family, &params, pose)?,
            ))
        });
        match result {
            Ok((w, h, detection)) => {
                let targets = &detection.targets;
                if args.json {
                    let v = serde_json::json!({"image": path.display().to_string(), "width": w, "height": h, "family": name,
                        "detections": targets.iter().map(target_json).collect::<Vec<_>>(), "not_found": detection.not_found});
                    println!("{v}");
                } else {
                    match &detection.not_found {
                        Some(why) => println!(
                            "{}: {} {name} target(s): {why}",
                            path.display(),
                            targets.len()
                        ),
                        None => println!("{}: {} {name} target(s)", path.display(), targets.len()),
                    }
                    for t in targets {
                        let c: Vec<String> = t
                            .corners
                            .iter()
                            .take(4)
                            .map(|c| format!("({:.3}, {:.3})", c.x, c.y))
                            .collect();
                        let more = if t.corners.len() > 4 {
                            format!(" … {} corners", t.corners.len())
                        } else {
                            String::new()
                        };
                        print!("  id {:>4}: {}{more}", t.id, c.join(" "));
                        if let Some(p) = &t.pose {
                            let s = |i: usize| p.covariance[7 * i].sqrt() * 1e6;
                            print!(
                                "  t = ({:.3}, {:.3}, {:.3}) mm ± ({:.1}, {:.1}, {:.1}) µm",
                                p.position[0] * 1e3,
                                p.position[1] * 1e3,
                                p.position[2] * 1e3,
                                s(0),
                                s(1),
                                s(2)
                            );
                        }
                        println!();
                    }
                }
            }
            Err(e) => {
                failed += 1;
                eprintln!("metrocell detect: {e:#}");
            }
        }
    }
    i32::from(failed > 0)
}
