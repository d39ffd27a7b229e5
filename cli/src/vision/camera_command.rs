//! `metrocell camera calibrate --images GLOB --board COLSxROWS --square 10mm [--fisheye] [-o FILE]`:
//! checkerboard corners from every image, Zhang + Levenberg–Marquardt calibration with parameter
//! uncertainties, per-view RMS, rejected views with the reason, ROS camera_info YAML out.

use std::path::PathBuf;

use metrocell_camera_model::{calibrate, CalibrationFlags, CameraInfo, LensModel, View};
use metrocell_camera_node::file_list::list_image_files;
use metrocell_vision::checkerboard::detect_checkerboard;

use super::image_input::{load_gray, parse_board, parse_length};

#[derive(clap::Subcommand)]
pub enum CameraCommand {
    /// Calibrate a camera from checkerboard images and write ROS camera_info YAML
    #[command(
        after_help = "Example:\n  metrocell camera calibrate --images 'views/*.png' --board 9x6 --square 10mm -o camera_info.yaml"
    )]
    Calibrate(CalibrateArgs),
}

#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Directory or glob of checkerboard images (quote the glob)
    #[arg(long)]
    pub images: String,
    /// Inner corners COLSxROWS, e.g. 9x6
    #[arg(long, value_parser = parse_board)]
    pub board: (usize, usize),
    /// Square side, e.g. 10mm
    #[arg(long, value_parser = parse_length)]
    pub square: f64,
    /// Kannala–Brandt fisheye (k1..k4) instead of Brown–Conrady (k1, k2, p1, p2, k3)
    #[arg(long)]
    pub fisheye: bool,
    /// Output camera_info YAML
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// camera_name written into the YAML
    #[arg(long, default_value = "camera")]
    pub camera_name: String,
}

pub fn run(command: CameraCommand) -> i32 {
    match command {
        CameraCommand::Calibrate(a) => match calibrate_command(a) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("metrocell camera calibrate: {e:#}");
                1
            }
        },
    }
}

fn calibrate_command(a: CalibrateArgs) -> anyhow::Result<i32> {
    let files = list_image_files(&a.images)?;
    let (cols, rows) = a.board;
    let object: Vec<[f64; 3]> = (0..cols * rows)
        .map(|k| {
            [
                (k % cols) as f64 * a.square,
                (k / cols) as f64 * a.square,
                0.0,
            ]
        })
        .collect();
    let mut views = Vec::new();
    let mut view_files = Vec::new();
    let mut size = None;
    // what is said, printed after the camera_info is written (a closed stdout must not cost it)
    let mut out: Vec<String> = Vec::new();
    for f in &files {
        let img = match load_gray(f) {
            Ok(i) => i,
            Err(e) => {
                out.push(format!("rejected {}: {e:#}", f.display()));
                continue;
            }
        };
        let s = (img.width(), img.height());
        if *size.get_or_insert(s) != s {
            out.push(format!(
                "rejected {}: size {}x{} differs from the first image's {}x{}",
                f.display(),
                s.0,
                s.1,
                size.unwrap().0,
                size.unwrap().1
            ));
            continue;
        }
        match detect_checkerboard(&img, cols, rows) {
            Ok(b) => {
                views.push(View {
                    object_points: object.clone(),
                    image_points: b
                        .corners
                        .iter()
                        .map(|c| [c.position.x, c.position.y])
                        .collect(),
                });
                view_files.push(f.clone());
            }
            Err(e) => out.push(format!(
                "rejected {}: checkerboard {cols}x{rows} not found ({e})",
                f.display()
            )),
        }
    }
    let say = |out: &[String]| out.iter().for_each(|l| println!("{l}"));
    let Some(size) = size else {
        say(&out);
        anyhow::bail!("{}: no readable image", a.images);
    };
    let model = if a.fisheye {
        LensModel::Fisheye
    } else {
        LensModel::BrownConrady
    };
    // A view is an outlier only if its RMS is both 3× the median and above 0.1 px: on clean
    // images every view sits at ~0.002 px and a 3× ratio alone would throw good views away.
    let flags = CalibrationFlags {
        outlier_view_min_rms_px: 0.1,
        ..Default::default()
    };
    let cal = match calibrate(&views, size, model, &flags) {
        Ok(cal) => cal,
        Err(e) => {
            say(&out);
            return Err(e.into());
        }
    };
    for r in &cal.rejected {
        out.push(format!(
            "rejected {}: {:?}",
            view_files[r.index].display(),
            r.reason
        ));
    }
    for v in &cal.views {
        out.push(format!(
            "view {}: RMS {:.4} px over {} corners",
            view_files[v.index].display(),
            v.rms_px,
            v.n_points
        ));
    }
    let names: &[&str] = if a.fisheye {
        &["fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"]
    } else {
        &["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
    };
    out.push(format!(
        "overall RMS {:.4} px ({} views, {} corners; σ per coordinate {:.4} px)",
        cal.rms_px,
        cal.views.len(),
        cal.n_points,
        cal.sigma_px
    ));
    for ((n, v), s) in names.iter().zip(cal.camera.params()).zip(&cal.param_std) {
        out.push(format!("  {n:>2} = {v:>14.6} ± {s:.6}"));
    }
    // the covariance goes into the file too, so poses measured with this camera can carry it
    let info = CameraInfo::from_model(&a.camera_name, &cal.camera)
        .with_intrinsics_covariance(&cal.param_covariance);
    match &a.output {
        Some(p) => {
            info.save(p)?;
            out.push(format!("wrote {}", p.display()));
            say(&out);
        }
        None => {
            say(&out);
            print!("{}", info.to_yaml());
        }
    }
    Ok(0)
}
