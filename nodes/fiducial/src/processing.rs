//! What the node does with each input, shared by the live run and the bag replay so both give
//! the same numbers: parameters → [`FiducialProcessor`]; a CameraInfo updates the camera model;
//! an Image becomes a FiducialDetectionArray (header = the image's: its stamp and frame_id) and
//! one PoseWithCovarianceStamped per target with a pose.

use metrocell_camera_model::CameraModel;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{ParamDecl, Parameters};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, PoseInputs, TargetFamily};
use nalgebra::DMatrix;

use crate::{detection_msgs, frame};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("family", "DICT_4X4_50".to_string(), "OpenCV dictionary name (DICT_4X4_50, DICT_APRILTAG_36h11, ...), checkerboard, or drilled_holes"),
        ParamDecl::new("marker_size", 0.0, "marker side [m] for marker poses; 0 = no marker pose").with_range(0.0, 10.0),
        // ≥ 2: the checkerboard detector needs a 2×2 inner grid, and so does the hole plate's
        // corner extrapolation; ≤ 1000 only catches typos.
        ParamDecl::new("board_cols", 9i64, "checkerboard / hole plate: inner corners along a row (squares − 1)").with_range(2.0, 1000.0),
        ParamDecl::new("board_rows", 6i64, "checkerboard / hole plate: inner corners along a column (squares − 1)").with_range(2.0, 1000.0),
        ParamDecl::new("square_size", 0.01, "checkerboard square side [m]").with_range(0.0, 10.0),
        ParamDecl::new("corner_sigma_px", 0.1, "corner σ [px] where a corner has no covariance").with_range(1e-6, 100.0),
        ParamDecl::new("threads", 0i64, "detector worker threads; 0 = all cores").with_range(0.0, 1024.0),
        ParamDecl::new("calibration_file", String::new(), "camera_info YAML written by `metrocell camera calibrate`: while the received camera_info is that calibration, each pose's covariance includes the calibration's own uncertainty (its intrinsics_covariance); '' = the intrinsics count as exact"),
    ]
}

/// Outputs of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameOutputs {
    pub detections: FiducialDetectionArray,
    pub poses: Vec<PoseWithCovarianceStamped>,
}

pub struct FiducialProcessor {
    family: TargetFamily,
    family_name: String,
    marker_size: Option<f64>,
    sigma: f64,
    params: DetectorParams,
    camera: Option<CameraModel>,
    /// `calibration_file`: its camera and the covariance of its parameters.
    calibration: Option<(String, CameraModel, DMatrix<f64>)>,
    /// The calibration's covariance, while the received camera is the calibration's.
    intrinsics_covariance: Option<DMatrix<f64>>,
    /// A received camera differing from `calibration_file`'s was reported.
    mismatch_said: bool,
}

impl FiducialProcessor {
    pub fn from_parameters(p: &Parameters) -> Result<Self, Box<dyn std::error::Error>> {
        // Non-negative by the declared ranges, so the conversions cannot fail.
        let count = |name: &str| -> Result<usize, Box<dyn std::error::Error>> {
            Ok(usize::try_from(p.get::<i64>(name)?)?)
        };
        let board = (count("board_cols")?, count("board_rows")?);
        let family = TargetFamily::parse(
            &p.get::<String>("family")?,
            Some(board),
            Some(p.get::<f64>("square_size")?),
        )?;
        Ok(FiducialProcessor {
            family_name: family.message_name(),
            family,
            marker_size: Some(p.get::<f64>("marker_size")?).filter(|s| *s > 0.0),
            sigma: p.get::<f64>("corner_sigma_px")?,
            params: DetectorParams {
                threads: count("threads")?,
                ..Default::default()
            },
            camera: None,
            calibration: calibration(&p.get::<String>("calibration_file")?)?,
            intrinsics_covariance: None,
            mismatch_said: false,
        })
    }

    pub fn describe(&self) -> String {
        let calibration = match &self.calibration {
            Some((path, ..)) => {
                format!("; poses include the uncertainty of the calibration in {path}")
            }
            None => String::new(),
        };
        format!(
            "detecting {}, marker_size {:?} m{calibration}",
            self.family_name, self.marker_size
        )
    }

