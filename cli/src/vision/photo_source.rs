//! Where a workflow's photos come from: image files (a directory or a glob), or a recording —
//! the `sensor_msgs/Image` frames a camera node published in the cell and the recorder kept,
//! with the calibration from `--camera` or from the recorded `camera_info`. Both arrive as the
//! same 8-bit grey images at the same measurement, so a plate or a star measured from a
//! recording gives the table its photo files give.

use std::path::PathBuf;

use anyhow::{bail, Context};
use image::GrayImage;
use metrocell_bagtools::BagSource;
use metrocell_camera_node::file_list::list_image_files;
use metrocell_fiducial_node::frame::gray_from_image;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};

use super::image_input::CalibratedCamera;

#[derive(clap::Args, Debug, Clone)]
pub struct PhotoArgs {
    /// The camera's calibration (ROS camera_info YAML, from `metrocell camera calibrate`);
    /// with --bag it defaults to the recording's camera_info
    #[arg(long, required_unless_present = "bag")]
    pub camera: Option<PathBuf>,
    /// Photos: a directory or a glob (quote it)
    #[arg(long, required_unless_present = "bag", conflicts_with = "bag")]
    pub images: Option<String>,
    /// A recording (rosbag2 directory or .mcap) whose image topic holds the photos, e.g. the
    /// camera node's frames recorded by `metrocell bag record`
    #[arg(long)]
    pub bag: Option<PathBuf>,
    /// With --bag: the image topic (its camera_info is the sibling topic `camera_info`)
    #[arg(long, default_value = "/camera/image_raw")]
    pub topic: String,
}

/// One photo: what to call it in messages, and its pixels.
pub struct Photo {
    pub label: String,
    pub image: GrayImage,
}

enum Source {
    Files(Vec<PathBuf>),
    Recording { bag: Box<BagSource>, topic: String },
}

/// The photos of one run and the camera that took them.
pub struct Photos {
    pub camera: CalibratedCamera,
    source: Source,
    count: usize,
}

/// `/camera/image_raw` → `/camera/camera_info`.
fn camera_info_topic(image_topic: &str) -> String {
    match image_topic.rsplit_once('/') {
        Some((ns, _)) => format!("{ns}/camera_info"),
        None => "camera_info".into(),
    }
}

impl PhotoArgs {
    /// Opens the photos and the camera, saying what to do when either is missing.
    pub fn open(&self) -> anyhow::Result<Photos> {
        let Some(bag_path) = &self.bag else {
            let camera = CalibratedCamera::load(self.camera.as_ref().expect("clap requires it"))?;
            let files = list_image_files(self.images.as_deref().expect("clap requires it"))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            return Ok(Photos {
                camera,
                count: files.len(),
                source: Source::Files(files),
            });
        };
        let mut bag = BagSource::open(bag_path)
            .with_context(|| format!("opening the recording {}", bag_path.display()))?;
        if !bag.subscribe::<Image>(&self.topic)? {
            bail!("{}", bag.missing_topic_hint(&self.topic));
        }
        let count = bag
            .topics()
            .iter()
            .find(|t| t.name == self.topic)
            .map_or(0, |t| t.message_count as usize);
        let camera = match &self.camera {
            Some(path) => CalibratedCamera::load(path)?,
            None => recorded_camera(bag_path, &self.topic)?,
        };
        Ok(Photos {
            camera,
            count,
            source: Source::Recording {
                bag: Box::new(bag),
                topic: self.topic.clone(),
            },
        })
    }
}

/// The first `camera_info` recorded beside `image_topic`.
fn recorded_camera(
    bag_path: &std::path::Path,
    image_topic: &str,
) -> anyhow::Result<CalibratedCamera> {
    let info_topic = camera_info_topic(image_topic);
    let mut infos = BagSource::open(bag_path)?;
    if !infos.subscribe::<CameraInfo>(&info_topic)? {
        bail!(
            "{} holds no {info_topic} to say which camera took the frames: give the calibration \
             with --camera camera_info.yaml (or record the camera node's camera_info too)",
            bag_path.display()
        );
    }
    let first = infos
        .messages()?
        .next()
        .transpose()?
        .with_context(|| format!("{info_topic} in {} has no message", bag_path.display()))?;
    let info = first.decode::<CameraInfo>()?;
    CalibratedCamera::from_msg(&info).with_context(|| {
        format!(
            "the camera_info recorded on {info_topic} in {}",
            bag_path.display()
        )
    })
}

impl Photos {
    /// How many photos there are (frames on the topic, for a recording).
    pub fn len(&self) -> usize {
        self.count
    }

    /// Calls `each(k, photo)` for every photo in order (file name order; log-time order for a
    /// recording). A photo at another size than the calibration's ends the run with an error
    /// naming it; a recorded frame that cannot be decoded is reported and skipped.
    pub fn for_each(
        &self,
        mut each: impl FnMut(usize, Photo) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        match &self.source {
            Source::Files(files) => {
                for (k, file) in files.iter().enumerate() {
                    let image = self.camera.photo(file)?;
                    each(
                        k,
                        Photo {
                            label: file.display().to_string(),
                            image,
                        },
                    )?;
                }
            }
            Source::Recording { bag, topic } => {
                for (k, m) in bag.messages()?.enumerate() {
                    let m = m?;
                    let decoded = m
                        .decode::<Image>()
                        .map_err(|e| e.to_string())
                        .and_then(|msg| {
                            let label = format!(
                                "{topic} frame {} (stamp {}.{:09} s)",
                                k + 1,
                                msg.header.stamp.sec,
                                msg.header.stamp.nanosec
                            );
                            gray_from_image(&msg)
                                .map(|image| (label, image))
                                .map_err(|e| e.to_string())
                        });
                    let (label, image) = match decoded {
                        Ok(v) => v,
                        Err(e) => {
                            println!(
                                "[{}/{}] {topic} at log time {} ns skipped: {e}",
                                k + 1,
                                self.count,
                                m.log_time_ns
                            );
                            continue;
                        }
                    };
                    self.camera.check_size(&image, &label)?;
                    each(k, Photo { label, image })?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_info_is_the_image_topics_sibling() {
        assert_eq!(
            camera_info_topic("/camera/image_raw"),
            "/camera/camera_info"
        );
        assert_eq!(
            camera_info_topic("/cell1/cam/image"),
            "/cell1/cam/camera_info"
        );
        assert_eq!(camera_info_topic("image"), "camera_info");
    }
}
