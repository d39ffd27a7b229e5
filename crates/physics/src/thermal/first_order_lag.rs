//! The first-order lag of a temperature sensor: the one implementation of the workspace (the
//! catalog's `thermal_growth` term through [`crate::TemperatureTimeline`], the thermal node's
//! compensation in crates/compensation, and the twin all advance this filter).
//!
//! The temperature between two readings is taken to vary linearly (a first-order hold: a sensor
//! read every few minutes sees a structure warm along a ramp, not in steps), and the lag's
//! response to that ramp is exact. With e = e^(−Δt/τ), the ramp's slope s = (T[k] − T[k−1])/Δt:
//!
//! `T_f[0] = T[0],  T_f[k] = T[k] − τ·s + (T_f[k−1] − T[k−1] + τ·s)·e`
//!
//! (a reading held constant over its interval instead — a zero-order hold — lags the truth by
//! about Δt/2, which at readings 10 min apart shifts a fitted τ by minutes). The derivative
//! w.r.t. τ is propagated through it analytically,
//! `∂T_f[k]/∂τ = −s + (∂T_f[k−1]/∂τ + s)·e + (T_f[k−1] − T[k−1] + τ·s)·e·Δt/τ²`,
//! and the variance of T_f from the readings' variances, treated as independent per reading
//! (white noise is averaged down by the lag; a sensor's calibration error is not — that is the
//! caller's to add). Constant work per reading, however long the shift.

use crate::temperature_timeline::TemperatureHistory;

/// A first-order lag advanced one reading at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstOrderLag {
    /// τ, s.
    pub time_constant: f64,
    state: Option<LagState>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct LagState {
    time: f64,
    value: f64,
    d_value_d_tau: f64,
    variance: f64,
    /// The last reading and its variance (the ramp to the next one starts there).
    input: f64,
    input_variance: f64,
}

impl FirstOrderLag {
    pub fn new(time_constant: f64) -> Self {
        Self {
            time_constant,
            state: None,
        }
    }

    /// Feed a reading at `time` (s) of variance `variance` (K²). A reading not later than the
    /// previous one is ignored (returns false): a lag cannot go back in time.
    pub fn advance(&mut self, time: f64, temperature: f64, variance: f64) -> bool {
        let tau = self.time_constant;
        match &mut self.state {
            None => {
                self.state = Some(LagState {
                    time,
                    value: temperature,
                    d_value_d_tau: 0.0,
                    variance,
                    input: temperature,
                    input_variance: variance,
                });
                true
            }
            Some(s) if time > s.time => {
                let dt = time - s.time;
                let e = (-dt / tau).exp();
                let slope = (temperature - s.input) / dt;
                // the state's distance from the ramp's steady response at its start
                let gap = s.value - s.input + tau * slope;
                s.d_value_d_tau =
                    -slope + (s.d_value_d_tau + slope) * e + gap * e * dt / (tau * tau);
                s.value = temperature - tau * slope + gap * e;
                // T_f[k] = w₁·T[k] + w₀·T[k−1] + e·T_f[k−1]
                let c = tau / dt;
                let (w1, w0) = (1.0 - c * (1.0 - e), c * (1.0 - e) - e);
                s.variance = e * e * s.variance + w1 * w1 * variance + w0 * w0 * s.input_variance;
                s.input = temperature;
                s.input_variance = variance;
                s.time = time;
                true
            }
            Some(_) => false,
        }
    }

    /// (time of the last reading s, T_f °C, ∂T_f/∂τ K/s, variance of T_f K²), if fed yet.
    pub fn output(&self) -> Option<(f64, f64, f64, f64)> {
        self.state
            .map(|s| (s.time, s.value, s.d_value_d_tau, s.variance))
    }
}

