//! `thermal_scale` — thermal expansion of an axis scale (thesis P5 eqs 7–9):
//!
//! d = e_k · α·q_k·(T(q_k) − T_ref),   T_ref = 20 °C by default
//!
//! T(q) is linearly interpolated between the sensors mounted along the axis (option `sensors`:
//! list of {name, position}), held constant beyond the outer sensors; one sensor means a uniform
//! temperature. The scale grows with the temperature, so the carriage overshoots the commanded
//! coordinate by α·q·ΔT along the commanded direction. Frame: machine, tool relative to
//! workpiece. Options: `axis`, `sensors`, `reference_temperature` (°C). Parameter `alpha` (1/K).

use nalgebra::DMatrix;

use crate::config::{quantity, ConfigValue, Options};
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

/// A temperature sensor at a position along an axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSensor {
    pub name: String,
    pub position: f64,
}

/// Linear interpolation of sensor temperatures at q (sensors sorted by position, non-empty),
/// constant beyond the outer sensors.
pub fn interpolate_temperature(sensors: &[(f64, f64)], q: f64) -> f64 {
    let first = sensors[0];
    let last = sensors[sensors.len() - 1];
    if q <= first.0 {
        return first.1;
    }
    if q >= last.0 {
        return last.1;
    }
    for w in sensors.windows(2) {
        let ((q0, t0), (q1, t1)) = (w[0], w[1]);
        if q >= q0 && q <= q1 {
            return t0 + (t1 - t0) * (q - q0) / (q1 - q0);
        }
    }
    last.1
}

/// Read `sensors: [{name, position}, ...]` (positions in m), sorted by position.
pub(crate) fn read_sensors(o: &Options, term: &str) -> Result<Vec<AxisSensor>, PhysicsError> {
    let v = o.required("sensors")?;
    let items = match v {
        ConfigValue::List(items) if !items.is_empty() => items,
        _ => return Err(o.bad("sensors", "expected a non-empty list of {name, position}")),
    };
    let mut out = Vec::new();
    for it in items {
        match it {
            ConfigValue::Map(m) => {
                let name = match m.get("name") {
                    Some(ConfigValue::Text(t)) => t.clone(),
                    _ => return Err(o.bad("sensors", "each sensor needs a text `name`")),
                };
                let position = quantity(
                    term,
                    "sensors.position",
                    m.get("position").ok_or_else(|| {
                        o.bad("sensors", format!("sensor `{name}` needs a `position` (m)"))
                    })?,
                    "m",
                )?;
                out.push(AxisSensor { name, position });
            }
            _ => return Err(o.bad("sensors", "each sensor must be a map {name, position}")),
        }
    }
    out.sort_by(|a, b| a.position.total_cmp(&b.position));
    if out.windows(2).any(|w| w[0].position == w[1].position) {
        return Err(o.bad("sensors", "two sensors share one position"));
    }
    Ok(out)
}

#[derive(Debug, Clone)]
pub struct ThermalScale {
    pub axis: Axis,
    pub sensors: Vec<AxisSensor>,
    pub reference_temperature: f64,
}

impl ThermalScale {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            axis: o.axis("axis", None)?,
            sensors: read_sensors(o, "thermal_scale")?,
            reference_temperature: o.quantity("reference_temperature", "degC", Some(20.0))?,
        })
    }
    /// α-free part: q·(T(q) − T_ref).
    fn lever(&self, s: &Signals) -> Result<f64, PhysicsError> {
        let q = s.position(self, self.axis)?;
        let temps = self
            .sensors
            .iter()
            .map(|x| Ok((x.position, s.temperature(self, &x.name)?)))
            .collect::<Result<Vec<_>, PhysicsError>>()?;
        Ok(q * (interpolate_temperature(&temps, q) - self.reference_temperature))
    }
}

impl PhysicsTerm for ThermalScale {
    fn id(&self) -> TermId {
        TermId::ThermalScale
    }
    fn label(&self) -> String {
        format!("thermal_scale[{}]", self.axis)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("alpha", "1/K", -2e-6, 30e-6, 11.5e-6, "α: expansion coefficient of the axis scale")
            .possible(-100e-6, 100e-6)
            .unusual_means("an α below −2 µm/m/K means the axis shrinks as the sensor warms: the controller's thermal compensation over-corrects, or the sensor sits where the temperature runs opposite to the scale's; above 30 µm/m/K more than aluminium: the sensor lags or under-reads the scale's temperature")]
    }
    fn signals(&self) -> Vec<SignalKind> {
        let mut v = vec![SignalKind::AxisPosition(self.axis)];
        v.extend(
            self.sensors
                .iter()
                .map(|x| SignalKind::Temperature(x.name.clone())),
        );
        v
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(displacement(
            Frame::Machine,
            self.axis.unit() * (p[0] * self.lever(s)?),
        ))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(DMatrix::from_column_slice(
            3,
            1,
            (self.axis.unit() * self.lever(s)?).as_slice(),
        ))
    }
}
