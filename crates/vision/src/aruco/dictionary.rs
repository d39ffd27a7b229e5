//! ArUco dictionaries, bit-exact with OpenCV's predefined ones.
//!
//! Convention: a marker's payload is an n×n grid of cells (border excluded); cell (row, col) with
//! row 0 at the top. A white cell is bit 1 (OpenCV's convention). The grid is packed into a `u64` *code*, row-major, the
//! top-left cell being the most significant of the n² bits (OpenCV's `bytesList` rotation 0).
//! Rotations in this crate are clockwise quarter turns of the image. OpenCV's `bytesList[:, :, k]`
//! holds the grid turned k quarter turns counter-clockwise (= 4−k clockwise); the tests check it.

use super::dictionary_data::PREDEFINED;
use crate::error::{Result, VisionError};

/// One ArUco dictionary: a list of marker codes and how many bit errors may be corrected.
#[derive(Debug, Clone, Copy)]
pub struct Dictionary {
    /// OpenCV name, e.g. `DICT_4X4_50`.
    pub name: &'static str,
    /// Payload side in cells (4 for 4X4), without the border.
    pub marker_size: usize,
    /// OpenCV's `maxCorrectionBits` for this dictionary.
    pub max_correction_bits: u32,
    codes: &'static [u64],
}

/// A successful dictionary lookup.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Identification {
    pub id: usize,
    /// Number of clockwise quarter turns the observed grid is rotated from the canonical marker.
    pub rotation: usize,
    /// Hamming distance between observed bits and the canonical marker (bits corrected).
    pub bit_errors: u32,
}

impl Dictionary {
    /// Look a predefined dictionary up by its OpenCV name (`DICT_4X4_50`, `DICT_ARUCO_ORIGINAL`, ...).
    pub fn predefined(name: &str) -> Result<Dictionary> {
        PREDEFINED
            .iter()
            .find(|e| e.0.eq_ignore_ascii_case(name))
            .map(|&(name, n, mcb, count, codes)| Dictionary {
                name,
                marker_size: n,
                max_correction_bits: mcb,
                codes: &codes[..count],
            })
            .ok_or_else(|| VisionError::UnknownDictionary(name.to_string()))
    }

    /// Names of all predefined dictionaries, in OpenCV enum order within each family.
    pub fn predefined_names() -> impl Iterator<Item = &'static str> {
        PREDEFINED.iter().map(|e| e.0)
    }

    pub fn len(&self) -> usize {
        self.codes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Canonical (rotation 0) code of marker `id`.
    pub fn code(&self, id: usize) -> Result<u64> {
        self.codes
            .get(id)
            .copied()
            .ok_or(VisionError::MarkerIdOutOfRange {
                dictionary: self.name,
                id,
                count: self.codes.len(),
            })
    }

    /// Payload bits of marker `id` as rows of booleans (true = white).
    pub fn bits(&self, id: usize) -> Result<Vec<Vec<bool>>> {
        Ok(code_to_bits(self.code(id)?, self.marker_size))
    }

    /// OpenCV `bytesList` row of marker `id` in OpenCV's memory order: ⌈n²/8⌉ bytes for each of
    /// rotations 0..3 (counter-clockwise quarter turns), one rotation after the other.
    pub fn opencv_byte_list(&self, id: usize) -> Result<Vec<u8>> {
        let n = self.marker_size;
        let code = self.code(id)?;
        let nbits = n * n;
        let mut out = Vec::with_capacity(4 * nbits.div_ceil(8));
        for ccw in 0..4 {
            let c = rotate_code(code, n, (4 - ccw) % 4);
            let mut remaining = nbits;
            while remaining > 0 {
                let k = remaining.min(8);
                remaining -= k;
                out.push(((c >> remaining) & ((1u64 << k) - 1)) as u8);
            }
        }
        Ok(out)
    }

    /// Identify an observed payload code: the marker and rotation with the smallest Hamming distance,
    /// accepted when the distance is ≤ `max_bit_errors`.
    pub fn identify(&self, observed: u64, max_bit_errors: u32) -> Option<Identification> {
        let n = self.marker_size;
        let rotations = [
            observed,
            rotate_code(observed, n, 3),
            rotate_code(observed, n, 2),
            rotate_code(observed, n, 1),
        ];
        let mut best: Option<Identification> = None;
        for (id, &code) in self.codes.iter().enumerate() {
            for (rotation, &obs) in rotations.iter().enumerate() {
                // obs is the observed grid turned back by `rotation` quarter turns.
                let d = (code ^ obs).count_ones();
                if d <= max_bit_errors && best.map_or(true, |b| d < b.bit_errors) {
                    best = Some(Identification {
                        id,
                        rotation,
                        bit_errors: d,
                    });
                    if d == 0 {
                        return best;
                    }
                }
            }
        }
        best
    }
}

/// Unpack a code into rows of cells (true = white).
pub fn code_to_bits(code: u64, n: usize) -> Vec<Vec<bool>> {
    let nbits = n * n;
    (0..n)
        .map(|r| {
            (0..n)
                .map(|c| (code >> (nbits - 1 - (r * n + c))) & 1 == 1)
                .collect()
        })
        .collect()
}

/// Pack rows of cells (true = white) into a code.
pub fn bits_to_code(bits: &[Vec<bool>]) -> u64 {
    bits.iter()
        .flatten()
        .fold(0u64, |acc, &b| (acc << 1) | b as u64)
}

/// Rotate a code's grid by `k` quarter turns clockwise.
pub fn rotate_code(code: u64, n: usize, k: usize) -> u64 {
    let mut c = code;
    for _ in 0..(k % 4) {
        let nbits = n * n;
        let mut out = 0u64;
        // clockwise: new(r, c) = old(n-1-c, r)
        for r in 0..n {
            for col in 0..n {
                let (sr, sc) = (n - 1 - col, r);
                let bit = (c >> (nbits - 1 - (sr * n + sc))) & 1;
                out = (out << 1) | bit;
            }
        }
        c = out;
    }
    c
}
