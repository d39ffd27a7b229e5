//! Online estimation: an extended Kalman filter over the free parameters of the shared model,
//! one measured point at a time.
//!
//! State: the stacked parameter vector of the [`ForwardModel`] (fixed parameters never move) and
//! the covariance P of the free ones. Each parameter may drift as a random walk: between two
//! measurements Δt apart its variance grows by q²·Δt (`process_noise`, in the parameter's unit
//! per √s; 0 for a constant), which is how slowly drifting quantities such as thermal growth are
//! tracked while constants converge.
//!
//! Update for a record with covariance R (measured − predicted, as in [`crate::residuals`]):
//! ν = z − h(x), H = ∂h/∂x (the model's analytic Jacobian, free columns), S = H·P·Hᵀ + R,
//! K = P·Hᵀ·S⁻¹, x ← x + K·ν, P ← P − K·S·Kᵀ (symmetrised). The normalised innovation squared
//! NIS = νᵀS⁻¹ν is χ²(3) when the model explains the data:
//! * a single NIS beyond the gate (probability `gate_probability` under the model) is an outlier:
//!   the update is skipped and counted;
//! * the sum of the last `window` NIS values is χ²(3·window); when its upper-tail probability falls
//!   below `alarm_probability` the model has stopped explaining the data (a crash shifted an axis,
//!   a term is missing) and the update says so. A run of `window`/2 consecutive outliers is an
//!   alarm too (a step so large that every measurement after it fails the gate). On an alarm the filter forgets
//!   the data's information by `alarm_inflation` (P⁻¹ ← P₀⁻¹ + (P⁻¹ − P₀⁻¹)/`alarm_inflation`, [`ranges`]) so it
//!   re-converges to the new state instead of averaging over the step: the covariance opens along the
//!   directions the data inform, never beyond the prior P₀.
//!
//! What keeps a published state one a user can apply:
//! * no variance exceeds the prior's (itself no wider than half the parameter's possible range),
//!   neither on an alarm nor by a random walk;
//! * a parameter the data have not informed (less than [`observability::MIN_INFORMATION`] of its
//!   prior's information: no measurement so far depended on it) is held at its start value — the
//!   update treats it as not measured — and a combination of parameters the data cannot separate
//!   stays at its prior; [`RecursiveEstimator::observability`] names both;
//! * every free parameter is kept inside its possible range ([`ranges::possible_range`]); one
//!   held at an edge is named too.
//!
//! Everything is deterministic: the same records in the same order give the same states bit for
//! bit (what the estimator node's `--bag` replay relies on).

use std::collections::VecDeque;

use metrocell_model::{ForwardModel, ParameterSetup, Workspace, TRACKER_ROWS};
use metrocell_physics::PhysicsError;
use nalgebra::{DMatrix, Matrix3, Vector3};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::records::MeasurementRecord;

pub mod observability;
pub mod ranges;

pub use observability::{Observability, Unobserved};
pub use ranges::{possible_range, start_range};

/// Settings of the filter.
#[derive(Debug, Clone, PartialEq)]
pub struct RecursiveOptions {
    /// Random-walk intensity q per stacked parameter (unit per √s); 0 = constant.
    pub process_noise: Vec<f64>,
    /// A single innovation whose χ²(3) tail probability is below this is an outlier.
    pub gate_probability: f64,
    /// Measurements in the moving NIS test.
    pub window: usize,
    /// The moving test alarms below this tail probability.
    pub alarm_probability: f64,
    /// On an alarm the data's information is divided by this (a well-measured parameter's
    /// variance grows by about this factor, none beyond its prior).
    pub alarm_inflation: f64,
}

impl RecursiveOptions {
    /// Constant parameters, 1e-6 outlier gate, a 10-measurement window alarming at 1e-3.
    pub fn constant(n: usize) -> Self {
        Self {
            process_noise: vec![0.0; n],
            gate_probability: 1e-6,
            window: 10,
            alarm_probability: 1e-3,
            alarm_inflation: 100.0,
        }
    }
}

