//! # metrocell-diagnose — where a model and a recording disagree, and which physics is missing
//!
//! [`diagnose`] fits the model the user declared to a recording's records, asks of the residuals
//! whether they are what the stated noise predicts and where they are not, tries every catalog
//! term the model lacks (columns from the shared model) and empirical corrections, keeps what
//! lowers the error on held-out blocks of time and of workspace, refits the augmented model and
//! says what it found in a metrologist's words ([`report::Report`]). The crate README lists the
//! steps and the JSON fields. Modules, in the order the pipeline uses them:
//!
//! * [`record_preparation`], [`outliers`], [`residual_view`] — records made ready, gross outliers,
//!   residuals seen along the workpiece axes;
//! * [`noise_tests`], [`locate`], [`multiple_testing`] — χ², mean shift, Ljung–Box and runs;
//!   structure by region, time window, direction and condition, Holm-corrected;
//! * [`signal_inventory`], [`candidates`], [`candidate_columns`], [`periodogram`], [`empirical`] —
//!   what can be tried and its Jacobian columns;
//! * [`folds`], [`blocked_least_squares`], [`selection`] — held-out blocks and the selection;
//! * [`serial_correlation`] — the found terms' σ with residuals correlated in time or by place;
//! * [`pipeline`] and its stages (`declared_stage`, `candidate_stage`, `augmented_stage`,
//!   `judgement`), [`all_at_once`] (the baseline), [`findings`], [`report`], [`html_report`],
//!   [`residual_table`] — the whole run and its outputs.
//!
//! Conventions: residual = measured − predicted (m), in the records' frame for fits and rotated
//! into the workpiece frame for localisation and reports; σ is the measurement's stated standard
//! uncertainty. SI throughout; reports show µm, mm and minutes.

pub mod all_at_once;
mod augmented_stage;
pub mod blocked_least_squares;
pub mod candidate_columns;
mod candidate_stage;
pub mod candidates;
mod declared_stage;
pub mod empirical;
pub mod findings;
pub mod folds;
pub mod html_report;
mod judgement;
pub mod locate;
pub mod multiple_testing;
pub mod noise_tests;
pub mod outliers;
pub mod periodogram;
pub mod pipeline;
pub mod record_preparation;
mod reference_columns;
pub mod report;
pub mod residual;
pub mod residual_table;
pub mod residual_view;
pub mod selection;
pub mod serial_correlation;
pub mod signal_coverage;
pub mod signal_inventory;

pub use pipeline::{
    diagnose, AddedTerm, DeclaredModel, DiagnoseError, DiagnoseOptions, Diagnosis, Strategy,
};
pub use report::Report;
