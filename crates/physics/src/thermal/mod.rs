//! Thermal terms (axis scale, structure growth, workpiece expansion) and the lumped thermal
//! model of a shift that produces temperature histories for the simulator.
pub mod cte_uncertainty;
pub mod first_order_lag;
pub mod shift_model;
pub mod thermal_growth;
pub mod thermal_scale;
pub mod workpiece_expansion;
