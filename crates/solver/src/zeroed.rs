//! Jacobian-sized buffers whose zeroing is left to the operating system.
//!
//! `DMatrix::zeros` writes every entry: for the 30 000 × 75 Jacobian of an XFYZ calibration
//! that is 18 MB stored once by hand, after the kernel has already cleared each page on first
//! touch, and the columns of fixed parameters (a third of them) are then never written again.
//! An allocation from `vec![0.0; len]` is a zeroed one (`calloc`): large ones are fresh pages
//! the kernel maps as zero, so only the columns a problem writes cost memory traffic. On the
//! XFYZ benchmark fit, the solver's two m × n buffers took 19 ms of a 124 ms fit to allocate.
//!
//! First touch still costs a page fault per 4 KB page, and on a virtual machine a fault is dear
//! (~2.5 µs measured here: faulting in the 11 MB of a 10 000-reading Jacobian's free columns
//! made its first evaluation 6–7 ms slower than the next). On Linux the buffer's 2 MB-aligned
//! interior is therefore advised to the kernel as huge pages (`MADV_HUGEPAGE`; honoured when
//! transparent huge pages are `always` or `madvise`, ignored when `never`), 512 times fewer faults.

use nalgebra::DMatrix;

/// An m × n matrix of zeros, column-major, allocated zeroed rather than written with zeros.
pub fn zeroed_matrix(m: usize, n: usize) -> DMatrix<f64> {
    let len = m.checked_mul(n).expect("matrix size overflows usize");
    let data = vec![0.0; len];
    advise_huge_pages(&data);
    DMatrix::from_vec(m, n, data)
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(data: &[f64]) {
    const HUGE: usize = 2 << 20;
    let start = data.as_ptr() as usize;
    let end = start + std::mem::size_of_val(data);
    let (lo, hi) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
    if hi > lo {
        // SAFETY: [lo, hi) lies within `data`'s allocation; MADV_HUGEPAGE changes only how the
        // kernel backs the pages, not their contents or validity
        unsafe { libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_: &[f64]) {}

/// Sets column `k` of `j` to zero, writing it only if it holds anything else: an untouched
/// column of a [`zeroed_matrix`] is then read (from the kernel's shared zero page) but never
/// given pages of its own.
pub(crate) fn clear_column(j: &mut DMatrix<f64>, k: usize) {
    let mut column = j.column_mut(k);
    if column.iter().any(|v| *v != 0.0) {
        column.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeroed_matrix_is_zero_and_column_major() {
        let mut j = zeroed_matrix(1000, 3);
        assert_eq!(j.shape(), (1000, 3));
        assert!(j.iter().all(|v| *v == 0.0));
        j[(999, 1)] = 2.0;
        assert_eq!(j.as_slice()[1999], 2.0);
        clear_column(&mut j, 1);
        assert!(j.iter().all(|v| *v == 0.0));
    }
}
