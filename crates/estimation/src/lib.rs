//! # metrocell-estimation — learning a machine's error model from measurements
//!
//! Pure functions, no DDS; used by `metrocell calibrate`, the estimator node and `diagnose`.
//! Records in, estimates out: the records are built from bags and live messages by
//! crates/records (`metrocell_records::records_from_bags`, `RecordStream`), so this crate links
//! neither the bag stack nor the messages.
//!
//! * [`records`] — measurement records (what was measured — a tracker or machine-frame point, a
//!   probe hit, a camera point — with its covariance, its commanded joints and the signals at its
//!   time) and the frame they are in.
//! * [`residuals`] — measured − predicted on the shared forward model (crates/model), whitened
//!   by each record's covariance, with the model's analytic Jacobian: a solver problem.
//! * [`fit`] — batch identification of the declared free parameters: registration of the
//!   instrument frame (crates/kinematics `rigid_registration`), bounded robust Levenberg–Marquardt,
//!   scaled covariance, identifiability.
//! * [`fit_summary`] — a fit in words: values ± σ in µm/µrad, what is not identifiable and
//!   why, residuals before/after, consistency with the stated noise, outliers and skipped records.
//! * [`error_functions`] — the fitted error along each axis with its uncertainty band
//!   (u_e = √diag(J·C·Jᵀ)).
//! * [`recursive`] — online estimation: an extended Kalman filter with random-walk drift,
//!   outlier gating and a moving normalised-innovation χ² test that flags when the model stops
//!   explaining the data.
//! * [`volumetric_monte_carlo`] — N simulated verifications (noise, tracker placement) fitted
//!   like a real one: the volumetric error map with its uncertainty and the residual error after
//!   compensation (seed 001, P3).
//! * [`map_gauge`] — the gauge a map is stated in: as fitted, or with its least-squares rigid
//!   motion removed (a freely placed instrument fixes a map only up to one).
//! * [`simulated_records`] — the readings a tracker would give of planned points at known
//!   parameters, with its noise model and stated covariance (planning, Monte Carlo, tests).
//! * [`uncertainty_budget`] — GUM combination of standard uncertainties and the ISO/TS 15530-3
//!   expanded uncertainty U = k·√(u_cal² + u_p² + u_b² + u_w²) (seed 001, eq. 3.4), with each
//!   component's share.
//! * [`improvement`] — before/after error statistics and percent improvement as seed 000 reports
//!   them (its Table 3).
//! * [`general_tolerance`] — ISO 2768-1 general tolerances for linear dimensions (the class a
//!   compensation reaches, seed 000).
//! * [`sequential_anova`] — ANOVA with sequential (type I) sums of squares, for a designed
//!   experiment's table (seed 000's Tables 6 and 7).
//! * [`method_comparison`] — a method against a reference on the same parts (seed 002's Table 2).
//! * [`design_of_experiments`] — D-optimal choice of measurement rows from candidates (Fedorov
//!   exchange, the family DETMAX belongs to; seed 000 §4).
//!
//! Units: SI (m) in and out; reports convert to mm and µm.

pub mod accelerometer_alignment;
pub mod check_points;
pub mod delta_calibration;
pub mod design_of_experiments;
pub mod error_functions;
pub mod fit;
pub mod fit_summary;
pub mod general_tolerance;
pub mod improvement;
pub mod map_gauge;
pub mod method_comparison;
mod record_chunks;
pub mod records;
pub mod recursive;
pub mod reference_nests;
pub mod residuals;
pub mod sequential_anova;
pub mod simulated_records;
pub mod uncertainty_budget;
pub mod volumetric_monte_carlo;

pub use check_points::{check_report, check_statistics, setups_of, CheckReport, CheckStatistics};
pub use fit::{
    fit, inseparable, rms, start_vector, BoundSide, Fit, FitError, FitOptions, HeldParameter,
    ParameterEstimate, RecordNote,
};
pub use records::{MeasurementRecord, RecordFrame, RecordKind, RecordSet, Rejected};
pub use recursive::{RecursiveEstimator, RecursiveOptions, Update};
pub use reference_nests::{estimate_nests, is_reference};
pub use residuals::PointResiduals;
