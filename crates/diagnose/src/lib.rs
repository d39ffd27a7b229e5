//! # metrocell-diagnose — where a model and a recording disagree
//!
//! `diagnose` fits the model the user declared, then asks of the residuals: are they what the
//! stated noise predicts, and if not, where do they live? This crate holds those questions as
//! pure functions over [`residual::ResidualSample`]s (one component of one measurement's residual
//! with its stated σ and the conditions it was taken in), so they hold on any honest data, not
//! only on the twin's:
//!
//! * [`noise_tests`] — χ² of the normalised residuals against their stated σ, a mean-shift test,
//!   whiteness in time (Ljung–Box) and a runs test on signs.
//! * [`locate`] — structure by channel and axis in regions of the workspace, windows of time,
//!   directions of motion and ranges of recorded conditions (velocity, temperature, load), with
//!   effect sizes and p-values corrected for the number of tests made ([`multiple_testing`]).
//! * [`selection`] — which candidate terms explain the structure: greedy forward selection judged
//!   on held-out blocks of time and workspace ([`folds`]), significance, plausible ranges and BIC.
//!
//! Convention: residual = measured − predicted (m); σ is the measurement's stated standard
//! uncertainty of that component (m).

pub mod blocked_least_squares;
pub mod candidate_columns;
pub mod candidates;
pub mod empirical;
pub mod findings;
pub mod folds;
pub mod html_report;
pub mod locate;
pub mod multiple_testing;
pub mod noise_tests;
pub mod outliers;
pub mod periodogram;
pub mod pipeline;
pub mod record_preparation;
pub mod report;
pub mod residual;
pub mod residual_table;
pub mod residual_view;
pub mod selection;
pub mod signal_inventory;

pub use pipeline::{diagnose, AddedTerm, DeclaredModel, Diagnosis, DiagnoseError, DiagnoseOptions, Strategy};
pub use report::Report;
