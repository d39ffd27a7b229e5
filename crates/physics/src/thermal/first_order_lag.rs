//! The first-order lag of a temperature sensor: the one implementation of the workspace (the
//! catalog's `thermal_growth` term through [`crate::TemperatureTimeline`], the thermal node's
//! compensation in crates/compensation, and the twin all advance this filter).
//!
//! The exact discrete recursion, each new reading held over the interval that ends at it:
//! `T_f[0] = T[0],  T_f[k] = T_f[k−1] + a_k·(T[k] − T_f[k−1]),  a_k = 1 − e^(−Δt_k/τ)`,
//! with the derivative w.r.t. τ propagated through it analytically,
//! `∂T_f[k]/∂τ = (1 − a_k)·∂T_f[k−1]/∂τ + (∂a_k/∂τ)·(T[k] − T_f[k−1])`, `∂a_k/∂τ = −e^(−Δt_k/τ)·Δt_k/τ²`,
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
}

impl FirstOrderLag {
    pub fn new(time_constant: f64) -> Self {
        Self { time_constant, state: None }
    }

    /// Feed a reading at `time` (s) of variance `variance` (K²). A reading not later than the
    /// previous one is ignored (returns false): a lag cannot go back in time.
    pub fn advance(&mut self, time: f64, temperature: f64, variance: f64) -> bool {
        let tau = self.time_constant;
        match &mut self.state {
            None => {
                self.state = Some(LagState { time, value: temperature, d_value_d_tau: 0.0, variance });
                true
            }
            Some(s) if time > s.time => {
                let dt = time - s.time;
                let e = (-dt / tau).exp();
                let a = 1.0 - e;
                let da = -e * dt / (tau * tau);
                let innovation = temperature - s.value;
                s.d_value_d_tau = (1.0 - a) * s.d_value_d_tau + da * innovation;
                s.value += a * innovation;
                s.variance = e * e * s.variance + a * a * variance;
                s.time = time;
                true
            }
            Some(_) => false,
        }
    }

    /// (time of the last reading s, T_f °C, ∂T_f/∂τ K/s, variance of T_f K²), if fed yet.
    pub fn output(&self) -> Option<(f64, f64, f64, f64)> {
        self.state.map(|s| (s.time, s.value, s.d_value_d_tau, s.variance))
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
    lag.output().map_or((f64::NAN, f64::NAN), |(_, v, d, _)| (v, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recursion written out once more, as the catalog term had it before the filter was
    /// shared: the shared filter must reproduce it bit for bit (the twin's outputs depend on it).
    fn reference(samples: &[(f64, f64)], tau: f64) -> (f64, f64) {
        let mut tf = samples[0].1;
        let mut dtf = 0.0;
        for w in samples.windows(2) {
            let dt = w[1].0 - w[0].0;
            let e = (-dt / tau).exp();
            let a = 1.0 - e;
            let da = -e * dt / (tau * tau);
            let innov = w[1].1 - tf;
            dtf = (1.0 - a) * dtf + da * innov;
            tf += a * innov;
        }
        (tf, dtf)
    }

    #[test]
    fn equals_the_written_out_recursion_bit_for_bit() {
        let samples: Vec<(f64, f64)> = (0..500).map(|k| (k as f64 * 7.0, 20.0 + (k as f64 * 0.05).sin() + 0.001 * k as f64)).collect();
        let (tf, d) = first_order_lag(&TemperatureHistory { samples: samples.clone() }, 600.0);
        let (tf_ref, d_ref) = reference(&samples, 600.0);
        assert_eq!(tf.to_bits(), tf_ref.to_bits(), "{tf} vs {tf_ref}");
        assert_eq!(d.to_bits(), d_ref.to_bits(), "{d} vs {d_ref}");
    }

    #[test]
    fn step_response_and_noise_averaging() {
        // a 1 K step: after one τ the output has risen 1 − 1/e
        let mut lag = FirstOrderLag::new(100.0);
        lag.advance(0.0, 20.0, 0.0);
        for k in 1..=100 {
            lag.advance(k as f64, 21.0, 0.04);
        }
        let (_, tf, _, var) = lag.output().unwrap();
        assert!((tf - (21.0 - (-1.0f64).exp())).abs() < 1e-12);
        // white noise of variance σ² at Δt = 1 s settles to σ²·(1 − e)/(1 + e) ≈ σ²·Δt/(2τ)
        let e = (-0.01f64).exp();
        let settled = 0.04 * (1.0 - e) / (1.0 + e);
        assert!(var < settled && var > 0.8 * settled, "{var} vs {settled}");
        assert!(!lag.advance(50.0, 30.0, 0.0), "a reading from the past is refused");
    }

    #[test]
    fn derivative_matches_central_differences() {
        let samples: Vec<(f64, f64)> = (0..300).map(|k| (k as f64 * 11.0, 20.0 + 2.0 * (1.0 - (-(k as f64) / 90.0).exp()))).collect();
        let h = TemperatureHistory { samples };
        let tau = 900.0;
        let (_, d) = first_order_lag(&h, tau);
        let step = 1e-3;
        let numeric = (first_order_lag(&h, tau + step).0 - first_order_lag(&h, tau - step).0) / (2.0 * step);
        assert!((d - numeric).abs() < 1e-7 * d.abs(), "{d} vs {numeric}");
        assert!(first_order_lag(&TemperatureHistory::default(), tau).0.is_nan());
    }
}
