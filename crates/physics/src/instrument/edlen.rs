//! Refractive index of air (pure functions) and the range error it causes.
//!
//! Three formulas:
//! * [`shop_floor_index`] — the simplified Edlén equation of the thesis (eq. 5.5, NIST
//!   "shop-floor" form): n = 1 + 7.86·10⁻⁴·p/(273 + t) − 1.5·10⁻¹¹·h·(t² + 160), p in kPa,
//!   t in °C, h in %RH. This is the formula behind the thesis figure n = 1.000265156791 at
//!   99 kPa, 20 °C, 50 %RH (digest 001 §5.5: the exact value is 1.0002651567918, which the
//!   text truncates to …791; it is a 633 nm HeNe approximation of the full equation).
//! * [`birch_downs_index`] — the updated Edlén equation of Birch & Downs (1993, corrected 1994),
//!   as documented by NIST's Engineering Metrology Toolbox, with IAPWS saturation vapour pressure.
//! * [`boensch_potulski_index`] — Bönsch & Potulski (1998), with CO₂ content.
//!
//! All functions take SI inputs (Pa, °C, %RH, vacuum wavelength in m).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Simplified (shop-floor) Edlén index; `p` in Pa, `t` in °C, `h` in %RH (thesis eq. 5.5).
pub fn shop_floor_index(p: f64, t: f64, h: f64) -> f64 {
    1.0 + shop_floor_refractivity(p, t, h)
}

/// n − 1 of [`shop_floor_index`], computed without the leading 1 so that differences of
/// refractivities keep full precision.
pub fn shop_floor_refractivity(p: f64, t: f64, h: f64) -> f64 {
    7.86e-4 * (p / 1000.0) / (273.0 + t) - 1.5e-11 * h * (t * t + 160.0)
}

/// ∂n/∂t of [`shop_floor_index`], 1/K.
pub fn shop_floor_index_dt(p: f64, t: f64, h: f64) -> f64 {
    -7.86e-4 * (p / 1000.0) / ((273.0 + t) * (273.0 + t)) - 1.5e-11 * h * 2.0 * t
}

/// ∂n/∂p of [`shop_floor_index`], 1/Pa.
pub fn shop_floor_index_dp(_p: f64, t: f64, _h: f64) -> f64 {
    7.86e-4 / 1000.0 / (273.0 + t)
}

/// Saturation vapour pressure over water (IAPWS-IF97, as used by the NIST toolbox), Pa; t in °C.
pub fn saturation_vapour_pressure(t: f64) -> f64 {
    const K: [f64; 10] = [
        1.16705214528e3,
        -7.24213167032e5,
        -1.70738469401e1,
        1.20208247025e4,
        -3.23255503223e6,
        1.49151086135e1,
        -4.82326573616e3,
        4.05113405421e5,
        -2.38555575678e-1,
        6.50175348448e2,
    ];
    let tk = t + 273.15;
    let om = tk + K[8] / (tk - K[9]);
    let a = om * om + K[0] * om + K[1];
    let b = K[2] * om * om + K[3] * om + K[4];
    let c = K[5] * om * om + K[6] * om + K[7];
    let x = -b + (b * b - 4.0 * a * c).sqrt();
    1e6 * (2.0 * c / x).powi(4)
}

/// Updated Edlén equation, Birch & Downs (1993/1994). `lambda` = vacuum wavelength (m).
pub fn birch_downs_index(lambda: f64, p: f64, t: f64, h: f64) -> f64 {
    let s = 1.0 / (lambda * 1e6).powi(2);
    let ns = (8342.54 + 2406147.0 / (130.0 - s) + 15998.0 / (38.9 - s)) * 1e-8;
    let x = (1.0 + 1e-8 * (0.601 - 0.00972 * t) * p) / (1.0 + 0.003661 * t);
    let ntp = p * ns * x / 96095.43;
    let pv = h / 100.0 * saturation_vapour_pressure(t);
    1.0 + ntp - pv * (3.7345 - 0.0401 * s) * 1e-10
}

/// Bönsch & Potulski (1998). `co2` = CO₂ mole fraction (e.g. 400e-6).
pub fn boensch_potulski_index(lambda: f64, p: f64, t: f64, h: f64, co2: f64) -> f64 {
    let s2 = 1.0 / (lambda * 1e6).powi(2);
    let rs = (8091.37 + 2333983.0 / (130.0 - s2) + 15518.0 / (38.9 - s2)) * 1e-8;
    let rx = rs * (1.0 + 0.5327 * (co2 - 0.0004));
    let rtp =
        rx * p / 93214.60 * (1.0 + 1e-8 * (0.5953 - 0.009876 * t) * p) / (1.0 + 0.0036610 * t);
    let f = h / 100.0 * saturation_vapour_pressure(t);
    1.0 + rtp - f * (3.8020 - 0.0384 * s2) * 1e-10
}

/// Range error of a beam crossing sections of different index (thesis eq. 5.7, discrete form):
/// Δρ = Σ ρ_i·(n_i/n_LT − 1), measured − true; `segments` = (true length m, index).
pub fn segmented_path_range_error(segments: &[(f64, f64)], n_assumed: f64) -> f64 {
    segments
        .iter()
        .map(|(len, n)| len * (n / n_assumed - 1.0))
        .sum()
}

/// Standard deviations of the weather-station readings used by
/// [`weather_station_scale_error_2sigma`].
#[derive(Debug, Clone, Copy)]
pub struct StationUncertainty {
    pub temperature: f64,
    pub pressure: f64,
    pub humidity: f64,
}

/// Monte Carlo of the thesis (P1 §3): sample station readings around the true (p, t, h) with
/// normal errors of the given σ, compute the per-metre range error n_true/n_station − 1 with the
/// shop-floor formula, and return twice its standard deviation (m/m). Deterministic in `seed`.
pub fn weather_station_scale_error_2sigma(
    p: f64,
    t: f64,
    h: f64,
    sigma: StationUncertainty,
    samples: usize,
    seed: u64,
) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n_true = shop_floor_index(p, t, h);
    let errs: Vec<f64> = (0..samples)
        .map(|_| {
            let n_station = shop_floor_index(
                p + sigma.pressure * normal(&mut rng),
                t + sigma.temperature * normal(&mut rng),
                h + sigma.humidity * normal(&mut rng),
            );
            n_true / n_station - 1.0
        })
        .collect();
    let m = errs.iter().sum::<f64>() / errs.len() as f64;
    let var = errs.iter().map(|e| (e - m).powi(2)).sum::<f64>() / (errs.len() as f64 - 1.0);
    2.0 * var.sqrt()
}

/// Standard normal sample (Box–Muller), so the crate needs no distribution crate.
pub(crate) fn normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