/// What one measurement did.
#[derive(Debug, Clone, PartialEq)]
pub struct Update {
    /// measured − predicted before the update, m.
    pub innovation: Vector3<f64>,
    pub nis: f64,
    /// false: rejected as an outlier (or unusable covariance), the state is unchanged.
    pub accepted: bool,
    /// Tail probability of the windowed NIS sum (1 until the window is full).
    pub window_probability: f64,
    /// The model stopped explaining the data at this measurement.
    pub alarm: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum RecursiveError {
    #[error("{0}")]
    Model(#[from] PhysicsError),
    #[error("initial covariance must be {n} × {n} over the free parameters and positive semi-definite, finite")]
    BadCovariance { n: usize },
    #[error("process noise has {got} entries, the model has {n} parameters")]
    ProcessNoise { got: usize, n: usize },
}

/// The filter.
#[derive(Debug, Clone)]
pub struct RecursiveEstimator {
    x: Vec<f64>,
    free: Vec<usize>,
    p: DMatrix<f64>,
    options: RecursiveOptions,
    last_time: Option<f64>,
    nis_window: VecDeque<f64>,
    gate: f64,
    accepted: u64,
    rejected: u64,
    consecutive_rejects: usize,
    alarms: u64,
    sum_squared_innovation: f64,
    jacobian: DMatrix<f64>,
    /// Per free parameter: the prior σ, no σ of the filter exceeds it.
    prior_sigma: Vec<f64>,
    /// Per free parameter: its possible range.
    range: Vec<(f64, f64)>,
    /// The information of every accepted measurement about the free parameters, prior-whitened
    /// (see [`observability`]); not faded by alarms.
    information: DMatrix<f64>,
    /// Per free parameter: its value was clamped to an edge of its possible range by the last
    /// update that moved it.
    at_bound: Vec<bool>,
}

impl RecursiveEstimator {
    /// Start at `x0` (stacked) with covariance `p0` over the free parameters of `setup` (in
    /// stacked order).
    pub fn new(
        model: &ForwardModel,
        setup: &ParameterSetup,
        x0: Vec<f64>,
        p0: DMatrix<f64>,
        options: RecursiveOptions,
    ) -> Result<Self, RecursiveError> {
        let n = model.param_count();
        if options.process_noise.len() != n {
            return Err(RecursiveError::ProcessNoise {
                got: options.process_noise.len(),
                n,
            });
        }
        let free = setup.free_indices();
        let k = free.len();
        if p0.shape() != (k, k)
            || !p0.iter().all(|v| v.is_finite())
            || (0..k).any(|i| p0[(i, i)] < 0.0)
        {
            return Err(RecursiveError::BadCovariance { n: k });
        }
        let gate = ChiSquared::new(3.0)
            .map(|d| d.inverse_cdf(1.0 - options.gate_probability))
            .unwrap_or(f64::INFINITY);
        let specs = Self::specs(model);
        let start = Self::initial_covariance(model, setup);
        // the prior: the setup's (or a wider start's), never wider than half the possible range
        let prior_sigma: Vec<f64> = free
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                start[(i, i)]
                    .max(p0[(i, i)])
                    .sqrt()
                    .min(ranges::possible_half_width(&specs[s]))
            })
            .collect();
        let range: Vec<(f64, f64)> = free.iter().map(|&s| possible_range(&specs[s])).collect();
        let information = Self::information_of_start(&p0, &prior_sigma);
        let mut filter = Self {
            x: x0,
            free,
            p: p0,
            options,
            last_time: None,
            nis_window: VecDeque::new(),
            gate,
            accepted: 0,
            rejected: 0,
            consecutive_rejects: 0,
            alarms: 0,
            sum_squared_innovation: 0.0,
            jacobian: DMatrix::zeros(TRACKER_ROWS, n),
            prior_sigma,
            range,
            information,
            at_bound: vec![false; k],
        };
        filter.clamp_to_ranges(None);
        Ok(filter)
    }

    fn specs(model: &ForwardModel) -> Vec<metrocell_physics::ParamSpec> {
        model
            .machine_terms
            .param_specs()
            .into_iter()
            .chain(model.instrument_terms.param_specs())
            .collect()
    }

    /// What a start covariance already knows beyond the prior (a state saved by an earlier
    /// run): D·P₀⁻¹·D − I, prior-whitened; zero for a start at the prior.
    fn information_of_start(p0: &DMatrix<f64>, sigma: &[f64]) -> DMatrix<f64> {
        let k = p0.nrows();
        let inv = |s: f64| if s > 0.0 { 1.0 / s } else { 0.0 };
        let white = DMatrix::from_fn(k, k, |i, j| p0[(i, j)] * inv(sigma[i]) * inv(sigma[j]));
        match white.clone().cholesky() {
            Some(c) if white != DMatrix::identity(k, k) => {
                let info = c.inverse() - DMatrix::identity(k, k);
                DMatrix::from_fn(k, k, |i, j| {
                    if sigma[i] > 0.0 && sigma[j] > 0.0 {
                        0.5 * (info[(i, j)] + info[(j, i)])
                    } else {
                        0.0
                    }
                })
            }
            _ => DMatrix::zeros(k, k),
        }
    }

