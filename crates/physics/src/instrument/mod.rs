//! Instrument physics: laser tracker (refraction, warm-up, turbulence, pose), touch probe,
//! camera, and stream timing.
pub mod camera_scale;
pub mod edlen;
pub mod lens_distortion;
pub mod probe_pretravel;
pub mod refraction;
pub mod spherical;
pub mod time_offset;
pub mod tracker_pose;
pub mod tracker_uncertainty;
pub mod tracker_warmup;
pub mod turbulence;
