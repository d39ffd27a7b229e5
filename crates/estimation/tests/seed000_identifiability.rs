//! Seed 000, test T6: the planar 12-parameter model of the CNC router measured at its 36 grid
//! points with X3 held constant cannot identify its 12 parameters — the rank is reported, the
//! null space is named in words, and the minimum-norm solution reproduces the field.
//!
//! The sensitivity matrix U (72 rows: e_x and e_y at each of the 36 points) is built from the
//! first-order chain the seed digest infers (§2.3 c–d; the paper gives no U): each parameter's
//! regressor of eq. 7 — ρ11 → X1 in e_x (C), ρ21 → X2 in e_y (F), Δα4 → X2 in e_x (B),
//! (Δα2 − C2·γ11) → X1 in e_y (E), Δβ4 and (Δβ2 + b2·γ11) → X3 in e_x (D), Δγ4 → X3 in e_y (G),
//! α11 → X1²/2 in e_y (I), α21 → −X2²/2 in e_x and X1·X2 in e_y (A = −α21/2, H = α21: the y
//! axis's yaw bends X and turns the X1 offset), and the angular slopes β11, β21, γ21 through the
//! Abbe lever X3: X1·X3 in e_x, X2·X3 in e_x, −X2·X3 in e_y. With X3 = 1 (the paper's "z = 1")
//! those land on C, B and F. So the rank is 8 of the digest's bound 9: A and H come from one
//! parameter in this chain.

use metrocell_estimation::inseparable;
use metrocell_solver::{solve, Identifiability, NotEvaluable, NullSpace, Options, Problem};
use nalgebra::{DMatrix, DVector};

const NAMES: [&str; 12] = [
    "ρ11",
    "ρ21",
    "Δα2 − C2·γ11",
    "Δα4",
    "Δβ2 + b2·γ11",
    "Δβ4",
    "Δγ4",
    "α11",
    "β11",
    "α21",
    "β21",
    "γ21",
];

/// The 36 grid points of the digest's hypothesised grid (62.5 … 137.5 mm, 15 mm pitch), X3 = 1.
fn grid() -> Vec<(f64, f64)> {
    let mut v = vec![];
    for i in 0..6 {
        for j in 0..6 {
            v.push((62.5 + 15.0 * i as f64, 62.5 + 15.0 * j as f64));
        }
    }
    v
}

/// U: rows e_x then e_y of each point; columns in NAMES order.
fn sensitivity() -> DMatrix<f64> {
    let pts = grid();
    let x3 = 1.0;
    let mut u = DMatrix::zeros(2 * pts.len(), 12);
    for (i, (x1, x2)) in pts.iter().enumerate() {
        let (rx, ry) = (2 * i, 2 * i + 1);
        u[(rx, 0)] = *x1; // ρ11
        u[(ry, 1)] = *x2; // ρ21
        u[(ry, 2)] = *x1; // Δα2 − C2·γ11
        u[(rx, 3)] = *x2; // Δα4
        u[(rx, 4)] = -x3; // Δβ2 + b2·γ11 (opposite to Δβ4: Table 1's ± pair)
        u[(rx, 5)] = x3; // Δβ4
        u[(ry, 6)] = x3; // Δγ4
        u[(ry, 7)] = x1 * x1 / 2.0; // α11
        u[(rx, 8)] = x1 * x3; // β11
        u[(rx, 9)] = -x2 * x2 / 2.0; // α21
        u[(ry, 9)] = x1 * x2;
        u[(rx, 10)] = x2 * x3; // β21
        u[(ry, 11)] = -x2 * x3; // γ21
    }
    u
}

struct Linear {
    u: DMatrix<f64>,
    e: DVector<f64>,
}

impl Problem for Linear {
    fn residual_count(&self) -> usize {
        self.u.nrows()
    }
    fn parameter_count(&self) -> usize {
        12
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        let v = &self.u * DVector::from_column_slice(x) - &self.e;
        r.copy_from_slice(v.as_slice());
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        j: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.residuals(x, r)?;
        j.copy_from(&self.u);
        Ok(())
    }
}