    /// A start covariance from the setup: a prior's σ², else (half the [`start_range`])².
    pub fn initial_covariance(model: &ForwardModel, setup: &ParameterSetup) -> DMatrix<f64> {
        let specs = Self::specs(model);
        let free = setup.free_indices();
        DMatrix::from_fn(free.len(), free.len(), |i, j| {
            if i != j {
                return 0.0;
            }
            let k = free[i];
            match setup.priors[k] {
                Some(p) => p.sigma * p.sigma,
                None => {
                    let (lo, hi) = start_range(&specs[k]);
                    let half = 0.5 * (hi - lo);
                    half * half
                }
            }
        })
    }

    /// The stacked parameter vector.
    pub fn state(&self) -> &[f64] {
        &self.x
    }
    /// Covariance over the free parameters (stacked order of [`Self::free_indices`]).
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.p
    }
    pub fn free_indices(&self) -> &[usize] {
        &self.free
    }
    /// (accepted, rejected as outliers, alarms) so far.
    pub fn counts(&self) -> (u64, u64, u64) {
        (self.accepted, self.rejected, self.alarms)
    }
    /// RMS of the accepted innovations per coordinate, m.
    pub fn innovation_rms(&self) -> f64 {
        if self.accepted == 0 {
            0.0
        } else {
            (self.sum_squared_innovation / (3 * self.accepted) as f64).sqrt()
        }
    }

    fn predict_to(&mut self, time: f64) {
        if let Some(t0) = self.last_time {
            let dt = (time - t0).max(0.0);
            for (i, &k) in self.free.iter().enumerate() {
                let q = self.options.process_noise[k];
                // a random walk opens the variance up to the prior's, not beyond
                let room = (self.prior_sigma[i] * self.prior_sigma[i] - self.p[(i, i)]).max(0.0);
                self.p[(i, i)] += (q * q * dt).min(room);
            }
        }
        self.last_time = Some(match self.last_time {
            Some(t0) => t0.max(time),
            None => time,
        });
    }

    /// Take one measured point. `work` is [`Workspace::new`] of the same model.
    pub fn update(
        &mut self,
        model: &ForwardModel,
        record: &MeasurementRecord,
        work: &mut Workspace,
    ) -> Result<Update, RecursiveError> {
        self.predict_to(record.time);
        let kin = model.kinematic_truth(&self.x)?;
        let mut signals = record.signals.clone();
        let pred = model.tracker_jacobian(
            &self.x,
            &kin,
            &record.q,
            &mut signals,
            work,
            &mut self.jacobian,
        )?;
        let nu = record.measured - pred.measured_point();
        let k = self.free.len();
        let mut h = DMatrix::from_fn(3, k, |r, c| self.jacobian[(r, self.free[c])]);
        // this record's information (prior-whitened, on the true Jacobian); a parameter the
        // data have not informed yet is held: the update treats it as not measured
        let information = self.record_information(&h, &record.covariance);
        for c in 0..k {
            if self.information[(c, c)] + information.as_ref().map_or(0.0, |m| m[(c, c)])
                < observability::MIN_INFORMATION
            {
                h.column_mut(c).fill(0.0);
            }
        }
        let ph = &self.p * h.transpose(); // k × 3
        let s = Matrix3::from_fn(|r, c| (0..k).map(|i| h[(r, i)] * ph[(i, c)]).sum::<f64>())
            + record.covariance;
        let Some(s_inv) = s.try_inverse().filter(|m| m.iter().all(|v| v.is_finite())) else {
            self.rejected += 1;
            return Ok(Update {
                innovation: nu,
                nis: f64::NAN,
                accepted: false,
                window_probability: 1.0,
                alarm: false,
            });
        };
        let nis = (nu.transpose() * s_inv * nu)[(0, 0)];
        if !(nis <= self.gate) {
            self.rejected += 1;
            self.consecutive_rejects += 1;
            let alarm = self.consecutive_rejects >= (self.options.window / 2).max(1);
            if alarm {
                self.raise_alarm();
            }
            return Ok(Update {
                innovation: nu,
                nis,
                accepted: false,
                window_probability: self.window_probability(),
                alarm,
            });
        }
        self.consecutive_rejects = 0;
        // K = P Hᵀ S⁻¹; x += K ν; P -= K S Kᵀ = P Hᵀ S⁻¹ H P
        let s_inv_d = DMatrix::from_fn(3, 3, |r, c| s_inv[(r, c)]);
        let gain = &ph * &s_inv_d; // k × 3
        let step = &gain * DMatrix::from_column_slice(3, 1, nu.as_slice());
        for (i, &kk) in self.free.iter().enumerate() {
            self.x[kk] += step[(i, 0)];
        }
        self.p -= &gain * ph.transpose();
        self.p = (&self.p + self.p.transpose()) * 0.5;
        if let Some(m) = information {
            self.information += m;
        }
        self.clamp_to_ranges(Some(step.as_slice()));
        self.accepted += 1;
        self.sum_squared_innovation += nu.norm_squared();
        self.nis_window.push_back(nis);
        if self.nis_window.len() > self.options.window {
            self.nis_window.pop_front();
        }
        let window_probability = self.window_probability();
        let alarm = window_probability < self.options.alarm_probability;
        if alarm {
            self.raise_alarm();
        }
        Ok(Update {
            innovation: nu,
            nis,
            accepted: true,
            window_probability,
            alarm,
        })
    }

    /// Dᵀ·Hᵀ·R⁻¹·H·D for one record (D = diag of the prior σ); None when R is not invertible.
    fn record_information(
        &self,
        h: &DMatrix<f64>,
        covariance: &Matrix3<f64>,
    ) -> Option<DMatrix<f64>> {
        let r_inv = covariance
            .try_inverse()
            .filter(|m| m.iter().all(|v| v.is_finite()))?;
        let k = self.free.len();
        let hw = DMatrix::from_fn(3, k, |r, c| h[(r, c)] * self.prior_sigma[c]);
        let r_inv = DMatrix::from_fn(3, 3, |r, c| r_inv[(r, c)]);
        Some(hw.transpose() * r_inv * hw)
    }

    /// Keep every free parameter inside its possible range; `step` (free order) is what the
    /// last update moved each by (None: at the start).
    fn clamp_to_ranges(&mut self, step: Option<&[f64]>) {
        for (i, &s) in self.free.iter().enumerate() {
            let (lo, hi) = self.range[i];
            if self.x[s] < lo {
                self.x[s] = lo;
                self.at_bound[i] = true;
            } else if self.x[s] > hi {
                self.x[s] = hi;
                self.at_bound[i] = true;
            } else if step.is_some_and(|d| d[i] != 0.0) {
                self.at_bound[i] = false;
            }
        }
    }

    /// What the measurements so far leave unobserved (held at the start values) and which
    /// parameters are held at an edge of their possible range; stacked indices (name them with
    /// the model's `param_names`). Costs an eigen-decomposition over the free parameters.
    pub fn observability(&self) -> Observability {
        Observability {
            unobserved: observability::unobserved(&self.information, &self.free),
            at_bound: self.at_bound(),
        }
    }

    /// The free parameters (stacked indices) no measurement so far has informed: cheap, for
    /// every update (the combinations the data cannot separate need [`Self::observability`]).
    pub fn held(&self) -> Vec<usize> {
        (0..self.free.len())
            .filter(|&i| self.information[(i, i)] < observability::MIN_INFORMATION)
            .map(|i| self.free[i])
            .collect()
    }

    /// The free parameters (stacked indices) held at an edge of their possible range: cheap.
    pub fn at_bound(&self) -> Vec<usize> {
        self.free
            .iter()
            .zip(&self.at_bound)
            .filter(|(_, &b)| b)
            .map(|(&s, _)| s)
            .collect()
    }

    /// The data's information about the free parameters, prior-whitened (free order; see
    /// [`observability`]).
    pub fn information(&self) -> &DMatrix<f64> {
        &self.information
    }

    /// The prior σ of each free parameter (free order): no σ of the filter exceeds it.
    pub fn prior_sigma(&self) -> &[f64] {
        &self.prior_sigma
    }

    fn raise_alarm(&mut self) {
        self.alarms += 1;
        // the covariance forgets; the information does not: it says what the program has
        // measured at all, which an alarm does not change
        self.p =
            ranges::fade_toward_prior(&self.p, &self.prior_sigma, self.options.alarm_inflation);
        self.nis_window.clear();
        self.consecutive_rejects = 0;
    }

    fn window_probability(&self) -> f64 {
        if self.nis_window.len() < self.options.window {
            return 1.0;
        }
        let sum: f64 = self.nis_window.iter().sum();
        ChiSquared::new(3.0 * self.nis_window.len() as f64)
            .map(|d| 1.0 - d.cdf(sum))
            .unwrap_or(1.0)
    }
}
