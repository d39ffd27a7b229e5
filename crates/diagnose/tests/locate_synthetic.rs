//! Noise tests and localisation on residuals made here with plain random numbers (not by the
//! twin): null data must stay quiet at the stated rate, and each planted structure must be found
//! where it was planted.

use metrocell_diagnose::locate::{locate, LocateOptions, Place};
use metrocell_diagnose::noise_tests::noise_report;
use metrocell_diagnose::residual::ResidualSample;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SIGMA: f64 = 5e-6;

/// A serpentine grid over 400 × 300 × 200 mm visited over two hours, x residuals only, with the
/// x approach direction alternating by row.
fn samples(
    seed: u64,
    noise_scale: f64,
    effect: impl Fn(&Vector3<f64>, f64, f64) -> f64,
) -> Vec<ResidualSample> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut t = 0.0;
    for k in 0..4 {
        for j in 0..10 {
            for i in 0..10 {
                let (ii, dir) = if j % 2 == 0 { (i, 1.0) } else { (9 - i, -1.0) };
                let p = Vector3::new(
                    0.4 * ii as f64 / 9.0,
                    0.3 * j as f64 / 9.0,
                    0.2 * k as f64 / 3.0,
                );
                let noise: f64 = rng.sample::<f64, _>(rand_distr_normal()) * SIGMA * noise_scale;
                out.push(ResidualSample {
                    channel: "tracker".into(),
                    axis: 0,
                    time: t,
                    position: p,
                    residual: noise + effect(&p, dir, t),
                    sigma: SIGMA,
                    approach: [Some(dir), Some(1.0), Some(1.0)],
                    conditions: vec![("temperature.x_scale".into(), 20.0 + 2.0 * (t / 7200.0))],
                });
                t += 18.0;
            }
        }
    }
    out
}

/// Standard normal via Box–Muller on the crate-free `rand` API.
fn rand_distr_normal() -> impl rand::distr::Distribution<f64> {
    struct BoxMuller;
    impl rand::distr::Distribution<f64> for BoxMuller {
        fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
            let u1: f64 = rng.random::<f64>().max(1e-300);
            let u2: f64 = rng.random();
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
    }
    BoxMuller
}

#[test]
fn null_data_stays_quiet_at_the_stated_rate() {
    let options = LocateOptions::default();
    let runs = 200;
    let mut false_structure = 0;
    let mut noise_rejections = 0;
    for seed in 0..runs {
        let s = samples(seed, 1.0, |_, _, _| 0.0);
        if !locate(&s, &options).is_empty() {
            false_structure += 1;
        }
        if !noise_report(&s, 10)
            .iter()
            .all(|c| c.consistent_with_noise(0.01))
        {
            noise_rejections += 1;
        }
    }
    // family-wise α = 0.01 per run: ≤ 5 of 200 allows for chance (binomial 99.5th percentile ≈ 6)
    assert!(
        false_structure <= 6,
        "{false_structure} of {runs} null runs claimed structure"
    );
    assert!(
        noise_rejections <= 6,
        "{noise_rejections} of {runs} null runs rejected the noise model"
    );
}

#[test]
fn understated_noise_is_flagged_by_chi_square_not_taken_for_structure() {
    let s = samples(3, 1.6, |_, _, _| 0.0);
    let report = noise_report(&s, 10);
    let chi = report[0]
        .tests
        .iter()
        .find(|t| t.name == "chi_square")
        .unwrap();
    assert!(
        chi.p_adjusted < 1e-6 && (report[0].chi2_per_dof - 2.56).abs() < 0.5,
        "{report:?}"
    );
    let found = locate(&s, &LocateOptions::default());
    assert!(
        found.is_empty(),
        "{:?}",
        found.iter().map(|f| f.describe()).collect::<Vec<_>>()
    );
}

#[test]
fn reversal_error_is_located_by_direction() {
    // 3σ backlash: +β/2 moving +, −β/2 moving −
    let beta = 3.0 * SIGMA;
    let s = samples(11, 1.0, |_, dir, _| dir * beta / 2.0);
    let found = locate(&s, &LocateOptions::default());
    let first = found.first().expect("structure found");
    assert!(
        matches!(first.place, Place::Direction { axis: 0, .. }),
        "{}",
        first.describe()
    );
    assert!(
        (first.effect_m.abs() - beta / 2.0).abs() < 3.0 * first.effect_sigma_m + 1e-12,
        "{}",
        first.describe()
    );
    assert!(!noise_report(&s, 10)[0].consistent_with_noise(0.01));
}

#[test]
fn local_bump_is_located_in_its_region() {
    // a 12 µm bump where x > 0.3 m and y < 0.1 m (a local defect no catalog term has)
    let s = samples(
        5,
        1.0,
        |p, _, _| if p.x > 0.3 && p.y < 0.1 { 12e-6 } else { 0.0 },
    );
    let found = locate(&s, &LocateOptions::default());
    let region = found
        .iter()
        .find(|f| matches!(f.place, Place::Region { .. }))
        .expect("a region");
    match region.place {
        Place::Region { axis, from, to } => assert!(
            (axis == 0 && from >= 0.25) || (axis == 1 && to <= 0.11),
            "{}",
            region.describe()
        ),
        _ => unreachable!(),
    }
}

#[test]
fn thermal_drift_is_located_in_time_and_by_temperature() {
    // 4 µm per K of the scale temperature, which rises 2 K over the run: a drift in time
    let s = samples(8, 1.0, |_, _, t| 4e-6 * 2.0 * (t / 7200.0));
    let found = locate(&s, &LocateOptions::default());
    assert!(found
        .iter()
        .any(|f| matches!(f.place, Place::TimeWindow { .. })));
    let corr = found
        .iter()
        .find(|f| matches!(&f.place, Place::Correlation { name } if name == "temperature.x_scale"))
        .expect("correlated with temperature");
    // effect across one standard deviation of T (2 K span uniform → σ_T ≈ 0.577 K): ≈ 2.3 µm
    assert!(
        (corr.effect_m - 4e-6 * 2.0 / 12f64.sqrt()).abs() < 3.0 * corr.effect_sigma_m,
        "{}",
        corr.describe()
    );
}
