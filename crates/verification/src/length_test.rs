//! Length-measurement conformity in the manner of ISO 10360-2 (seed 001 §2.5): lengths along
//! seven directions — the three axes and the four space diagonals (two face diagonals when the
//! mesh is a plane) — at five lengths each, measured three times: 105 length errors, each
//! judged against the maximum permissible error
//!
//!   MPE(L) = min(A + L/K, B)   (form 1; form 2 without B, form 3 with B alone)
//!
//! in the convention of CMM specifications: A and B in µm, L in mm, K dimensionless (a CMM of
//! "1.5 + L/333 µm" has A = 1.5 µm, K = 333); [`Mpe`] holds A and B in m and applies it so.
//!
//! with its expanded uncertainty U as ISO 14253-1 decides: conformance proven when
//! |E| + U ≤ MPE, non-conformance when |E| − U > MPE, otherwise not proven either way.
//!
//! A length here is between two mesh points along the direction, measured as the distance of
//! the tracker's (registered) points against the commanded distance: E = |P_j − P_i| − |q_j − q_i|.

use nalgebra::Vector3;

/// The maximum permissible error of a length measurement, in one of the three forms; A and B in
/// m, K dimensionless (L in mm giving µm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mpe {
    /// ±min(A + L/K, B)
    Capped { a: f64, k: f64, b: f64 },
    /// ±(A + L/K)
    Linear { a: f64, k: f64 },
    /// ±B
    Constant { b: f64 },
}

impl Mpe {
    /// MPE at length `l` (m), in m.
    pub fn at(&self, l: f64) -> f64 {
        let linear = |a: f64, k: f64| a + (l * 1e3 / k) * 1e-6;
        match *self {
            Mpe::Capped { a, k, b } => linear(a, k).min(b),
            Mpe::Linear { a, k } => linear(a, k),
            Mpe::Constant { b } => b,
        }
    }
}

/// ISO 14253-1's decision with the measurement's expanded uncertainty.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    Conforms,
    DoesNotConform,
    NotProven,
}

impl Decision {
    pub fn judge(error: f64, expanded_uncertainty: f64, mpe: f64) -> Decision {
        if error.abs() + expanded_uncertainty <= mpe {
            Decision::Conforms
        } else if error.abs() - expanded_uncertainty > mpe {
            Decision::DoesNotConform
        } else {
            Decision::NotProven
        }
    }

    pub fn in_words(self) -> &'static str {
        match self {
            Decision::Conforms => "conforms",
            Decision::DoesNotConform => "does not conform",
            Decision::NotProven => "not proven (within U of the MPE)",
        }
    }
}

/// One length of the test: between mesh points `from` and `to` (indices) along `direction`.
#[derive(Debug, Clone, PartialEq)]
pub struct LengthCase {
    pub direction: String,
    pub from: usize,
    pub to: usize,
    /// m
    pub nominal: f64,
}

/// The test's lengths on `points` (commanded positions, m): for each of the seven directions
/// the mesh spans, up to five pairs of points along it, their lengths spread from the shortest
/// to the longest the mesh holds in that direction, each pair the one nearest the mesh's
/// centre. Fewer lengths exist on a small mesh: the caller says so.
pub fn length_cases(points: &[[f64; 3]]) -> Vec<LengthCase> {
    let v: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
    let centre = v.iter().sum::<Vector3<f64>>() / v.len().max(1) as f64;
    let spans: Vec<bool> = (0..3)
        .map(|a| {
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[a]), h.max(p[a])));
            hi - lo > 1e-9
        })
        .collect();
    let mut directions: Vec<(String, Vector3<f64>)> = vec![];
    for (a, name) in ["X", "Y", "Z"].iter().enumerate() {
        if spans[a] {
            let mut d = Vector3::zeros();
            d[a] = 1.0;
            directions.push((name.to_string(), d));
        }
    }
    let spanned: Vec<usize> = (0..3).filter(|&a| spans[a]).collect();
    let signs: Vec<Vec<f64>> = match spanned.len() {
        3 => vec![
            vec![1., 1., 1.],
            vec![-1., 1., 1.],
            vec![1., -1., 1.],
            vec![1., 1., -1.],
        ],
        2 => vec![vec![1., 1.], vec![-1., 1.]],
        _ => vec![],
    };
    for s in signs {
        let mut d = Vector3::zeros();
        let mut name = String::new();
        for (k, &a) in spanned.iter().enumerate() {
            d[a] = s[k];
            name.push_str(&format!(
                "{}{}",
                if s[k] > 0.0 { "+" } else { "-" },
                ["X", "Y", "Z"][a]
            ));
        }
        directions.push((format!("diagonal {name}"), d.normalize()));
    }
    let mut out = vec![];
    for (name, d) in directions {
        // every pair along d, by length (µm-rounded), keeping the one nearest the centre
        let mut by_length: std::collections::BTreeMap<i64, (f64, usize, usize, f64)> =
            Default::default();
        for i in 0..v.len() {
            for j in 0..v.len() {
                let w = v[j] - v[i];
                let l = w.norm();
                if l < 1e-9 || (w / l - d).norm() > 1e-6 {
                    continue;
                }
                let mid = (v[i] + v[j]) / 2.0;
                let off = (mid - centre).norm();
                let key = (l * 1e6).round() as i64;
                let e = by_length.entry(key).or_insert((f64::MAX, i, j, l));
                if off < e.0 - 1e-12 {
                    *e = (off, i, j, l);
                }
            }
        }
        let lengths: Vec<(f64, usize, usize, f64)> = by_length.into_values().collect();
        let n = lengths.len();
        let picks: Vec<usize> = if n <= 5 {
            (0..n).collect()
        } else {
            let mut p: Vec<usize> = (0..5).map(|k| (k * (n - 1) + 2) / 4).collect();
            p.dedup();
            p
        };
        for k in picks {
            let (_, i, j, l) = lengths[k];
            out.push(LengthCase {
                direction: name.clone(),
                from: i,
                to: j,
                nominal: l,
            });
        }
    }
    out
}

