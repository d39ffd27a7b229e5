//! Laser-tracker logging as pure functions: what the `metrocell-tracker` node does to each
//! reading, with no DDS in it.
//!
//! * [`reading`]: one raw reading → refraction re-corrected range and Cartesian point with its
//!   covariance (beam breaks and bad values are named, never passed on).
//! * [`dwell`]: consecutive readings of one target grouped and averaged, with standard error.
//! * [`turbulence`]: the χ² test of a dwell's range scatter against the noise model.
//! * [`warmup`]: fit of A + B(1 − e^(−t/τ)) to repeated nest readings, and the "stable" flag.
//! * [`registration`] (crates/kinematics' `rigid_registration`, re-exported): weighted Kabsch fit of the tracker pose
//!   in the machine frame, 6×6 covariance.
//! * [`time_alignment`]: commanded machine position at a measurement's time; the thesis's T_v.
//! * [`line_protocol`] and [`tcp_client`]: the ASCII line driver for trackers that stream readings.
//! * [`total_station_gsi`]: Leica GSI-8/GSI-16 blocks from a total station → point and covariance
//!   in the levelled instrument frame (the TCP client reads them with `LineFormat::LeicaGsi`).
//!
//! Units are SI throughout (m, rad, s, Pa, °C; relative humidity as a 0..1 fraction).

pub mod dwell;
pub mod line_protocol;
pub mod reading;
pub mod registration;
pub mod tcp_client;
pub mod time_alignment;
pub mod total_station_gsi;
pub mod turbulence;
pub mod warmup;

#[cfg(test)]
mod test_noise;

pub use dwell::{DwellAverage, DwellGrouper};
pub use reading::{
    AirSource, EdlenForm, ProcessedReading, RawReading, ReadingError, ReadingProcessor,
};
pub use registration::{register, Registration, RegistrationError};
pub use time_alignment::{program_point_time, CommandedTrajectory, ProgramSchedule};
pub use turbulence::{TurbulenceTest, TurbulenceVerdict};
pub use warmup::{fit_warmup, WarmupFit, WarmupTracker};