/// First-order lag of a whole temperature history: (T_f at its last sample, ∂T_f/∂τ); NaN for
/// an empty history. The same filter as [`FirstOrderLag`] (samples that do not advance in time
/// are skipped).
pub fn first_order_lag(history: &TemperatureHistory, tau: f64) -> (f64, f64) {
    let mut lag = FirstOrderLag::new(tau);
    for &(t, v) in &history.samples {
        lag.advance(t, v, 0.0);
    }
    lag.output()
        .map_or((f64::NAN, f64::NAN), |(_, v, d, _)| (v, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lag of a smooth temperature, integrated numerically at a fine step (the truth a
    /// structure follows), against the filter fed readings 10 min apart: the ramp between
    /// readings follows it to a small fraction of what the filter lags, where a hold of each
    /// reading would lag by Δt/2 of the slope.
    #[test]
    fn sparse_readings_follow_a_smooth_temperature() {
        let tau = 1200.0;
        let t_of = |t: f64| 20.0 + 3.0 / (1.0 + (-(t - 5000.0) / 1500.0).exp());
        // the truth: dy/dt = (T − y)/τ by RK4 at 1 s
        let (mut y, mut t) = (t_of(0.0), 0.0);
        let h = 1.0;
        while t < 12_000.0 {
            let f = |t: f64, y: f64| (t_of(t) - y) / tau;
            let k1 = f(t, y);
            let k2 = f(t + h / 2.0, y + h / 2.0 * k1);
            let k3 = f(t + h / 2.0, y + h / 2.0 * k2);
            let k4 = f(t + h, y + h * k3);
            y += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t += h;
        }
        let samples: Vec<(f64, f64)> = (0..=20)
            .map(|k| (k as f64 * 600.0, t_of(k as f64 * 600.0)))
            .collect();
        let (tf, _) = first_order_lag(&TemperatureHistory { samples }, tau);
        // the hold of each reading over its interval would be ~0.05 K off at this slope
        assert!((tf - y).abs() < 3e-3, "filter {tf} vs truth {y}");
    }

    #[test]
    fn the_tau_derivative_matches_central_differences() {
        let samples: Vec<(f64, f64)> = (0..200)
            .map(|k| {
                (
                    k as f64 * 37.0 + (k % 3) as f64 * 11.0,
                    20.0 + (k as f64 * 0.05).sin() + 0.004 * k as f64,
                )
            })
            .collect();
        let h = TemperatureHistory { samples };
        for tau in [300.0, 1200.0, 5000.0] {
            let (_, d) = first_order_lag(&h, tau);
            let step = 1e-4 * tau;
            let numeric = (first_order_lag(&h, tau + step).0 - first_order_lag(&h, tau - step).0)
                / (2.0 * step);
            assert!(
                (d - numeric).abs() <= 1e-5 * numeric.abs().max(1e-9),
                "τ {tau}: analytic {d} vs numeric {numeric}"
            );
        }
    }

    #[test]
    fn step_response_and_noise_averaging() {
        // a 1 K rise over the first second (the ramp between the readings), then constant: the
        // ramp's exact response, then the exponential approach over the remaining 99 s
        let mut lag = FirstOrderLag::new(100.0);
        lag.advance(0.0, 20.0, 0.0);
        for k in 1..=100 {
            lag.advance(k as f64, 21.0, 0.04);
        }
        let (_, tf, _, var) = lag.output().unwrap();
        let after_ramp = 21.0 - 100.0 + 100.0 * (-0.01f64).exp();
        let want = 21.0 - (21.0 - after_ramp) * (-0.99f64).exp();
        assert!((tf - want).abs() < 1e-12, "{tf} vs {want}");
        // white noise of variance σ² at Δt = 1 s settles to σ²·(w₁² + w₀²)/(1 − e²) ≈ σ²·Δt/(2τ)
        let e = (-0.01f64).exp();
        let (w1, w0) = (1.0 - 100.0 * (1.0 - e), 100.0 * (1.0 - e) - e);
        let settled = 0.04 * (w1 * w1 + w0 * w0) / (1.0 - e * e);
        assert!(var < settled && var > 0.8 * settled, "{var} vs {settled}");
        assert!(
            !lag.advance(50.0, 30.0, 0.0),
            "a reading from the past is refused"
        );
    }

    #[test]
    fn derivative_matches_central_differences() {
        let samples: Vec<(f64, f64)> = (0..300)
            .map(|k| {
                (
                    k as f64 * 11.0,
                    20.0 + 2.0 * (1.0 - (-(k as f64) / 90.0).exp()),
                )
            })
            .collect();
        let h = TemperatureHistory { samples };
        let tau = 900.0;
        let (_, d) = first_order_lag(&h, tau);
        let step = 1e-3;
        let numeric =
            (first_order_lag(&h, tau + step).0 - first_order_lag(&h, tau - step).0) / (2.0 * step);
        assert!((d - numeric).abs() < 1e-7 * d.abs(), "{d} vs {numeric}");
        assert!(first_order_lag(&TemperatureHistory::default(), tau)
            .0
            .is_nan());
    }
}
