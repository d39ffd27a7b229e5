//! The pure parts of the `metrocell-camera` node (no DDS), unit-tested here:
//! - [`capture_stamp`]: the capture stamp of a file frame (mtime, file name pattern or now);
//! - [`file_list`]: a directory or a glob (`*`, `?` in the file-name part) → sorted image files;
//! - [`image_file`]: one PNG/JPEG/TIFF file → sensor_msgs/Image (mono8, mono16, rgb8), errors naming the file;
//! - [`parameters`]: the node's parameter declarations, numeric ones with ranges.

pub mod capture_stamp;
pub mod file_list;
pub mod image_file;
pub mod parameters;