    /// Use this camera for poses from now on; a bad message keeps the previous camera. Returns
    /// a warning, once, when `calibration_file` is set and the received camera is not its
    /// calibration (poses then count the corner noise only).
    pub fn camera_info(
        &mut self,
        info: &CameraInfo,
    ) -> Result<Option<String>, metrocell_camera_model::CameraError> {
        let camera = metrocell_camera_model::camera_model_from_msg(info)?;
        let mut warning = None;
        self.intrinsics_covariance = match &self.calibration {
            Some((_, calibrated, cov)) if *calibrated == camera => Some(cov.clone()),
            Some((path, ..)) => {
                if !std::mem::replace(&mut self.mismatch_said, true) {
                    warning = Some(format!("the received camera_info is not the calibration in {path} (calibration_file): its uncertainty is left out of the poses until it is"));
                }
                None
            }
            None => None,
        };
        self.camera = Some(camera);
        Ok(warning)
    }

    /// Detect in one frame. Errors name the frame (stamp, frame_id) and the problem.
    pub fn frame(&self, img: &Image) -> Result<FrameOutputs, String> {
        let name = || {
            format!(
                "frame {}.{:09} ({})",
                img.header.stamp.sec, img.header.stamp.nanosec, img.header.frame_id
            )
        };
        let gray = frame::gray_from_image(img).map_err(|e| format!("{}: {e}", name()))?;
        let pose_inputs = self
            .camera
            .as_ref()
            .filter(|c| c.width == gray.width() && c.height == gray.height())
            .map(|c| PoseInputs {
                camera: c,
                marker_side: self.marker_size,
                fallback_sigma_px: self.sigma,
                intrinsics_covariance: self.intrinsics_covariance.as_ref(),
            });
        let targets = detect_targets(&gray, &self.family, &self.params, pose_inputs)
            .map_err(|e| format!("{}: {e}", name()))?;
        Ok(FrameOutputs {
            detections: detection_msgs::detection_array(
                &img.header,
                img.width,
                img.height,
                &self.family_name,
                &targets,
            ),
            poses: detection_msgs::pose_messages(&img.header, &targets),
        })
    }
}

/// The camera and covariance of `calibration_file` ('' = none); errors name the file and say
/// how to write one that has it.
/// A calibration file's camera: its name, model and the model's covariance.
type LoadedCalibration = (String, CameraModel, DMatrix<f64>);

