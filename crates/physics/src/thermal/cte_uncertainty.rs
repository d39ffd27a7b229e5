//! Standard uncertainty of a coefficient of thermal expansion (ISO/TR 230-9, thesis P5 eq. 10):
//! the CTE is known to within a full range of at least 10 % of its nominal value and never
//! less than 0.002 µm/(mm·K) = 2·10⁻⁶ /K; that range is a rectangular distribution, so
//! u(α) = range/(2√3). For steel-like α ≤ 20·10⁻⁶ /K this is 0.000577 µm/(mm·K) = 5.77·10⁻⁷ /K.

/// Floor of the CTE uncertainty range, 1/K (0.002 µm/(mm·K)).
pub const CTE_RANGE_FLOOR: f64 = 2e-6;

/// u(α) in 1/K for a nominal α in 1/K.
pub fn cte_standard_uncertainty(alpha: f64) -> f64 {
    (0.1 * alpha.abs()).max(CTE_RANGE_FLOOR) / (2.0 * 3f64.sqrt())
}
