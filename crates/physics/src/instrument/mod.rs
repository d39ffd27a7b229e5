//! Instrument physics: laser tracker (refraction, warm-up, turbulence, pose), touch probe,
//! camera, and stream timing.
pub mod base_tilt;
pub mod camera_scale;
pub mod edlen;
pub mod instrument_drift;
pub mod lens_distortion;
pub mod probe_pretravel;
pub mod refraction;
pub mod spherical;
pub mod time_offset;
pub mod tracker_pose;
pub mod tracker_uncertainty;
pub mod tracker_warmup;
pub mod turbulence;

use crate::config::Options;
use crate::error::PhysicsError;

/// The instance name of an instrument term, option `instrument` (absent: the cell's only
/// instrument of its kind). A cell with two trackers or two cameras names each, and every term
/// of one instrument carries its name, so labels stay unique (`tracker_pose[lt1]`,
/// `tracker_pose[lt2]`) and the forward model groups the terms by instrument.
pub(crate) fn instance(o: &Options) -> Result<Option<String>, PhysicsError> {
    if !o.has("instrument") {
        return Ok(None);
    }
    let name = o.text("instrument", None)?;
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return Err(o.bad("instrument", format!("`{name}` is not an instrument name; use letters, digits, `_` or `-` (e.g. lt1, cam_left)")));
    }
    Ok(Some(name))
}

/// `base` or `base[name]`.
pub(crate) fn instance_label(base: &str, instance: &Option<String>) -> String {
    match instance {
        Some(n) => format!("{base}[{n}]"),
        None => base.to_string(),
    }
}
