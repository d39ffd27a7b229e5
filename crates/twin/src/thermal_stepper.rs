//! Streaming integration of the physics [`ShiftThermalModel`]: the same equations as its batch
//! `simulate` (first-order nodes integrated exactly with inputs held over each step, ambient
//! cycle plus random walk), advanced lazily as the simulation clock moves, so an 8-hour shift
//! needs only the two states bracketing the current time (flat memory). Between grid steps the
//! true temperatures are linearly interpolated, as `TemperatureLog::at` does.

use metrocell_physics::thermal::shift_model::{SensorLocation, ShiftThermalModel};

use crate::noise::{stream, NoiseStream};

/// Lazily advanced true temperatures of the ambient and every structure node.
#[derive(Debug, Clone)]
pub struct ThermalStepper {
    model: ShiftThermalModel,
    dt: f64,
    /// (source index, steady-state rise) per node.
    heating: Vec<Vec<(usize, f64)>>,
    k: u64,
    walk: f64,
    /// State at t_k and t_{k+1}: [ambient, node 0, node 1, …].
    prev: Vec<f64>,
    next: Vec<f64>,
    rng: NoiseStream,
}

impl ThermalStepper {
    /// `model` must be validated (the cell does it).
    pub fn new(model: &ShiftThermalModel, dt: f64, seed: u64) -> Self {
        let heating = model
            .nodes
            .iter()
            .map(|n| {
                n.heating
                    .iter()
                    .filter_map(|(src, g)| {
                        model
                            .sources
                            .iter()
                            .position(|s| &s.name == src)
                            .map(|i| (i, *g))
                    })
                    .collect()
            })
            .collect();
        let amb = model.ambient.deterministic(0.0);
        let mut prev = vec![amb];
        prev.extend(model.nodes.iter().map(|n| n.initial.unwrap_or(amb)));
        let mut s = Self {
            model: model.clone(),
            dt,
            heating,
            k: 0,
            walk: 0.0,
            next: prev.clone(),
            prev,
            rng: NoiseStream::new(seed, stream::THERMAL_WALK),
        };
        s.next = s.step_from(0);
        s
    }

    /// State at t_{k+1} from `prev` = state at t_k.
    fn step_from(&mut self, k: u64) -> Vec<f64> {
        let tp = k as f64 * self.dt;
        let t = tp + self.dt;
        let amb_prev = self.prev[0];
        let mut out = Vec::with_capacity(self.prev.len());
        self.walk += self.model.ambient.walk_std
            * self.dt.sqrt()
            * if self.model.ambient.walk_std > 0.0 {
                self.rng.normal()
            } else {
                0.0
            };
        out.push(self.model.ambient.deterministic(t) + self.walk);
        for (i, n) in self.model.nodes.iter().enumerate() {
            let heat: f64 = self.heating[i]
                .iter()
                .map(|(s, g)| g * self.model.sources[*s].level(tp))
                .sum();
            let target = amb_prev + heat;
            out.push(target + (self.prev[i + 1] - target) * (-self.dt / n.time_constant).exp());
        }
        out
    }

    fn advance_to(&mut self, t: f64) {
        while (self.k + 1) as f64 * self.dt <= t {
            self.k += 1;
            std::mem::swap(&mut self.prev, &mut self.next);
            self.next = self.step_from(self.k);
        }
    }

    /// True temperature of slot `i` (0 = ambient, 1 + node index) at t; t must not decrease
    /// between calls by more than the current step.
    pub fn at(&mut self, slot: usize, t: f64) -> f64 {
        self.advance_to(t);
        let t0 = self.k as f64 * self.dt;
        let f = ((t - t0) / self.dt).clamp(0.0, 1.0);
        self.prev[slot] + (self.next[slot] - self.prev[slot]) * f
    }

    /// True ambient temperature at t (°C).
    pub fn ambient(&mut self, t: f64) -> f64 {
        self.at(0, t)
    }

    /// Slot of a sensor location.
    pub fn slot(&self, location: &SensorLocation) -> usize {
        match location {
            SensorLocation::Ambient => 0,
            SensorLocation::Node(n) => {
                1 + self
                    .model
                    .nodes
                    .iter()
                    .position(|x| &x.name == n)
                    .unwrap_or(0)
            }
        }
    }

    /// Slot of a node by name (`None` → ambient).
    pub fn slot_of_node(&self, node: Option<&str>) -> usize {
        match node {
            None => 0,
            Some(n) => {
                1 + self
                    .model
                    .nodes
                    .iter()
                    .position(|x| x.name == n)
                    .unwrap_or(0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_physics_batch_model_without_random_walk() {
        let mut m = ShiftThermalModel::example_machine_shift();
        m.ambient.walk_std = 0.0;
        let log = m.simulate(3.0 * 3600.0, 1.0, 1).unwrap();
        let mut s = ThermalStepper::new(&m, 1.0, 99);
        for (k, t) in log.times.iter().enumerate().step_by(97) {
            assert!(
                (s.ambient(*t) - log.truth["ambient"][k]).abs() < 1e-9,
                "ambient at {t}"
            );
            for (i, n) in m.nodes.iter().enumerate() {
                let v = s.at(1 + i, *t);
                assert!(
                    (v - log.truth[&n.name][k]).abs() < 1e-9,
                    "{} at {t}: {v} vs {}",
                    n.name,
                    log.truth[&n.name][k]
                );
            }
        }
    }
}
