//! Benchmark: a quasi-XFYZ identification (10 002 residuals × 70 parameters) solved here and by
//! scipy.optimize.least_squares (method "trf", analytic Jacobian) on the identical problem and
//! start; prints both wall times, their ratio and how far apart the solutions are. Then the
//! normal matrix alone (30 000 × 46) against nalgebra's general product.
//!
//! `METROCELL_PYTHON=/path/to/python cargo run --release -p metrocell-solver --example solver_benchmark`
//!
//! Model (the same in `tests/scipy_reference.py`): a tracker at pose (α, β, γ, t) sees the point
//! m = Rz(γ)·Ry(β)·Rx(α)·(q + E(q)·p) + t of the nominal position q ∈ [0, 1]³ m. The error E(q)·p
//! of coordinate c is a sum over the three axes a of Legendre polynomials P_k(2q_a − 1), degrees
//! 1..7 along its own axis and 2..8 across (the linear cross terms would alias the tracker's
//! rotation), plus a twist q_x·q_y in z: 63 + 1 error parameters and 6 pose parameters.

#[path = "../tests/common/mod.rs"]
mod common;

use metrocell_solver::{solve, NotEvaluable, Options, Problem};
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::time::Instant;

const ERRORS: usize = 64;
const PARAMS: usize = ERRORS + 6;

/// (coordinate c, axis a, degree k) of each error parameter but the twist.
fn error_terms() -> Vec<(usize, usize, usize)> {
    let mut v = Vec::new();
    for c in 0..3 {
        for a in 0..3 {
            let ks = if c == a { 1..8 } else { 2..9 };
            for k in ks {
                v.push((c, a, k));
            }
        }
    }
    v
}

/// P_0..P_8 at u by Bonnet's recurrence.
fn legendre(u: f64) -> [f64; 9] {
    let mut p = [0.0; 9];
    p[0] = 1.0;
    p[1] = u;
    for k in 1..8 {
        p[k + 1] = ((2 * k + 1) as f64 * u * p[k] - k as f64 * p[k - 1]) / (k + 1) as f64;
    }
    p
}

/// R = Rz(γ)Ry(β)Rx(α) and its derivatives by α, β, γ.
fn rotation(x: &[f64]) -> (Matrix3<f64>, [Matrix3<f64>; 3]) {
    let (a, b, g) = (x[ERRORS], x[ERRORS + 1], x[ERRORS + 2]);
    let (ca, sa, cb, sb, cg, sg) = (a.cos(), a.sin(), b.cos(), b.sin(), g.cos(), g.sin());
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca);
    let ry = Matrix3::new(cb, 0.0, sb, 0.0, 1.0, 0.0, -sb, 0.0, cb);
    let rz = Matrix3::new(cg, -sg, 0.0, sg, cg, 0.0, 0.0, 0.0, 1.0);
    let drx = Matrix3::new(0.0, 0.0, 0.0, 0.0, -sa, -ca, 0.0, ca, -sa);
    let dry = Matrix3::new(-sb, 0.0, cb, 0.0, 0.0, 0.0, -cb, 0.0, -sb);
    let drz = Matrix3::new(-sg, -cg, 0.0, cg, -sg, 0.0, 0.0, 0.0, 0.0);
    (rz * ry * rx, [rz * ry * drx, rz * dry * rx, drz * ry * rx])
}

struct Xfyz {
    q: Vec<Vector3<f64>>,
    measured: Vec<Vector3<f64>>,
    /// Per point, the Legendre values of the three axes.
    basis: Vec<[[f64; 9]; 3]>,
    terms: Vec<(usize, usize, usize)>,
}

impl Xfyz {
    fn new(q: Vec<Vector3<f64>>, measured: Vec<Vector3<f64>>) -> Self {
        let basis = q
            .iter()
            .map(|p| {
                [
                    legendre(2.0 * p.x - 1.0),
                    legendre(2.0 * p.y - 1.0),
                    legendre(2.0 * p.z - 1.0),
                ]
            })
            .collect();
        Xfyz {
            q,
            measured,
            basis,
            terms: error_terms(),
        }
    }

    /// q + E(q)·p for point i.
    fn displaced(&self, i: usize, x: &[f64]) -> Vector3<f64> {
        let mut p = self.q[i];
        for (t, &(c, a, k)) in self.terms.iter().enumerate() {
            p[c] += self.basis[i][a][k] * x[t];
        }
        p.z += self.q[i].x * self.q[i].y * x[ERRORS - 1];
        p
    }

    fn predict(&self, x: &[f64]) -> Vec<Vector3<f64>> {
        let (r, _) = rotation(x);
        let t = Vector3::new(x[ERRORS + 3], x[ERRORS + 4], x[ERRORS + 5]);
        (0..self.q.len())
            .map(|i| r * self.displaced(i, x) + t)
            .collect()
    }
}

