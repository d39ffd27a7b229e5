//! Stable ids of the catalog's terms (DESIGN.md vocabulary) with their one-line docs and
//! equations. Every term module names its id from here; the catalog ([`crate::catalog`]) builds
//! terms from ids, so neither imports the other's internals. Adding a term: its file, one line
//! in the table below, one arm in [`crate::catalog::build_term`].

use std::fmt;

macro_rules! term_ids {
    ($($variant:ident => $id:literal, $cat:ident, $summary:literal, $eq:literal;)*) => {
        /// Stable id of a catalog term.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum TermId { $($variant),* }
        impl TermId {
            /// Every id, in catalog order.
            pub const ALL: &'static [TermId] = &[$(TermId::$variant),*];
            /// The stable string id.
            pub fn as_str(self) -> &'static str { match self { $(TermId::$variant => $id),* } }
            /// Look an id up; `None` if unknown.
            pub fn parse(s: &str) -> Option<TermId> { match s { $($id => Some(TermId::$variant),)* _ => None } }
            pub fn category(self) -> Category { match self { $(TermId::$variant => Category::$cat),* } }
            /// One-line description.
            pub fn summary(self) -> &'static str { match self { $(TermId::$variant => $summary),* } }
            /// The equation the term implements (same as its module docs).
            pub fn equation(self) -> &'static str { match self { $(TermId::$variant => $eq),* } }
        }
    };
}

