//! The sighted tool point of a machine that is linear in its parameters, kept per reading.
//!
//! On a cartesian or five-axis machine whose every machine term is linear in its parameters
//! (`PhysicsTerm::linear_in_params`: the geometric error series, squareness), the point an
//! instrument registered to the part sights ([`crate::ToolState::target`]) is exactly
//!
//!   P(p) = P₀ + A·p_machine,
//!
//! with P₀ (the nominal target) and A = ∂P/∂p_machine depending on the reading's joints and
//! signals alone: the kinematics add nothing that depends on p, and no term turns the tool. A
//! batch fit evaluates the same readings at every iterate; it can form (P₀, A) once per reading
//! ([`ForwardModel::linear_target`]) and then each evaluation is a 3 × n product instead of
//! every term's series, levers and dispatch ([`ForwardModel::tracker_point_jacobian_mapped_linear`]).
//! [`ForwardModel::linear_target`] writes a reading's P₀ (3 values), then A column-major (3 per
//! machine parameter, in stacked order): [`ForwardModel::linear_target_len`] values. The
//! instrument parameters come after the machine's in the stacked vector and do not move P.
//! Most of A is zero by construction (a positioning error moves one coordinate, an angular one
//! two), so what a caller keeps is packed by a [`KeptLayout`]: P₀, then of each column only the
//! rows the layout holds, in row order.

use metrocell_physics::{PhysicsError, Signals};
use nalgebra::Vector3;

use crate::forward::{ForwardModel, KinematicTruth};
use crate::machine::MachineKinematics;
use crate::workspace::Workspace;

impl ForwardModel<'_> {
    /// The number of machine parameters P depends on when it is linear in them, as the module
    /// doc states; None where it is not (a delta's or an arm's kinematic terms, any machine term
    /// that does not declare itself linear).
    pub fn linear_target_columns(&self) -> Option<usize> {
        self.linear_columns
    }

    pub(crate) fn find_linear_target_columns(&self) -> Option<usize> {
        let family = matches!(
            self.machine.kinematics,
            MachineKinematics::Cartesian(_) | MachineKinematics::FiveAxis(_)
        );
        let linear = self
            .machine_terms
            .terms
            .iter()
            .all(|t| t.term.linear_in_params());
        (family && linear).then(|| {
            self.machine_terms
                .terms
                .iter()
                .map(|t| t.params.len())
                .sum()
        })
    }

    /// Values one reading keeps (P₀ and A), for a model with [`Self::linear_target_columns`].
    pub fn linear_target_len(&self) -> Option<usize> {
        self.linear_target_columns().map(|k| 3 + 3 * k)
    }

    /// P₀ and A of the reading at joint vector `q` with signals `s`, into `out`
    /// ([`Self::linear_target_len`] values, the module's layout). Error when the target is not
    /// linear in this model.
    pub fn linear_target(
        &self,
        q: &[f64],
        s: &mut Signals,
        work: &mut Workspace,
        out: &mut [f64],
    ) -> Result<(), PhysicsError> {
        let len = self
            .linear_target_len()
            .ok_or_else(|| PhysicsError::InvalidInput {
                what: "forward model, linear target".into(),
                reason: "the machine's terms or kinematics are not linear in the parameters".into(),
            })?;
        assert_eq!(out.len(), len, "linear target buffer");
        work.check(self)?;
        // at p = 0 every linear term is zero: P(0) = P₀, and A is the same at any p
        let p0 = self.tool_point_jacobian(
            &work.zero_params,
            &KinematicTruth::None,
            q,
            s,
            &mut work.tool,
        )?;
        out[..3].copy_from_slice(p0.as_slice());
        out[3..].copy_from_slice(&work.tool.as_slice()[..len - 3]);
        Ok(())
    }
}

/// Which rows of each column of A a kept reading holds (see the module doc), and where.
#[derive(Debug, Clone, PartialEq)]
pub struct KeptLayout {
    /// Bit r set: row r of column c is held.
    rows: Vec<u8>,
    /// Offset of column c's first held row in a kept reading (after P₀).
    offsets: Vec<usize>,
    /// Row and column of each held value, in kept order (P = P₀ + A·p in one pass).
    entries: Vec<(usize, usize)>,
    /// Where each held value and each value not held is in the full layout of
    /// [`ForwardModel::linear_target`] (packing is a gather, the check a scan).
    held_at: Vec<usize>,
    not_held_at: Vec<usize>,
    len: usize,
}

impl KeptLayout {
    /// A layout of `columns` columns holding the rows `rows[c]` (bit r: row r).
    fn with_rows(rows: Vec<u8>) -> Self {
        let mut offsets = Vec::with_capacity(rows.len());
        let mut entries = Vec::new();
        for (c, m) in rows.iter().enumerate() {
            offsets.push(3 + entries.len());
            entries.extend((0..3).filter(|r| m & 1 << r != 0).map(|r| (r, c)));
        }
        let held_at = entries.iter().map(|(r, c)| 3 + 3 * c + r).collect();
        let not_held_at = (0..rows.len())
            .flat_map(|c| (0..3).map(move |r| (r, c)))
            .filter(|(r, c)| rows[*c] & 1 << r == 0)
            .map(|(r, c)| 3 + 3 * c + r)
            .collect();
        Self {
            len: 3 + entries.len(),
            rows,
            offsets,
            entries,
            held_at,
            not_held_at,
        }
    }

