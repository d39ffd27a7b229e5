//! Records evaluated in parallel: the records of a problem split into contiguous chunks, one per
//! worker thread, each with its own scratch (signals the model writes into, Jacobian buffers).
//!
//! A model evaluation is independent per record, so chunks need no coordination; results are
//! written to disjoint rows, and the outcome is bit for bit the same for any number of workers
//! (each record is computed by the same code on the same inputs). An error is the one of the
//! lowest-numbered failing record, as a sequential loop would report it.

use std::sync::Mutex;

/// Fewest records worth a thread of their own (spawning one costs ~20 µs, a record ~3 µs).
const MIN_RECORDS_PER_WORKER: usize = 1000;

/// The records `start..start + len` and a worker's scratch for them.
pub(crate) struct Chunk<S> {
    pub start: usize,
    pub len: usize,
    pub scratch: S,
}

/// `count` records split into as many chunks as there are cores (at most one per
/// [`MIN_RECORDS_PER_WORKER`] records), each with scratch `make(start, len)`.
pub(crate) fn split<S>(
    count: usize,
    mut make: impl FnMut(usize, usize) -> S,
) -> Vec<Mutex<Chunk<S>>> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = cores.min(count / MIN_RECORDS_PER_WORKER).max(1);
    let base = count / workers;
    let extra = count % workers;
    let mut start = 0;
    (0..workers)
        .map(|w| {
            let len = base + usize::from(w < extra);
            let chunk = Chunk {
                start,
                len,
                scratch: make(start, len),
            };
            start += len;
            Mutex::new(chunk)
        })
        .collect()
}

/// Runs `work(chunk, out)` for every chunk, chunk k with the k-th of `outputs` (its share of
/// the caller's output), chunks after the first on scoped threads. Returns the first error in
/// chunk order.
pub(crate) fn for_each<S: Send, O: Send, E: Send>(
    chunks: &[Mutex<Chunk<S>>],
    outputs: Vec<O>,
    work: impl Fn(&mut Chunk<S>, O) -> Result<(), E> + Sync,
) -> Result<(), E> {
    assert_eq!(chunks.len(), outputs.len(), "one output per chunk");
    // a poisoned lock means a worker panicked mid-record: its scratch is rewritten from the
    // record's own signals by the next evaluation, so it is safe to go on using it
    let run = |c: &Mutex<Chunk<S>>, o: O| work(&mut c.lock().unwrap_or_else(|p| p.into_inner()), o);
    let mut pairs = chunks.iter().zip(outputs);
    let Some((first, first_out)) = pairs.next() else {
        return Ok(());
    };
    if chunks.len() == 1 {
        return run(first, first_out);
    }
    std::thread::scope(|scope| {
        let run = &run;
        let handles: Vec<_> = pairs.map(|(c, o)| scope.spawn(move || run(c, o))).collect();
        let first = run(first, first_out);
        let rest: Vec<Result<(), E>> = handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect();
        first.and_then(|()| rest.into_iter().collect())
    })
}

/// Splits `out` (`per_record` values per record) into the chunks' shares.
pub(crate) fn shares<'o, S, T>(
    chunks: &[Mutex<Chunk<S>>],
    out: &'o mut [T],
    per_record: usize,
) -> Vec<&'o mut [T]> {
    let mut rest = out;
    chunks
        .iter()
        .map(|c| {
            let len = c.lock().unwrap_or_else(|p| p.into_inner()).len * per_record;
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
            rest = tail;
            head
        })
        .collect()
}

/// A column-major matrix's storage written from several threads, each to its own rows.
#[derive(Clone, Copy)]
pub(crate) struct DisjointRows {
    ptr: *mut f64,
    rows: usize,
    cols: usize,
}

// SAFETY: the pointer is only written through `set_column`, whose callers (the chunks) own disjoint row
// ranges; the matrix it points into outlives the scoped threads that write it.
unsafe impl Send for DisjointRows {}
unsafe impl Sync for DisjointRows {}

impl DisjointRows {
    pub fn new(m: &mut nalgebra::DMatrix<f64>) -> Self {
        DisjointRows {
            ptr: m.as_mut_ptr(),
            rows: m.nrows(),
            cols: m.ncols(),
        }
    }

    /// Writes `values` into rows `row0..row0 + values.len()` of column `col`.
    ///
    /// # Safety
    /// No other thread reads or writes those rows while the matrix is shared this way.
    #[inline]
    pub unsafe fn set_rows(&self, row0: usize, col: usize, values: &[f64]) {
        assert!(
            row0 + values.len() <= self.rows && col < self.cols,
            "rows {row0}..{} of column {col} outside {} × {}",
            row0 + values.len(),
            self.rows,
            self.cols
        );
        // SAFETY: in bounds (checked above); the rows are this caller's alone (the contract)
        unsafe {
            std::ptr::copy_nonoverlapping(
                values.as_ptr(),
                self.ptr.add(row0 + col * self.rows),
                values.len(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_every_record_once_in_order() {
        for count in [0, 1, 999, 1000, 2001, 10_000] {
            let chunks = split(count, |start, len| (start, len));
            let mut next = 0;
            for c in &chunks {
                let c = c.lock().unwrap();
                assert_eq!((c.start, c.scratch), (next, (c.start, c.len)));
                next += c.len;
            }
            assert_eq!(next, count);
        }
    }

    #[test]
    fn the_first_error_in_record_order_wins() {
        let chunks = split(4000, |_, _| ());
        let mut out = vec![0usize; 4000];
        let outs = shares(&chunks, &mut out, 1);
        let r = for_each(&chunks, outs, |c, o: &mut [usize]| {
            for (i, v) in o.iter_mut().enumerate() {
                *v = c.start + i;
                if (c.start + i) % 1500 == 1499 {
                    return Err(c.start + i);
                }
            }
            Ok(())
        });
        assert_eq!(r, Err(1499));
        assert_eq!(out[..1499], (0..1499).collect::<Vec<_>>()[..]);
    }
}
