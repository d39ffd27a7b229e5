//! First-order lag of a temperature sensor, advanced one reading at a time (constant work per
//! reading, however long the shift). Same recursion as the catalog's `thermal_growth` term
//! (physics `first_order_lag`): T_f[0] = T[0], T_f[k] = T_f[k−1] + (1 − e^(−Δt/τ))·(T[k] − T_f[k−1]),
//! i.e. each new reading is held over the interval that ends at it.
//!
//! Alongside T_f it carries ∂T_f/∂τ (for the uncertainty of τ and the online fit) and the
//! variance of T_f from the readings' variances, treated as independent per reading (white
//! noise is averaged down by the lag; a sensor's calibration error is not, see
//! [`crate::thermal_growth_compensation`]).

#[derive(Debug, Clone, PartialEq)]
pub struct FirstOrderLag {
    /// s
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

    /// Feed a reading at `time` (s). A reading not later than the previous one is ignored
    /// (returns false): a lag cannot go back in time.
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
                s.d_value_d_tau = e * s.d_value_d_tau + da * innovation;
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

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_physics::thermal::thermal_growth::first_order_lag;
    use metrocell_physics::TemperatureHistory;

    #[test]
    fn equals_the_catalog_lag_over_a_whole_history() {
        let samples: Vec<(f64, f64)> = (0..500).map(|k| (k as f64 * 7.0, 20.0 + (k as f64 * 0.05).sin() + 0.001 * k as f64)).collect();
        let mut lag = FirstOrderLag::new(600.0);
        for (t, v) in &samples {
            assert!(lag.advance(*t, *v, 0.0));
        }
        let (_, tf, d, _) = lag.output().unwrap();
        let (tf_ref, d_ref) = first_order_lag(&TemperatureHistory { samples }, 600.0);
        assert!((tf - tf_ref).abs() < 1e-12, "{tf} vs {tf_ref}");
        assert!((d - d_ref).abs() < 1e-15, "{d} vs {d_ref}");
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
}