term_ids! {
    Positioning => "positioning", Geometry, "linear positioning error of an axis (ISO 230-1 E_XX, VDI xTx)", "d = δ_k(q_k)·e_k, δ_k a Legendre/polynomial series over the travel";
    Straightness => "straightness", Geometry, "straightness error of an axis in a perpendicular direction (VDI xTy)", "d = δ_j(q_k)·e_j, j ≠ k";
    Angular => "angular", Geometry, "roll/pitch/yaw of an axis with its Abbe lever (VDI xRx, xRy, xRz)", "d = ε(q_k)·e_a × (r_abbe + Σ_{j∈lever_axes} q_j·e_j)";
    Squareness => "squareness", Geometry, "out-of-squareness of an axis pair (VDI xWy, xWz, yWz; P5 s_xy, s_xz, s_yz)", "xy: d = (−y·s,0,0); xz: d = (−z·s,0,0); yz: d = (0,−z·s,0)";
    PitchCyclic => "pitch_cyclic", Geometry, "periodic ball-screw error repeating every lead", "d = e_k·Σ_h [a_h cos(2πh q/P) + b_h sin(2πh q/P)]";
    RotaryAxisLocation => "rotary_axis_location", Geometry, "location errors of the B/C rotary axes of a five-axis table (ISO 230-1 E_XOB … E_C0C)", "d = −δW·W⁻¹t: each rotary axis turns about a line offset by (x_o, y_o/z_o), tilted by (a_o, b_o/c_o), from a zero off by θ₀ (first order)";
    Backlash => "backlash", Geometry, "reversal error by sign of approach", "d = −(β/2)·s_k·e_k, s_k = ±1 direction of approach";
    ThermalScale => "thermal_scale", Thermal, "thermal expansion of an axis scale, temperature interpolated between sensors", "d = e_k·α·q_k·(T(q_k) − 20 °C)";
    ThermalGrowth => "thermal_growth", Thermal, "growth of a structural element with its (optionally lagged) temperature", "d = n̂·g·(T_f − 20 °C), T_f = first-order lag (τ) of the sensor history";
    WorkpieceExpansion => "workpiece_expansion", Thermal, "expansion of the workpiece/artefact about its clamp point", "d = α·(T_w − 20 °C)·(p − c)";
    TrackerWarmup => "tracker_warmup", Instrument, "laser-tracker range drift during warm-up", "Δρ = A + B·(1 − e^(−t/τ))";
    Refraction => "refraction", Instrument, "range error from air on the beam differing from the weather station (Edlén)", "Δρ = ρ·(n(t+ΔT, p+Δp, h+Δh)/n(t, p, h) − 1), n = shop-floor Edlén, Δh a fixed option";
    Turbulence => "turbulence", Instrument, "range scatter inflated by turbulence (flagged, not fitted as bias)", "σ = √((σ₀ + s·ρ)² + (c·ρ)²)";
    TrackerPose => "tracker_pose", Instrument, "6-dof pose of the tracker in the frame tool points are reported in (workpiece; an arm's cell frame); one per placement (option `setup`)", "X_LT = (Rx(α)Ry(β)Rz(δ))ᵀ·(p − T_LT)";
    BaseTilt => "base_tilt", Instrument, "the measured base's tilt from level, shared by every placement of a levelled instrument", "P_level = Rx(roll)·Ry(pitch)·P";
    ProbePretravel => "probe_pretravel", Instrument, "direction-dependent touch-probe pretravel (n-lobe)", "d = [(1−u_z²)(p₀ + a cos nφ + b sin nφ) + u_z² p_z]·u";
    LensDistortion => "lens_distortion", Instrument, "Brown–Conrady radial/tangential lens distortion", "Δx = x(k1r²+k2r⁴+k3r⁶) + 2p1xy + p2(r²+2x²); Δy = y(…) + p1(r²+2y²) + 2p2xy";
    CameraScale => "camera_scale", Instrument, "metric scale error of a camera measurement", "d = s·p (camera frame)";
    InstrumentDrift => "instrument_drift", Instrument, "the instrument's pose moving slowly in time (a stand sinking, a head turning)", "pose(t) = pose + Σ_j P_j(u)·(dx_j, dy_j, dz_j, rx_j, ry_j, rz_j), u = 2(t − t_start)/(t_end − t_start) − 1";
    TimeOffset => "time_offset", Instrument, "latency between streams", "d = −Δt·v";
    Compliance => "compliance", Load, "deflection under load, growing with moment and extension", "d = F·(c₀ + c_θ e² + c_b e³), e = q_k − e₀";
    ToolOffset => "tool_offset", Load, "error of the tool/probe offset vector", "d = (dx, dy, dz)";
    DeltaRodLength => "delta_rod_length", MachineFamily, "delta diagonal-rod length trims (kinematic term)", "rod length per tower L + ΔL_T; effect via crates/kinematics";
    DeltaRadius => "delta_radius", MachineFamily, "delta radius trims (kinematic term)", "tower radius R + ΔR_T; effect via crates/kinematics";
    DeltaTowerAngle => "delta_tower_angle", MachineFamily, "delta tower angle trims (kinematic term)", "tower angle φ_T + Δφ_T (210°, 330°, 90°); effect via crates/kinematics";
    DeltaEndstop => "delta_endstop", MachineFamily, "delta endstop offsets (kinematic term)", "carriage height h_T + Δh_T; effect via crates/kinematics";
    JointOffset => "joint_offset", MachineFamily, "serial-arm joint zero offsets (kinematic term)", "θ_i + Δθ_i; effect via crates/kinematics";
    LinkLength => "link_length", MachineFamily, "serial-arm link length errors (kinematic term)", "l_i + Δl_i; effect via crates/kinematics";
    JointCompliance => "joint_compliance", MachineFamily, "a robot joint yielding to the gravity torque about it (URDF inertials, the measured gravity)", "Δθ_j = k_j·τ_j, τ_j = Σ_links m_i·gᵀ·∂c_i/∂q_j";
    JointBacklash => "joint_backlash", MachineFamily, "a robot joint's play taken up to the side gravity pushes it", "Δθ_j = (b_j/2)·sign(τ_j)";
    ColumnBending => "column_bending", MachineFamily, "a telescoping lifting column tilting under the moment of what it carries", "θ = M⊥·[c_foot + c_pads·Σ_i 1/o_i(e)² + c_flex·L(e)], each part about its pivot; Δp = Σ θ_k × (p − pivot_k)";
    LinkThermalExpansion => "link_thermal_expansion", MachineFamily, "a robot's links lengthening with their temperature", "Δl_j = α·(T − 20 °C)·l_j";
    FrameMisalignment => "frame_misalignment", Frame, "small rigid misalignment between two frames", "d = ω × (p − o) + t";
}

/// Family a term belongs to (DESIGN.md grouping).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Category {
    Geometry,
    Thermal,
    Instrument,
    Load,
    MachineFamily,
    Frame,
}

impl fmt::Display for TermId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
