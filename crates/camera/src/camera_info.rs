//! ROS camera_info YAML, the file format of `camera_calibration_parsers` (written by the ROS
//! `camera_calibration` package and read by camera drivers):
//!
//! ```yaml
//! image_width: 1280
//! image_height: 960
//! camera_name: cell_cam
//! camera_matrix:
//!   rows: 3
//!   cols: 3
//!   data: [fx, 0, cx, 0, fy, cy, 0, 0, 1]
//! distortion_model: plumb_bob          # or equidistant (fisheye k1..k4)
//! distortion_coefficients:
//!   rows: 1
//!   cols: 5
//!   data: [k1, k2, p1, p2, k3]
//! rectification_matrix: {rows: 3, cols: 3, data: [...]}   # written in block style
//! projection_matrix:    {rows: 3, cols: 4, data: [...]}
//! ```
//! One key of our own, which ROS readers ignore: `intrinsics_covariance` (rows, cols, data as the
//! matrices above), the calibration's covariance of (fx, fy, cx, cy, distortion coefficients…)
//! as `metrocell camera calibrate` estimated it, so a pose measured with this camera can carry
//! the calibration's uncertainty (crate::intrinsics_uncertainty).
//!
//! Reading follows the parser: a missing `camera_name` reads as "unknown", a missing
//! `distortion_model` as plumb_bob. Numbers are written in their shortest round-trip form, always with a '.' and a signed
//! exponent so that YAML 1.1 readers (PyYAML) also see floats.

use crate::distortion::Distortion;
use crate::error::{CameraError, Result};
use crate::model::CameraModel;
use serde_yaml::Value;

#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    pub camera_name: String,
    pub image_width: u32,
    pub image_height: u32,
    /// K, row-major 3×3.
    pub camera_matrix: [f64; 9],
    pub distortion_model: String,
    pub distortion_coefficients: Vec<f64>,
    /// R, row-major 3×3.
    pub rectification_matrix: [f64; 9],
    /// P, row-major 3×4.
    pub projection_matrix: [f64; 12],
    /// Covariance of (fx, fy, cx, cy, coefficients…), row-major, when the calibration stated it.
    pub intrinsics_covariance: Option<Vec<f64>>,
}

impl CameraInfo {
    /// Monocular camera_info for `cam`: R = I, P = [K | 0] (as the ROS calibrator writes for a
    /// monocular camera without alpha rescaling).
    pub fn from_model(camera_name: &str, cam: &CameraModel) -> Self {
        CameraInfo {
            camera_name: camera_name.to_string(),
            image_width: cam.width,
            image_height: cam.height,
            camera_matrix: [cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0],
            distortion_model: cam.distortion.ros_name().to_string(),
            distortion_coefficients: cam.distortion.coefficients(),
            rectification_matrix: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            projection_matrix: [
                cam.fx, 0.0, cam.cx, 0.0, 0.0, cam.fy, cam.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
            ],
            intrinsics_covariance: None,
        }
    }

    /// With the calibration's covariance of (fx, fy, cx, cy, coefficients…).
    pub fn with_intrinsics_covariance(mut self, covariance: &nalgebra::DMatrix<f64>) -> Self {
        self.intrinsics_covariance = Some(covariance.transpose().as_slice().to_vec());
        self
    }

    /// The calibration's covariance of the model's parameters ((fx, fy, cx, cy, coefficients…),
    /// [`CameraModel::params`]), None when the file states none; an error names a matrix of the
    /// wrong size, a negative variance or a non-finite value.
    pub fn intrinsics_covariance(&self) -> Result<Option<nalgebra::DMatrix<f64>>> {
        let Some(data) = &self.intrinsics_covariance else {
            return Ok(None);
        };
        let n = 4 + self.distortion_coefficients.len();
        let err = |reason: String| CameraError::CameraInfo {
            source_name: self.camera_name.clone(),
            field: "intrinsics_covariance".into(),
            reason,
        };
        if data.len() != n * n {
            return Err(err(format!(
                "has {} numbers; fx, fy, cx, cy and {} coefficients need {n}×{n} = {}",
                data.len(),
                n - 4,
                n * n
            )));
        }
        let m = nalgebra::DMatrix::from_row_slice(n, n, data);
        if let Some(i) = (0..n).find(|&i| !(m[(i, i)] >= 0.0)) {
            return Err(err(format!("variance {i} is {} (must be ≥ 0)", m[(i, i)])));
        }
        Ok(Some(m))
    }

