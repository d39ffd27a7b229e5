//! The reference nests' positions as nuisance columns of the linear stages: a nest's readings
//! carry its position (unknown to the µm, estimated from the readings themselves) and how the
//! instrument's terms move them; each nest's three coordinates are freed beside the declared
//! parameters, so only the change of its readings over time informs the candidates.

use std::collections::BTreeMap;

use metrocell_estimation::{MeasurementRecord, RecordKind};
use nalgebra::DMatrix;

use crate::residual_view::ResidualView;

/// Whitened columns (3 rows per record of `view`) of every nest's position: for the readings of
/// nest k, ∂reading/∂nest = Rᵀ (the records frame seen from the workpiece frame), zero
/// elsewhere. No columns without references.
pub(crate) fn nest_columns(records: &[MeasurementRecord], view: &ResidualView) -> DMatrix<f64> {
    let mut nests: BTreeMap<&str, usize> = BTreeMap::new();
    for r in records {
        if matches!(r.kind, RecordKind::Reference { .. }) {
            let k = nests.len();
            nests.entry(r.point_id.as_str()).or_insert(k);
        }
    }
    let mut out = DMatrix::zeros(3 * records.len(), 3 * nests.len());
    for (i, r) in records.iter().enumerate() {
        if let (RecordKind::Reference { .. }, Some(&k)) = (&r.kind, nests.get(r.point_id.as_str()))
        {
            out.view_mut((3 * i, 3 * k), (3, 3))
                .copy_from(&(view.whitening[i] * view.rotation(i).transpose()));
        }
    }
    out
}

/// `a` with `b`'s columns appended.
pub(crate) fn with_columns(a: DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    if b.ncols() == 0 {
        return a;
    }
    let mut out = DMatrix::zeros(a.nrows(), a.ncols() + b.ncols());
    out.columns_mut(0, a.ncols()).copy_from(&a);
    out.columns_mut(a.ncols(), b.ncols()).copy_from(b);
    out
}
