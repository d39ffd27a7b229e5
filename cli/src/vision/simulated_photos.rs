//! Writing the twin's photos of a workflow object: the camera's calibration as ROS camera_info
//! YAML, then each photo as `photo_K.png`, with progress.

use std::path::Path;

use anyhow::Context;
use metrocell_camera_model::{CameraInfo, CameraModel};

/// Writes `DIR/camera_info.yaml` for `camera` and `DIR/photo_K.png` for K = 0…count−1 from
/// `photo(K)`.
pub fn write_photos(
    dir: &Path,
    camera: &CameraModel,
    count: u64,
    photo: impl Fn(u64) -> Result<image::GrayImage, metrocell_simulation::SimError>,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let info_path = dir.join("camera_info.yaml");
    CameraInfo::from_model("workflow_camera", camera)
        .save(&info_path)
        .with_context(|| format!("writing {}", info_path.display()))?;
    for k in 0..count {
        let path = dir.join(format!("photo_{k}.png"));
        photo(k)?
            .save(&path)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("[{}/{count}] {}", k + 1, path.display());
    }
    Ok(())
}