    /// Machine columns the layout covers.
    pub fn columns(&self) -> usize {
        self.rows.len()
    }

    /// The layout of `columns` columns that holds nothing but P₀ (to be widened).
    pub fn empty(columns: usize) -> Self {
        Self::with_rows(vec![0; columns])
    }

    /// Values per kept reading (P₀ and the held values of A).
    pub fn values_per_reading(&self) -> usize {
        self.len
    }

    fn nonzero_rows(a: &[f64]) -> u8 {
        (0..3).filter(|&r| a[r] != 0.0).fold(0, |m, r| m | 1 << r)
    }

    /// Whether every non-zero of the [`ForwardModel::linear_target`] values `full` is held.
    pub fn covers(&self, full: &[f64]) -> bool {
        self.not_held_at.iter().all(|&i| full[i] == 0.0)
    }

    /// This layout widened to hold the non-zeros of `full` too.
    pub fn widened(&self, full: &[f64]) -> Self {
        Self::with_rows(
            full[3..]
                .chunks_exact(3)
                .zip(&self.rows)
                .map(|(a, m)| m | Self::nonzero_rows(a))
                .collect(),
        )
    }

    /// `full` packed into `out` ([`Self::len`] values); the rows not held must be zero
    /// ([`Self::covers`]).
    pub fn pack(&self, full: &[f64], out: &mut [f64]) {
        debug_assert!(self.covers(full));
        out[..3].copy_from_slice(&full[..3]);
        for (o, &i) in out[3..].iter_mut().zip(&self.held_at) {
            *o = full[i];
        }
    }

    /// Column `c` of A from a kept reading (zero past the machine's columns).
    #[inline]
    pub(crate) fn column(&self, kept: &[f64], c: usize) -> Vector3<f64> {
        let Some(&m) = self.rows.get(c) else {
            return Vector3::zeros();
        };
        let mut v = Vector3::zeros();
        let mut at = self.offsets[c];
        for r in 0..3 {
            if m & 1 << r != 0 {
                v[r] = kept[at];
                at += 1;
            }
        }
        v
    }

    /// P(p) = P₀ + A·p_machine from a kept reading.
    pub(crate) fn target_at(&self, p: &[f64], kept: &[f64]) -> Vector3<f64> {
        // the small displacement summed first, then added to the nominal point once
        let mut d = [0.0; 3];
        for (&(r, c), a) in self.entries.iter().zip(&kept[3..]) {
            d[r] += a * p[c];
        }
        Vector3::new(kept[0] + d[0], kept[1] + d[1], kept[2] + d[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Full values of two columns: P₀, then A's columns.
    fn full(p0: [f64; 3], a: [[f64; 3]; 2]) -> Vec<f64> {
        p0.iter().chain(a.iter().flatten()).copied().collect()
    }

    #[test]
    fn a_layout_holds_the_rows_any_reading_needs_and_gives_them_back() {
        let first = full([1.0, 2.0, 3.0], [[0.5, 0.0, 0.0], [0.0, 0.0, 0.0]]);
        let layout = KeptLayout::empty(2);
        assert!(!layout.covers(&first));
        let layout = layout.widened(&first);
        assert!(layout.covers(&first));
        assert_eq!(layout.values_per_reading(), 4, "P₀ and one value");
        // a later reading whose lever is not zero where the first one's was
        let second = full([0.0, 1.0, 0.0], [[0.25, 0.0, 0.0], [0.0, -2.0, 7.0]]);
        assert!(!layout.covers(&second));
        let layout = layout.widened(&second);
        assert!(
            layout.covers(&first) && layout.covers(&second) && layout.values_per_reading() == 6
        );
        for f in [&first, &second] {
            let mut kept = vec![f64::NAN; layout.values_per_reading()];
            layout.pack(f, &mut kept);
            for c in 0..2 {
                assert_eq!(layout.column(&kept, c).as_slice(), &f[3 + 3 * c..6 + 3 * c]);
            }
            assert_eq!(
                layout.column(&kept, 2),
                Vector3::zeros(),
                "past the machine's columns"
            );
            let p = [1e-6, -3e-6, 42.0];
            let want = Vector3::new(f[0], f[1], f[2])
                + Vector3::new(f[3], f[4], f[5]) * p[0]
                + Vector3::new(f[6], f[7], f[8]) * p[1];
            assert!(
                (layout.target_at(&p, &kept) - want).norm() < 1e-15,
                "instrument parameters do not move P"
            );
        }
    }
}
