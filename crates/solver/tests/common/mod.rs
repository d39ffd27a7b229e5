//! Test problems shared by the solver's tests, and the scipy reference runner.
#![allow(dead_code)]

use metrocell_solver::{NotEvaluable, Problem};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::io::Write;
use std::process::{Command, Stdio};

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Standard normal draw (Box–Muller).
pub fn normal(r: &mut ChaCha8Rng) -> f64 {
    let (u1, u2): (f64, f64) = (1.0 - r.random::<f64>(), r.random::<f64>());
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Rosenbrock as least squares: r = (10(x₁ − x₀²), 1 − x₀), minimum 0 at (1, 1).
/// r = A·x − y: a linear problem with design matrix `a`. The Jacobian columns the solver does not
/// ask for are filled with `unwanted` (0 unless a test sets it), and `nan_at` puts a NaN into one
/// entry of the Jacobian.
pub struct Linear {
    pub a: DMatrix<f64>,
    pub y: Vec<f64>,
    pub unwanted: f64,
    pub nan_at: Option<(usize, usize)>,
}

impl Linear {
    pub fn new(a: DMatrix<f64>, y: Vec<f64>) -> Self {
        Linear {
            a,
            y,
            unwanted: 0.0,
            nan_at: None,
        }
    }
}

impl Problem for Linear {
    fn residual_count(&self) -> usize {
        self.a.nrows()
    }
    fn parameter_count(&self) -> usize {
        self.a.ncols()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        let ax = &self.a * nalgebra::DVector::from_column_slice(x);
        for (ri, (axi, yi)) in r.iter_mut().zip(ax.iter().zip(&self.y)) {
            *ri = axi - yi;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.residuals_and_jacobian_of(x, r, j, &vec![true; self.a.ncols()])
    }
    fn residuals_and_jacobian_of(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
        wanted: &[bool],
    ) -> Result<(), NotEvaluable> {
        self.residuals(x, r)?;
        for k in 0..self.a.ncols() {
            if wanted[k] {
                j.column_mut(k).copy_from(&self.a.column(k));
            } else {
                j.column_mut(k).fill(self.unwanted);
            }
        }
        if let Some(entry) = self.nan_at {
            j[entry] = f64::NAN;
        }
        Ok(())
    }
}

pub struct Rosenbrock;

impl Problem for Rosenbrock {
    fn residual_count(&self) -> usize {
        2
    }
    fn parameter_count(&self) -> usize {
        2
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        r[0] = 10.0 * (x[1] - x[0] * x[0]);
        r[1] = 1.0 - x[0];
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.residuals(x, r)?;
        j.copy_from_slice(&[-20.0 * x[0], -1.0, 10.0, 0.0]);
        Ok(())
    }
}

/// Exponential approach y = A + B·(1 − e^(−t/τ)); x = (A, B, τ); r = model − y.
#[derive(Clone)]
pub struct Decay {
    pub t: Vec<f64>,
    pub y: Vec<f64>,
}

impl Decay {
    pub fn model(x: &[f64], t: f64) -> f64 {
        x[0] + x[1] * (1.0 - (-t / x[2]).exp())
    }
    /// `n` samples on t ∈ [0, 10] of the model at `truth` with Gaussian noise σ.
    pub fn simulate(seed: u64, n: usize, truth: &[f64], sigma: f64) -> Decay {
        let mut r = rng(seed);
        let t: Vec<f64> = (0..n).map(|i| 10.0 * i as f64 / (n - 1) as f64).collect();
        let y = t
            .iter()
            .map(|&ti| Self::model(truth, ti) + sigma * normal(&mut r))
            .collect();
        Decay { t, y }
    }
    pub fn data(&self) -> Vec<f64> {
        self.t.iter().chain(&self.y).copied().collect()
    }
}

impl Problem for Decay {
    fn residual_count(&self) -> usize {
        self.t.len()
    }
    fn parameter_count(&self) -> usize {
        3
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        if !(x[2] > 0.0) {
            return Err(NotEvaluable(format!(
                "time constant τ = {} must be positive",
                x[2]
            )));
        }
        for i in 0..self.t.len() {
            r[i] = Self::model(x, self.t[i]) - self.y[i];
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.residuals(x, r)?;
        for (i, &t) in self.t.iter().enumerate() {
            let e = (-t / x[2]).exp();
            j[(i, 0)] = 1.0;
            j[(i, 1)] = 1.0 - e;
            j[(i, 2)] = -x[1] * e * t / (x[2] * x[2]);
        }
        Ok(())
    }
}

/// Circle through points: r = ‖p − c‖ − R, x = (cx, cy, R).
pub struct Circle {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

impl Circle {
    /// `n` points on an arc of `span` rad of the circle `truth` with radial noise σ.
    pub fn simulate(seed: u64, n: usize, truth: &[f64], span: f64, sigma: f64) -> Circle {
        let mut r = rng(seed);
        let (mut x, mut y) = (Vec::new(), Vec::new());
        for i in 0..n {
            let a = span * i as f64 / n as f64;
            let rad = truth[2] + sigma * normal(&mut r);
            x.push(truth[0] + rad * a.cos());
            y.push(truth[1] + rad * a.sin());
        }
        Circle { x, y }
    }
    pub fn data(&self) -> Vec<f64> {
        self.x.iter().chain(&self.y).copied().collect()
    }
}

impl Problem for Circle {
    fn residual_count(&self) -> usize {
        self.x.len()
    }
    fn parameter_count(&self) -> usize {
        3
    }
    fn residuals(&self, p: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        for i in 0..self.x.len() {
            r[i] = (self.x[i] - p[0]).hypot(self.y[i] - p[1]) - p[2];
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        p: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        for i in 0..self.x.len() {
            let (dx, dy) = (self.x[i] - p[0], self.y[i] - p[1]);
            let d = dx.hypot(dy);
            if d == 0.0 {
                return Err(NotEvaluable(format!("point {i} lies on the centre")));
            }
            r[i] = d - p[2];
            j[(i, 0)] = -dx / d;
            j[(i, 1)] = -dy / d;
            j[(i, 2)] = -1.0;
        }
        Ok(())
    }
}

/// The Python with scipy: `$METROCELL_PYTHON`, else the workspace's `.venv` (made by `tests/run`).
pub fn python() -> String {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return p;
    }
    let venv = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(
        venv.exists(),
        "no Python with scipy: set METROCELL_PYTHON or run tests/run (creates .venv)"
    );
    venv.to_string_lossy().into_owned()
}

/// What scipy's least_squares returned.
pub struct Reference {
    pub x: Vec<f64>,
    pub seconds: f64,
    pub status_line: String,
}

fn line(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Runs `tests/scipy_reference.py` on problem `name` (see there for the protocol).
pub fn scipy(name: &str, x0: &[f64], lower: &[f64], upper: &[f64], data: &[f64]) -> Reference {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scipy_reference.py");
    let mut child = Command::new(python())
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start python");
    let input = format!(
        "{name}\n{}\n{}\n{}\n{}\n",
        line(x0),
        line(lower),
        line(upper),
        line(data)
    );
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "scipy reference failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let x = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    let seconds = lines
        .next()
        .unwrap()
        .trim_start_matches("seconds ")
        .parse()
        .unwrap();
    Reference {
        x,
        seconds,
        status_line: lines.next().unwrap_or("").to_string(),
    }
}

pub const INF: f64 = f64::INFINITY;