impl Problem for Xfyz {
    fn residual_count(&self) -> usize {
        3 * self.q.len()
    }
    fn parameter_count(&self) -> usize {
        PARAMS
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        for (i, m) in self.predict(x).iter().enumerate() {
            for c in 0..3 {
                r[3 * i + c] = m[c] - self.measured[i][c];
            }
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        let (rot, d) = rotation(x);
        let t = Vector3::new(x[ERRORS + 3], x[ERRORS + 4], x[ERRORS + 5]);
        for i in 0..self.q.len() {
            let p = self.displaced(i, x);
            let m = rot * p + t;
            let row = 3 * i;
            for c in 0..3 {
                r[row + c] = m[c] - self.measured[i][c];
            }
            // Each error column moves one coordinate c: R·e_c·value.
            for (col, &(c, a, k)) in self.terms.iter().enumerate() {
                let v = self.basis[i][a][k];
                for o in 0..3 {
                    j[(row + o, col)] = rot[(o, c)] * v;
                }
            }
            let twist = self.q[i].x * self.q[i].y;
            for o in 0..3 {
                j[(row + o, ERRORS - 1)] = rot[(o, 2)] * twist;
            }
            for (k, dk) in d.iter().enumerate() {
                let v = dk * p;
                for o in 0..3 {
                    j[(row + o, ERRORS + k)] = v[o];
                    j[(row + o, ERRORS + 3 + k)] = if o == k { 1.0 } else { 0.0 };
                }
            }
        }
        Ok(())
    }
}

fn main() {
    let points = 3334;
    let sigma = 2e-6;
    let mut r = common::rng(70);
    let mut truth = vec![0.0; PARAMS];
    for v in truth.iter_mut().take(ERRORS) {
        *v = 1e-5 * common::normal(&mut r);
    }
    truth[ERRORS..].copy_from_slice(&[0.02, -0.01, 0.3, 1.2, -0.4, 0.3]);
    let q: Vec<Vector3<f64>> = (0..points)
        .map(|_| {
            Vector3::new(
                rand::Rng::random(&mut r),
                rand::Rng::random(&mut r),
                rand::Rng::random(&mut r),
            )
        })
        .collect();
    let exact = Xfyz::new(q.clone(), vec![Vector3::zeros(); points]).predict(&truth);
    let measured: Vec<Vector3<f64>> = exact
        .iter()
        .map(|m| m + Vector3::from_fn(|_, _| sigma * common::normal(&mut r)))
        .collect();
    let problem = Xfyz::new(q.clone(), measured.clone());
    let mut x0 = vec![0.0; PARAMS];
    for k in 0..6 {
        x0[ERRORS + k] = truth[ERRORS + k] + if k < 3 { 0.01 } else { 0.005 };
    }
    let options = Options::default();
    let mut times = Vec::new();
    let mut solution = None;
    for _ in 0..5 {
        let start = Instant::now();
        let s = solve(&problem, &x0, &options).expect("solve");
        times.push(start.elapsed().as_secs_f64());
        solution = Some(s);
    }
    times.sort_by(f64::total_cmp);
    let ours = solution.expect("five runs");
    let median = times[2];
    let data: Vec<f64> = q
        .iter()
        .zip(&measured)
        .flat_map(|(a, b)| [a.x, a.y, a.z, b.x, b.y, b.z])
        .collect();
    let n = PARAMS;
    let reference = common::scipy(
        "xfyz",
        &x0,
        &vec![-common::INF; n],
        &vec![common::INF; n],
        &data,
    );
    let u = ours.standard_uncertainties().expect("identifiable");
    let scale = reference.x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = ours
        .x
        .iter()
        .zip(&reference.x)
        .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    let diff_sigma = (0..n).fold(0.0f64, |a, k| {
        a.max((ours.x[k] - reference.x[k]).abs() / u[k])
    });
    let err_rel = (0..ERRORS).fold(0.0f64, |a, k| {
        a.max((ours.x[k] - reference.x[k]).abs() / reference.x[k].abs())
    });
    println!(
        "problem: {} residuals × {n} parameters, σ = {:.1} µm",
        3 * points,
        sigma * 1e6
    );
    println!("metrocell-solver: median {:.1} ms of 5 ({} iterations, {:?}), residual RMS {:.3} µm, σ̂₀ = {:.3} µm", median * 1e3, ours.iterations, ours.termination, ours.residual_rms * 1e6, ours.variance_factor.unwrap_or(f64::NAN).sqrt() * 1e6);
    println!(
        "scipy trf:        {:.1} ms ({})",
        reference.seconds * 1e3,
        reference.status_line
    );
    println!("ratio scipy/ours: {:.1}×", reference.seconds / median);
    println!("solutions: max |Δx| / max |x| = {:.2e}; max |Δx_k|/u_k = {:.2e}; max per-parameter relative (error terms) = {:.2e}", diff / scale, diff_sigma, err_rel);
    normal_matrix_benchmark();
}

/// The normal matrix of a Jacobian shaped like the XFYZ fit's (30 000 × 75, 46 free columns),
/// as the solver forms it (`normal_matrix`: its register-tiled kernel on the free columns, read
/// in place) against nalgebra's general product Jᵀ·J (`matrixmultiply`'s dgemm, what the
/// solver used before) on the same columns and their transpose copied out beforehand (the
/// copies not timed). Fastest of 20 each, same run.
fn normal_matrix_benchmark() {
    let (m, n) = (30_000, 75);
    let j = DMatrix::from_fn(m, n, |i, k| ((i * 31 + k * 17) % 101) as f64 / 101.0 - 0.5);
    let free: Vec<usize> = (0..n)
        .filter(|k| k % 5 != 1 && k % 7 != 3)
        .take(46)
        .collect();
    let selected = j.select_columns(&free);
    let transposed = selected.transpose();
    let fastest = |f: &mut dyn FnMut() -> DMatrix<f64>| {
        let mut best = f64::INFINITY;
        let mut last = DMatrix::zeros(0, 0);
        for _ in 0..20 {
            let t = Instant::now();
            last = f();
            best = best.min(t.elapsed().as_secs_f64());
        }
        (best, last)
    };
    let (ours, a) = fastest(&mut || metrocell_solver::normal_matrix(&j, &free));
    let (peer, b) = fastest(&mut || &transposed * &selected);
    println!("normal matrix {m} × {} (of {n} columns): metrocell {:.2} ms, nalgebra Jᵀ·J (dgemm) {:.2} ms, ratio {:.2}×; max |ΔA| / max |A| = {:.1e}", free.len(), ours * 1e3, peer * 1e3, peer / ours, (&a - &b).amax() / b.amax());
}