    /// The camera model (K and distortion; R and P are rectification data, not part of it).
    pub fn to_model(&self) -> Result<CameraModel> {
        let err = |field: &str, reason: String| CameraError::CameraInfo {
            source_name: self.camera_name.clone(),
            field: field.into(),
            reason,
        };
        let k = &self.camera_matrix;
        if k[1] != 0.0 {
            return Err(err(
                "camera_matrix",
                format!("skew K[0,1] = {} is not supported", k[1]),
            ));
        }
        let d = &self.distortion_coefficients;
        let distortion = match self.distortion_model.as_str() {
            "plumb_bob" => match d.len() {
                0 => Distortion::BrownConrady([0.0; 5]),
                4 => Distortion::BrownConrady([d[0], d[1], d[2], d[3], 0.0]),
                5 => Distortion::BrownConrady([d[0], d[1], d[2], d[3], d[4]]),
                n => {
                    return Err(err(
                        "distortion_coefficients",
                        format!("plumb_bob needs 4 or 5 coefficients, got {n}"),
                    ))
                }
            },
            "equidistant" => match d.len() {
                4 => Distortion::Fisheye([d[0], d[1], d[2], d[3]]),
                n => {
                    return Err(err(
                        "distortion_coefficients",
                        format!("equidistant needs 4 coefficients, got {n}"),
                    ))
                }
            },
            other => {
                return Err(err(
                    "distortion_model",
                    format!("unsupported model `{other}` (plumb_bob, equidistant)"),
                ))
            }
        };
        CameraModel::new(
            self.image_width,
            self.image_height,
            k[0],
            k[4],
            k[2],
            k[5],
            distortion,
        )
        .map_err(|e| err("camera_matrix", e.to_string()))
    }

    pub fn to_yaml(&self) -> String {
        fn mat(name: &str, rows: usize, cols: usize, data: &[f64]) -> String {
            let d: Vec<String> = data.iter().map(|v| yaml_float(*v)).collect();
            format!(
                "{name}:\n  rows: {rows}\n  cols: {cols}\n  data: [{}]\n",
                d.join(", ")
            )
        }
        let name = if self.camera_name.is_empty() {
            "unknown".to_string()
        } else {
            self.camera_name.clone()
        };
        let mut s = format!(
            "image_width: {}\nimage_height: {}\ncamera_name: {}\n",
            self.image_width, self.image_height, name
        );
        s += &mat("camera_matrix", 3, 3, &self.camera_matrix);
        s += &format!("distortion_model: {}\n", self.distortion_model);
        s += &mat(
            "distortion_coefficients",
            1,
            self.distortion_coefficients.len(),
            &self.distortion_coefficients,
        );
        s += &mat("rectification_matrix", 3, 3, &self.rectification_matrix);
        s += &mat("projection_matrix", 3, 4, &self.projection_matrix);
        if let Some(c) = &self.intrinsics_covariance {
            let n = (c.len() as f64).sqrt().round() as usize;
            s += "# metrocell: the calibration's covariance of (fx, fy, cx, cy, distortion coefficients)\n";
            s += &mat("intrinsics_covariance", n, n, c);
        }
        s
    }