#[test]
fn t6_rank_and_null_space_in_words_and_the_minimum_norm_field() {
    let u = sensitivity();
    let labels: Vec<&str> = NAMES.to_vec();
    let id = Identifiability::analyze(&u, &labels, None).unwrap();
    assert_eq!(id.rank, 8, "{:?}", id.singular_values);
    assert!(id.rank <= 9, "T6: rank ≤ 9 (nine monomials in eq. 7)");
    assert_eq!(id.null_directions.len(), 4);
    // which parameters cannot be told apart, in words (kept in the paper's table order)
    let names: Vec<String> = NAMES.iter().map(|s| s.to_string()).collect();
    let held = inseparable(&u, &(0..12).collect::<Vec<_>>(), &names);
    let sentences: Vec<&str> = held.iter().map(|(_, s)| s.as_str()).collect();
    println!("{sentences:#?}");
    assert_eq!(
        held.iter().map(|(k, _)| NAMES[*k]).collect::<Vec<_>>(),
        ["Δβ4", "β11", "β21", "γ21"]
    );
    assert!(
        sentences[0].contains("Δβ4 is not separable from Δβ2 + b2·γ11"),
        "{}",
        sentences[0]
    );
    assert!(sentences[1].contains("β11 is not separable from ρ11"));
    assert!(sentences[2].contains("β21 is not separable from Δα4"));
    assert!(sentences[3].contains("γ21 is not separable from ρ21"));
    // the B72 field (Table 2 with A = −H/2 as this chain requires) measured at the 36 points;
    // the minimum-norm solution reproduces it exactly and splits each inseparable pair evenly
    let (b, c, d, e, f, g, h, i) = (
        5.20e-3, -7.10e-3, 4.85e-3, 1.11e-2, 1.03e-2, -1.12e-5, -2.01e-5, -1.55e-5,
    );
    let a = -h / 2.0;
    let mut meas = DVector::zeros(72);
    for (k, (x1, x2)) in grid().iter().enumerate() {
        meas[2 * k] = a * x2 * x2 + b * x2 + c * x1 + d;
        meas[2 * k + 1] = e * x1 + f * x2 + g + h * x1 * x2 + i * x1 * x1;
    }
    let problem = Linear {
        u: u.clone(),
        e: meas.clone(),
    };
    let sol = solve(
        &problem,
        &[0.0; 12],
        &Options {
            null_space: NullSpace::Truncated { rcond: 1e-10 },
            ..Options::default()
        },
    )
    .unwrap();
    let fitted = &u * DVector::from_column_slice(&sol.x);
    assert!((fitted - &meas).amax() < 1e-12, "the field is reproduced");
    let x = &sol.x;
    // C is shared by ρ11 and β11 in proportion to their columns (X1 and X1·X3, equal at X3 = 1)
    assert!(
        (x[0] - c / 2.0).abs() < 1e-12 && (x[8] - c / 2.0).abs() < 1e-12,
        "ρ11 {} β11 {}",
        x[0],
        x[8]
    );
    // Δβ4 = −(Δβ2 + b2·γ11): the ± pair of Table 1
    assert!(
        (x[5] + x[4]).abs() < 1e-12 && (x[5] - d / 2.0).abs() < 1e-12,
        "Δβ4 {} Δβ2' {}",
        x[5],
        x[4]
    );
    // the identified ones come back whole
    assert!(
        (x[9] - h).abs() < 1e-12
            && (x[7] - 2.0 * i).abs() < 1e-12
            && (x[2] - e).abs() < 1e-12
            && (x[6] - g).abs() < 1e-12
    );
    // the solver says the covariance does not exist rather than inventing one
    assert!(sol.covariance_unscaled.is_none());
}
