//! Nonlinear least squares for metrocell: one solver for camera calibration and pose refinement,
//! edge and corner fitting, and error-model identification.
//!
//! **Approach.** A dense Levenberg–Marquardt ([`solve`]) on a [`Problem`] that writes residuals
//! and its analytic Jacobian into buffers allocated once per solve, with per-residual whitening
//! (σᵢ), robust losses ([`Loss::Huber`], [`Loss::Cauchy`]) by iteratively reweighted least
//! squares, projected box bounds, Moré's column scaling, a fixed-parameter mask, Gaussian priors
//! as extra residuals, and a truncated-SVD step that stays on the identifiable subspace
//! ([`NullSpace::Truncated`]). The normal equations JᵀWJ are formed from the column-major
//! Jacobian's free columns, weighted a cache-sized block of rows at a time and multiplied there
//! (a register-tiled kernel that forms one triangle, AVX2/FMA chosen at run time; no Jᵀ copy,
//! no m × m weight matrix, J read from memory once); at 70
//! parameters the n × n solve is negligible next to forming them, which is why a dense method is
//! used rather than a QR or SVD of the full Jacobian per iteration (scipy's "trf"). The
//! iteration stops without a confirming trial once the Gauss–Newton step's predicted reduction
//! is below `ftol` of the cost. [`solve_from`] starts from residuals and a Jacobian the caller
//! has already evaluated (and their normal matrix, if formed), working in the caller's buffers.
//! Jacobian-sized buffers are allocated zeroed by the OS ([`zeroed_matrix`]; on Linux backed by
//! huge pages where the kernel allows), not written with zeros.
//!
//! **Why not a crate.** `levenberg-marquardt` (nalgebra-based, a MINPACK port) has scaling and
//! termination reasons but no weights, robust losses, bounds, priors, fixed parameters or
//! covariance, and solves by QR of the full Jacobian each iteration; `argmin` offers
//! Gauss–Newton/LM-free trust regions over generic operators, again without bounds, robust losses
//! or covariance. Each would need most of this crate around it, so the solver is written here.
//!
//! **Uncertainty.** [`Solution`] carries the a-posteriori variance factor σ̂₀² = r̂ᵀWr̂/(n − p),
//! the covariance (JᵀWJ)⁻¹·σ̂₀² (and unscaled), correlations and the count of measurements the
//! robust loss down-weighted; [`Identifiability`] names the combinations the data do not
//! determine; [`monte_carlo`] re-solves with simulated noise.
//!
//! **Conventions.** Residuals are r = model − measurement or measurement − model as the problem
//! likes (the solver only squares them); σᵢ in the residuals' units; parameters in SI units.

mod error;
mod gram_kernel;
pub mod identifiability;
mod levenberg_marquardt;
mod loss;
pub mod monte_carlo;
mod normal_equations;
pub mod numeric_jacobian;
mod options;
mod problem;
mod solution;
pub mod time_constant_fit;
mod zeroed;

pub use error::{NotEvaluable, SolverError};
pub use identifiability::{Identifiability, NullDirection};
pub use levenberg_marquardt::{solve, solve_from, Evaluated};
pub use loss::Loss;
pub use monte_carlo::{monte_carlo, MonteCarlo, Noise};
pub use normal_equations::normal_matrix;
pub use options::{NullSpace, Options, Prior};
pub use problem::Problem;
pub use solution::{Solution, Termination};
pub use time_constant_fit::{
    fit_time_constant, ChiSquareScaling, TimeConstantFit, TimeConstantFitError, TimeConstantRow,
    TimeConstantSearch,
};
pub use zeroed::zeroed_matrix;
