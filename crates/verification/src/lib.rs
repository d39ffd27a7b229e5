//! # metrocell-verification — planning a volumetric verification with a laser tracker
//!
//! Seed 001 (thesis P2–P5): the machine visits a mesh of points and stops at each; a laser
//! tracker on the table measures the target (SMR) there; the readings identify the machine's
//! geometric errors and the tracker's pose together. Planning decides, before anything is
//! measured:
//!
//! * [`mesh`] — the points: a grid over the volume (part 2 fixture 15: X 800–1200, Y 100–500,
//!   Z 200–400 mm at 100 mm is 75 points);
//! * [`visiting_order`] — the order (a spiral per Z layer, as the thesis visits its plate) and a
//!   unidirectional approach to every point, so each axis's backlash is the same at every point
//!   and goes into the origin instead of the error map;
//! * [`machine_program`] — the G-code the machine runs: the approach, the point, a dwell;
//! * [`tracker_station`] — where to put the tracker: candidate stations, which of them see every
//!   point (range, the reflector's acceptance angle), and the standard uncertainty of the
//!   identified error map each would give (linearised from the identification's covariance with
//!   the tracker's noise model, P5's placement study).
//!
//! * [`identification_model`] — the errors one tracker target identifies, the model a plan is
//!   judged with when the user gives none.
//!
//! * [`length_lines`] — the points a mesh needs for the length test's five lengths in each of seven
//!   directions (a short axis and the diagonals of a regular grid hold fewer).
//! * [`length_test`] — ISO 10360-2-style length conformity: 5 lengths × 7 directions × 3
//!   repetitions against MPE = min(A + L/K, B), decided with the uncertainty (ISO 14253-1).
//!
//! * [`measured_lengths`] — the readings as that length test: each visit a measured point in
//!   the machine frame, lengths as the machine is and with the fitted map compensated.
//! * [`resampled_monte_carlo`] — P3's Monte Carlo on the verification's own readings: the
//!   identified map's uncertainty and the residual error a compensation from it leaves.
//! * [`reference_conditions`] — the conditions the map is stated at: 20 °C at every sensor, so
//!   a model's thermal terms say what temperature adds and the map is the geometry.
//!
//! * [`hole_plate`] — a calibrated hole plate in the XY plane (the PTB method): ring centres,
//!   the plate's misalignment and expansion removed, six XY components and what correcting
//!   them compensates (the thesis's 94.39 %).
//!
//! * [`probe_tip`] — the probe-tip check: a sphere measured every 15° of the head, range and
//!   repeatability per axis, the tip's eccentricity and the three-lobe pretravel pattern.
//!
//! Units: SI (m, rad, s) in and out; the program is written in mm.

pub mod hole_plate;
pub mod identification_model;
pub mod length_lines;
pub mod length_test;
pub mod machine_program;
pub mod measured_lengths;
pub mod mesh;
pub mod probe_tip;
pub mod reference_conditions;
pub mod resampled_monte_carlo;
pub mod tracker_station;
pub mod visiting_order;

pub use mesh::Mesh;