    /// Parses camera_info YAML; `source_name` (e.g. the file path) is used in error messages.
    pub fn from_yaml(text: &str, source_name: &str) -> Result<Self> {
        let err = |field: &str, reason: String| CameraError::CameraInfo {
            source_name: source_name.into(),
            field: field.into(),
            reason,
        };
        let doc: Value =
            serde_yaml::from_str(text).map_err(|e| err("(document)", e.to_string()))?;
        let uint = |key: &str| -> Result<u32> {
            doc.get(key)
                .and_then(Value::as_u64)
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(|| err(key, "missing or not a non-negative integer".into()))
        };
        let matrix = |key: &str, rows: Option<usize>, cols: Option<usize>| -> Result<Vec<f64>> {
            let m = doc.get(key).ok_or_else(|| err(key, "missing".into()))?;
            let r = m
                .get("rows")
                .and_then(Value::as_u64)
                .ok_or_else(|| err(key, "missing `rows`".into()))? as usize;
            let c = m
                .get("cols")
                .and_then(Value::as_u64)
                .ok_or_else(|| err(key, "missing `cols`".into()))? as usize;
            if rows.is_some_and(|x| x != r) || cols.is_some_and(|x| x != c) {
                return Err(err(
                    key,
                    format!(
                        "is {r}×{c}, expected {}×{}",
                        rows.unwrap_or(r),
                        cols.unwrap_or(c)
                    ),
                ));
            }
            let data = m
                .get("data")
                .and_then(Value::as_sequence)
                .ok_or_else(|| err(key, "missing `data` sequence".into()))?;
            if data.len() != r * c {
                return Err(err(
                    key,
                    format!("`data` has {} numbers, rows×cols = {}", data.len(), r * c),
                ));
            }
            data.iter()
                .enumerate()
                .map(|(i, v)| {
                    v.as_f64()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| err(key, format!("data[{i}] is not a finite number")))
                })
                .collect()
        };
        let camera_name = match doc.get("camera_name") {
            None | Some(Value::Null) => "unknown".to_string(),
            Some(Value::String(s)) => s.clone(),
            Some(other) => serde_yaml::to_string(other)
                .unwrap_or_default()
                .trim()
                .to_string(),
        };
        let distortion_model = match doc.get("distortion_model") {
            None => "plumb_bob".to_string(),
            Some(v) => v
                .as_str()
                .ok_or_else(|| err("distortion_model", "not a string".into()))?
                .to_string(),
        };
        let k = matrix("camera_matrix", Some(3), Some(3))?;
        let d = matrix("distortion_coefficients", None, None)?;
        let r = matrix("rectification_matrix", Some(3), Some(3))?;
        let p = matrix("projection_matrix", Some(3), Some(4))?;
        let intrinsics_covariance = match doc.get("intrinsics_covariance") {
            None | Some(Value::Null) => None,
            Some(_) => {
                let n = 4 + d.len();
                Some(matrix("intrinsics_covariance", Some(n), Some(n))?)
            }
        };
        Ok(CameraInfo {
            camera_name,
            image_width: uint("image_width")?,
            image_height: uint("image_height")?,
            camera_matrix: k.try_into().expect("checked 3×3"),
            distortion_model,
            distortion_coefficients: d,
            rectification_matrix: r.try_into().expect("checked 3×3"),
            projection_matrix: p.try_into().expect("checked 3×4"),
            intrinsics_covariance,
        })
    }

    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| CameraError::Io {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::from_yaml(&text, &path.display().to_string())
    }

    pub fn save(&self, path: &std::path::Path) -> Result<()> {
        std::fs::write(path, self.to_yaml()).map_err(|e| CameraError::Io {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
    }
}

/// Shortest round-trip decimal that also reads as a float under YAML 1.1 resolvers (PyYAML,
/// used by Python ROS tools): always a '.', and a signed exponent ("1e-17" → "1.0e-17").
fn yaml_float(v: f64) -> String {
    let s = format!("{v:?}");
    match s.find('e') {
        None => s,
        Some(i) => {
            let (mant, exp) = (&s[..i], &s[i + 1..]);
            let mant = if mant.contains('.') {
                mant.to_string()
            } else {
                format!("{mant}.0")
            };
            let exp = if exp.starts_with('-') {
                exp.to_string()
            } else {
                format!("+{exp}")
            };
            format!("{mant}e{exp}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// As written by the ROS 2 `camera_calibration` calibrator (format_mat with aligned columns).
    const ROS_SAMPLE: &str = "image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [ 827.03654,    0.     ,  323.37587,
            0.     ,  826.38478,  227.44246,
            0.     ,    0.     ,    1.     ]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.398523, 0.156919, -0.001001, 0.000741, 0.000000]
rectification_matrix:
  rows: 3
  cols: 3
  data: [ 1.,  0.,  0.,
          0.,  1.,  0.,
          0.,  0.,  1.]
projection_matrix:
  rows: 3
  cols: 4
  data: [ 775.27844,    0.     ,  324.12289,    0.     ,
            0.     ,  788.64246,  226.51817,    0.     ,
            0.     ,    0.     ,    1.     ,    0.     ]
";

    #[test]
    fn parses_ros_calibrator_output() {
        let ci = CameraInfo::from_yaml(ROS_SAMPLE, "sample").unwrap();
        assert_eq!(
            (ci.image_width, ci.image_height, ci.camera_name.as_str()),
            (640, 480, "narrow_stereo")
        );
        let m = ci.to_model().unwrap();
        assert_eq!(
            (m.fx, m.fy, m.cx, m.cy),
            (827.03654, 826.38478, 323.37587, 227.44246)
        );
        assert_eq!(
            m.distortion,
            Distortion::BrownConrady([-0.398523, 0.156919, -0.001001, 0.000741, 0.0])
        );
        assert_eq!(ci.projection_matrix[5], 788.64246);
    }

    #[test]
    fn round_trip_is_exact_and_errors_name_the_field() {
        let cam = CameraModel::new(
            3840,
            2160,
            2901.123456789012,
            2899.5,
            1919.25,
            1080.125,
            Distortion::Fisheye([0.1, -0.02, 1e-17, 3.3e-5]),
        )
        .unwrap();
        let ci = CameraInfo::from_model("cell_cam", &cam);
        let text = ci.to_yaml();
        assert!(text.starts_with("image_width: 3840\nimage_height: 2160\ncamera_name: cell_cam\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: ["));
        assert!(text.contains(
            "distortion_model: equidistant\ndistortion_coefficients:\n  rows: 1\n  cols: 4\n"
        ));
        let back = CameraInfo::from_yaml(&text, "rt").unwrap();
        assert_eq!(back, ci);
        assert_eq!(back.to_model().unwrap(), cam);
        assert!(
            text.contains("1.0e-17") && text.contains("3.3e-5"),
            "{text}"
        );
        assert_eq!(yaml_float(1e20), "1.0e+20");
        let bad = text.replace("  cols: 4\n  data: [", "  cols: 5\n  data: [");
        let e = CameraInfo::from_yaml(&bad, "bad.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.yaml") && e.contains("distortion_coefficients"),
            "{e}"
        );
        let e = CameraInfo::from_yaml("image_width: 3\n", "x.yaml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera_matrix") && e.contains("missing"), "{e}");
    }

    #[test]
    fn the_intrinsics_covariance_round_trips_and_a_wrong_size_is_named() {
        let cam = CameraModel::new(
            800,
            600,
            700.0,
            705.0,
            405.3,
            296.8,
            Distortion::BrownConrady([-0.12, 0.05, 0.0, 0.0, 0.0]),
        )
        .unwrap();
        let cov = nalgebra::DMatrix::from_fn(9, 9, |i, j| {
            if i == j {
                0.01 * (i + 1) as f64
            } else {
                1e-4 * (i + j) as f64
            }
        });
        let ci = CameraInfo::from_model("cam", &cam).with_intrinsics_covariance(&cov);
        let text = ci.to_yaml();
        assert!(
            text.contains("intrinsics_covariance:\n  rows: 9\n  cols: 9\n"),
            "{text}"
        );
        let back = CameraInfo::from_yaml(&text, "cov.yaml").unwrap();
        assert_eq!(back.intrinsics_covariance().unwrap().unwrap(), cov);
        assert_eq!(
            CameraInfo::from_yaml(ROS_SAMPLE, "ros")
                .unwrap()
                .intrinsics_covariance()
                .unwrap(),
            None
        );
        let bad = text.replace("  rows: 9\n  cols: 9\n", "  rows: 3\n  cols: 3\n");
        let e = CameraInfo::from_yaml(&bad, "cov.yaml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cov.yaml")
                && e.contains("intrinsics_covariance")
                && e.contains("expected 9×9"),
            "{e}"
        );
    }
}
