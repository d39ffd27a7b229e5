//! The node's parameters. Numeric ones carry ranges, so an out-of-range value is an error naming
//! the parameter, its range and where the value came from (and `--help` shows the range),
//! instead of being clamped silently.

use metrocell_node::ParamDecl;

/// Largest frame side accepted for `width`/`height` [px]: above every V4L2 capture driver's
/// limit (16K video is 15360 px wide); the driver still picks the nearest size it supports.
pub const MAX_FRAME_SIDE_PX: u32 = 16384;

pub fn declarations() -> Vec<ParamDecl> {
    let side = MAX_FRAME_SIDE_PX as f64;
    vec![
        ParamDecl::new("path", String::new(), "directory of images, or a glob such as views/*.png"),
        ParamDecl::new("device", String::new(), "V4L2 capture device such as /dev/video0 (instead of path)"),
        ParamDecl::new("width", 0i64, "device: requested frame width [px]; 0 = camera_info's width if loaded, else the driver's current").with_range(0.0, side),
        ParamDecl::new("height", 0i64, "device: requested frame height [px]; 0 = camera_info's height if loaded, else the driver's current").with_range(0.0, side),
        ParamDecl::new("pixel_format", "auto".to_string(), "device: GREY, YUYV or auto (GREY, else YUYV)"),
        ParamDecl::new("rate", 10.0, "frames per second; 0 = as fast as possible").with_range(0.0, 10000.0),
        ParamDecl::new("loop", false, "start again after the last file"),
        ParamDecl::new("wait_for_subscribers", 0i64, "files: hold the first frame until this many subscribers of image (and of camera_info, when there is one) are matched — so a recorder started first records every photo of a folder; 0 = publish at once").with_range(0.0, 1000.0),
        ParamDecl::new("frame_id", "camera_optical_frame".to_string(), "frame_id of image and camera_info"),
        ParamDecl::new("camera_info_url", String::new(), "ROS camera_info YAML (path or file:// URL); empty = no camera_info"),
        ParamDecl::new("stamp_source", "mtime".to_string(), "header stamp of a frame: mtime (file modification time), filename (see stamp_pattern) or now (publication instant)"),
        ParamDecl::new("stamp_pattern", String::new(), "with stamp_source filename: the file name with one of {ns}, {us}, {ms}, {s} where the time is, e.g. frame_{ns}.png"),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_node::{parse_command_line, Parameters};

    fn resolve(args: &[&str]) -> Result<Parameters, String> {
        let cl = parse_command_line(
            ["metrocell-camera", "--ros-args"]
                .iter()
                .chain(args)
                .copied(),
        )
        .map_err(|e| e.to_string())?;
        Parameters::resolve(&declarations(), &cl.ros, "/camera", "camera")
            .map_err(|e| e.to_string())
    }

    #[test]
    fn frame_size_out_of_range_is_an_error_naming_the_range() {
        let p = resolve(&["-p", "width:=1920", "-p", "height:=1080"]).unwrap();
        assert_eq!(
            (
                p.get::<i64>("width").unwrap(),
                p.get::<i64>("height").unwrap()
            ),
            (1920, 1080)
        );
        // Negative sizes were clamped to 0 (= "driver's current") without a word.
        let e = resolve(&["-p", "width:=-640"]).unwrap_err();
        assert!(
            e.contains("'width'") && e.contains("[0, 16384]") && e.contains("-640"),
            "{e}"
        );
        let e = resolve(&["-p", "height:=100000"]).unwrap_err();
        assert!(e.contains("'height'") && e.contains("100000"), "{e}");
        // Above u32::MAX the old `as u32` wrapped to a different size.
        assert!(resolve(&["-p", "width:=4294967936"]).is_err());
    }
}
