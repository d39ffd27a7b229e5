//! Thesis (seed 001) fixtures through this crate's processing, to their stated digits.
//!
//! Run: `cargo test -p metrocell-laser-tracker --test thesis_fixtures`

use metrocell_compensation::{AirData, SphericalNoise};
use metrocell_laser_tracker::reading::{AirSource, EdlenForm, ReadingProcessor};
use metrocell_laser_tracker::warmup::{fit_warmup, WarmupSample};
use metrocell_physics::instrument::tracker_uncertainty::TrackerRangeBudget;
use metrocell_physics::instrument::tracker_warmup::warmup_drift;

#[test]
fn refractive_index_at_99_kpa_20_c_50_percent() {
    let air = AirData {
        temperature: 20.0,
        pressure: 99_000.0,
        humidity: 0.5,
    };
    let p = ReadingProcessor {
        noise: SphericalNoise {
            radial_base: 0.0,
            radial_per_metre: 0.0,
            angular: 0.0,
        },
        air: AirSource::Configured(air),
        form: EdlenForm::ShopFloor,
        max_range: 80.0,
    };
    assert!((p.index(&air) - 1.000265156791).abs() < 1e-11);
}

#[test]
fn combined_tracker_uncertainty_is_11_2_um_at_2_m() {
    // P1 eqs 12–14: u_AA = 5, u_R = 2.5, u_WS = 0.385, u_ED = 0 ppm (2σ) → U(k = 2) = 5.6 ppm
    let budget = TrackerRangeBudget {
        absolute_accuracy: 5e-6,
        repeatability: 2.5e-6,
        weather_station: 0.385e-6,
        environment_deviation: 0.0,
    };
    let noise = SphericalNoise {
        radial_base: 0.0,
        radial_per_metre: budget.standard_per_metre(),
        angular: 0.0,
    };
    let p = ReadingProcessor {
        noise,
        air: AirSource::Station,
        form: EdlenForm::ShopFloor,
        max_range: 80.0,
    };
    let expanded_um = 2.0 * p.radial_sigma(2.0) * 1e6;
    assert_eq!(format!("{expanded_um:.1}"), "11.2");
}

#[test]
fn warm_up_curves_settle_at_90_and_270_min() {
    // eqs 3.2 (API, τ = 30 min) and 3.3 (Leica, τ = 90 min), one point every 30 s for 270 min
    for (a, b, tau_min, settle) in [
        (0.159798, 19e-6, 30.0, "90"),
        (0.154999, 75e-6, 90.0, "270"),
    ] {
        let s: Vec<WarmupSample> = (1..=540)
            .map(|k| {
                let t = 30.0 * k as f64;
                WarmupSample {
                    t,
                    value: warmup_drift(a, b, tau_min * 60.0, t),
                    sigma: 1e-6,
                }
            })
            .collect();
        let f = fit_warmup(&s).unwrap();
        // 95 % settling, to the thesis's resolution (10 min)
        assert_eq!(
            format!("{:.0}", (f.settling_time() / 600.0).round() * 10.0),
            settle
        );
        assert!((f.b - b).abs() < 1e-8 && (f.tau / 60.0 - tau_min).abs() < 0.01);
    }
}