fn calibration(path: &str) -> Result<Option<LoadedCalibration>, Box<dyn std::error::Error>> {
    if path.trim().is_empty() {
        return Ok(None);
    }
    let info = metrocell_camera_model::CameraInfo::load(std::path::Path::new(path))?;
    let cov = info.intrinsics_covariance()?.ok_or_else(|| format!("calibration_file {path}: states no intrinsics_covariance; write it with `metrocell camera calibrate`, or leave calibration_file empty"))?;
    Ok(Some((path.to_string(), info.to_model()?, cov)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_node::parse_command_line;

    fn resolve(args: &[&str]) -> Result<Parameters, String> {
        let cl = parse_command_line(
            ["metrocell-fiducial", "--ros-args"]
                .iter()
                .chain(args)
                .copied(),
        )
        .map_err(|e| e.to_string())?;
        Parameters::resolve(&declarations(), &cl.ros, "/fiducial", "fiducial")
            .map_err(|e| e.to_string())
    }

    #[test]
    fn counts_out_of_range_are_errors_naming_the_range() {
        let p = resolve(&[
            "-p",
            "family:=checkerboard",
            "-p",
            "board_cols:=2",
            "-p",
            "board_rows:=1000",
            "-p",
            "threads:=4",
        ])
        .unwrap();
        assert!(FiducialProcessor::from_parameters(&p).is_ok());
        // These were clamped (−1 → 0 columns, −3 → 0 = all cores) or passed on to fail per frame.
        for (arg, name, range) in [
            ("board_cols:=-1", "'board_cols'", "[2, 1000]"),
            ("board_rows:=1", "'board_rows'", "[2, 1000]"),
            ("threads:=-3", "'threads'", "[0, 1024]"),
        ] {
            let e = resolve(&["-p", arg])
                .err()
                .unwrap_or_else(|| panic!("{arg} accepted"));
            assert!(e.contains(name) && e.contains(range), "{arg}: {e}");
        }
    }

    /// With calibration_file, a board's pose covariance includes the calibration's uncertainty
    /// while the received camera_info is that calibration; another camera is said once and its
    /// poses count the corner noise only.
    #[test]
    fn poses_carry_the_calibration_file_uncertainty_for_its_camera_only() {
        use metrocell_camera_model::{CameraInfo as InfoFile, Distortion};
        use metrocell_vision::{render_view, PlanarTarget, RenderSettings, TargetItem};
        let cam = CameraModel::new(
            800,
            600,
            900.0,
            905.0,
            401.3,
            297.8,
            Distortion::BrownConrady([-0.12, 0.05, 0.0, 0.0, 0.0]),
        )
        .unwrap();
        let cov = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
            0.15f64.powi(2),
            0.15f64.powi(2),
            0.2f64.powi(2),
            0.2f64.powi(2),
            1e-6,
            1e-5,
            1e-9,
            1e-9,
            1e-4,
        ]));
        let dir = std::env::temp_dir().join(format!("fiducial-calibration-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("camera_info.yaml");
        InfoFile::from_model("cam", &cam)
            .with_intrinsics_covariance(&cov)
            .save(&file)
            .unwrap();
        let board = PlanarTarget {
            items: vec![TargetItem::Checkerboard {
                top_left: [0.0, 0.0],
                square: 0.012,
                squares_x: 9,
                squares_y: 7,
                top_left_black: true,
            }],
        };
        let pose = nalgebra::Isometry3::new(
            nalgebra::Vector3::new(-0.05, -0.04, 0.4),
            nalgebra::Vector3::new(0.1, -0.15, 0.05),
        );
        let view = render_view(
            &cam,
            &pose,
            &board,
            &RenderSettings {
                blur_sigma_px: 0.8,
                noise_sigma: 1.0,
                ..Default::default()
            },
        )
        .unwrap();
        let img = Image {
            height: 600,
            width: 800,
            encoding: "mono8".into(),
            step: 800,
            data: view.image.into_raw(),
            ..Default::default()
        };
        let sigma_z = |args: &[&str], info: &CameraInfo| -> (f64, Option<String>) {
            let mut p = FiducialProcessor::from_parameters(&resolve(args).unwrap()).unwrap();
            let said = p.camera_info(info).unwrap();
            let out = p.frame(&img).unwrap();
            (out.poses[0].pose.covariance[14].sqrt(), said)
        };
        let board_args = [
            "-p",
            "family:=checkerboard",
            "-p",
            "board_cols:=8",
            "-p",
            "board_rows:=6",
            "-p",
            "square_size:=0.012",
        ];
        let with_file: Vec<&str> = board_args.iter().copied().chain(["-p"]).collect();
        let calibration_arg = format!("calibration_file:={}", file.display());
        let with_file: Vec<&str> = with_file
            .into_iter()
            .chain([calibration_arg.as_str()])
            .collect();
        let info = InfoFile::from_model("cam", &cam).to_msg();
        let (bare, _) = sigma_z(&board_args, &info);
        let (calibrated, said) = sigma_z(&with_file, &info);
        assert!(said.is_none());
        // fx known to 0.15 px of 900 at 0.4 m: ~70 µm along the line of sight, against a few µm
        assert!(
            bare < 10e-6 && calibrated > 40e-6,
            "σ_z without the file {bare:e} m, with it {calibrated:e} m"
        );
        let other = InfoFile::from_model("cam", &CameraModel { fx: 901.0, ..cam }).to_msg();
        let (sigma, said) = sigma_z(&with_file, &other);
        assert!(
            sigma < 10e-6 && said.unwrap().contains("is not the calibration in"),
            "{sigma:e}"
        );
        std::fs::write(&file, "image_width: 800\n").unwrap();
        assert!(
            FiducialProcessor::from_parameters(&resolve(&with_file).unwrap())
                .err()
                .unwrap()
                .to_string()
                .contains("camera_info.yaml")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