/// E = |P_to − P_from| − nominal, the measured points P (m).
pub fn length_error(case: &LengthCase, measured: &[Vector3<f64>]) -> f64 {
    (measured[case.to] - measured[case.from]).norm() - case.nominal
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;

    /// Seed 001 §2.5 / part 1 fixture 10: 5 lengths × 7 directions × 3 repetitions = 105
    /// measurements, all within MPE = ±min(A + L/K, B).
    #[test]
    fn a_mesh_gives_105_measurements_and_mpe_forms_evaluate() {
        let mesh = Mesh {
            min: [0.0, 0.0, 0.0],
            max: [0.8, 0.8, 0.8],
            step: 0.1,
        };
        let pts = mesh.points().unwrap();
        let cases = length_cases(&pts);
        let directions: std::collections::BTreeSet<&str> =
            cases.iter().map(|c| c.direction.as_str()).collect();
        assert_eq!(directions.len(), 7);
        assert_eq!(cases.len(), 35);
        assert_eq!(cases.len() * 3, 105);
        for c in &cases {
            let d = Vector3::from(pts[c.to]) - Vector3::from(pts[c.from]);
            assert!((d.norm() - c.nominal).abs() < 1e-12);
        }
        // along X, 0.1 … 0.8 m exist: five spread from the shortest to the longest
        let x: Vec<f64> = cases
            .iter()
            .filter(|c| c.direction == "X")
            .map(|c| c.nominal)
            .collect();
        assert_eq!(x.len(), 5);
        assert!(
            (x[0] - 0.1).abs() < 1e-9 && (x[4] - 0.8).abs() < 1e-9,
            "{x:?}"
        );
        // MPE forms: A = 5 µm, K = 200, B = 8 µm
        let f1 = Mpe::Capped {
            a: 5e-6,
            k: 200.0,
            b: 8e-6,
        };
        assert!((f1.at(0.4) - 7e-6).abs() < 1e-15, "5 µm + 400 mm/200");
        assert!((f1.at(1.0) - 8e-6).abs() < 1e-15, "B caps form 1");
        let f2 = Mpe::Linear { a: 5e-6, k: 200.0 };
        assert!((f2.at(1.0) - 10e-6).abs() < 1e-15);
        let f3 = Mpe::Constant { b: 8e-6 };
        assert!((f3.at(0.3) - 8e-6).abs() < 1e-15);
        // the test's verdict over its 105 measurements: all within the MPE (U small beside it)
        // conforms; one beyond it by more than U does not
        let judged = |errors: &[f64]| -> Vec<Decision> {
            cases
                .iter()
                .cycle()
                .zip(errors)
                .map(|(c, e)| Decision::judge(*e, 0.5e-6, f1.at(c.nominal)))
                .collect()
        };
        let mut errors: Vec<f64> = (0..105).map(|i| ((i as f64) * 0.37).sin() * 4e-6).collect();
        assert_eq!(errors.len(), 105);
        assert!(judged(&errors).iter().all(|d| *d == Decision::Conforms));
        errors[40] = 9e-6;
        let d = judged(&errors);
        assert_eq!(
            d.iter().filter(|d| **d == Decision::DoesNotConform).count(),
            1
        );
        assert_eq!(d[40], Decision::DoesNotConform);
    }

    #[test]
    fn iso_14253_decisions() {
        assert_eq!(Decision::judge(3e-6, 1e-6, 5e-6), Decision::Conforms);
        assert_eq!(Decision::judge(-4.5e-6, 1e-6, 5e-6), Decision::NotProven);
        assert_eq!(Decision::judge(5.5e-6, 1e-6, 5e-6), Decision::NotProven);
        assert_eq!(
            Decision::judge(-6.5e-6, 1e-6, 5e-6),
            Decision::DoesNotConform
        );
    }

    #[test]
    fn a_plane_has_two_face_diagonals() {
        let mesh = Mesh {
            min: [0.0, 0.0, 0.1],
            max: [0.4, 0.4, 0.1],
            step: 0.1,
        };
        let cases = length_cases(&mesh.points().unwrap());
        let directions: std::collections::BTreeSet<&str> =
            cases.iter().map(|c| c.direction.as_str()).collect();
        assert_eq!(directions.len(), 4, "{directions:?}");
        assert_eq!(
            cases.len(),
            4 * 4,
            "four lengths per direction on a 5 × 5 plane"
        );
    }
}
