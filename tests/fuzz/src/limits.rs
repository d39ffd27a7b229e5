//! Per-input limits: each input a harness runs gets at most [`TIME_LIMIT`] of wall time and
//! [`MEMORY_LIMIT`] bytes of heap above what its thread held before it — a parser that trusts a
//! length field and allocates for it, or loops on a malformed record, fails here instead of
//! passing because it eventually returned (or taking the machine down).
//!
//! Memory is counted per thread by this crate's global allocator (cargo runs the harnesses of a
//! test binary on parallel threads: a process-wide count would mix them). Time is watched by a
//! thread of its own, because a hung input never returns to be timed: past its deadline the
//! watchdog prints the harness and the input (hex) and aborts the process. An input over the
//! memory limit panics after it returns, so bolero prints it with its seed.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::collections::BTreeMap;
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Wall time one input may take (a parser answers garbage in milliseconds; this leaves room for
/// a loaded CI machine and debug assertions).
pub const TIME_LIMIT: Duration = Duration::from_secs(10);

/// Heap one input may hold at its peak, above its thread's before it (the inputs are at most a
/// few tens of KiB and their parsers peak at 2 MiB; one needing 64 MiB allocated for a length it read).
pub const MEMORY_LIMIT: usize = 64 << 20;

thread_local! {
    /// Bytes this thread holds now (allocations minus frees made on it; may go negative when
    /// it frees what another thread allocated).
    static LIVE: Cell<isize> = const { Cell::new(0) };
    /// The largest `LIVE` since the last reset.
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

/// The system allocator, counting each thread's bytes.
pub struct CountingAllocator;

fn count(delta: isize) {
    // `try_with`: a thread being torn down has no locals left; its bytes are not counted
    let _ = LIVE.try_with(|live| {
        let now = live.get() + delta;
        live.set(now);
        let _ = PEAK.try_with(|peak| {
            if now > peak.get() {
                peak.set(now);
            }
        });
    });
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        count(-(layout.size() as isize));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            count(new_size as isize - layout.size() as isize);
        }
        p
    }
}

/// What the harnesses' inputs took, per harness: (inputs, the slowest, the largest peak).
#[derive(Debug, Clone, Copy, Default)]
pub struct HarnessFigures {
    pub inputs: u64,
    pub slowest: Duration,
    pub largest_peak: usize,
}

struct Watch {
    deadline: Instant,
    harness: &'static str,
    /// The input's first 4 KiB, printed (in hex) only if it hangs.
    input: Vec<u8>,
}

fn watches() -> &'static Mutex<BTreeMap<u64, Watch>> {
    static WATCHES: OnceLock<Mutex<BTreeMap<u64, Watch>>> = OnceLock::new();
    WATCHES.get_or_init(|| {
        std::thread::spawn(|| loop {
            std::thread::sleep(Duration::from_millis(200));
            let w = watches().lock().unwrap_or_else(|e| e.into_inner());
            if let Some(late) = w.values().find(|w| Instant::now() > w.deadline) {
                eprintln!(
                    "metrocell-fuzz: harness {} — an input ran longer than {:?} (a hang?); input (hex): {}",
                    late.harness,
                    TIME_LIMIT,
                    hex(&late.input)
                );
                std::process::abort();
            }
        });
        Mutex::new(BTreeMap::new())
    })
}

fn figures() -> &'static Mutex<BTreeMap<&'static str, HarnessFigures>> {
    static FIGURES: OnceLock<Mutex<BTreeMap<&'static str, HarnessFigures>>> = OnceLock::new();
    FIGURES.get_or_init(|| Mutex::new(BTreeMap::new()))
}

fn thread_key() -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    std::thread::current().id().hash(&mut h);
    h.finish()
}

fn hex(input: &[u8]) -> String {
    input
        .iter()
        .take(4096)
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Runs one input of `harness` under the limits; panics (naming the input) when it held more
/// than [`MEMORY_LIMIT`], aborts the process when it runs past [`TIME_LIMIT`].
pub fn bounded<R>(harness: &'static str, input: &[u8], run: impl FnOnce() -> R) -> R {
    let key = thread_key();
    watches().lock().unwrap_or_else(|e| e.into_inner()).insert(
        key,
        Watch {
            deadline: Instant::now() + TIME_LIMIT,
            harness,
            input: input[..input.len().min(4096)].to_vec(),
        },
    );
    let before = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(before));
    let started = Instant::now();
    let out = run();
    let took = started.elapsed();
    let peak = (PEAK.with(Cell::get) - before).max(0) as usize;
    watches()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .remove(&key);
    {
        let mut f = figures().lock().unwrap_or_else(|e| e.into_inner());
        let f = f.entry(harness).or_default();
        f.inputs += 1;
        f.slowest = f.slowest.max(took);
        f.largest_peak = f.largest_peak.max(peak);
    }
    assert!(
        peak <= MEMORY_LIMIT,
        "harness {harness}: one input held {:.1} MiB at its peak (limit {} MiB): an allocation sized by what the input says?",
        peak as f64 / (1 << 20) as f64,
        MEMORY_LIMIT >> 20
    );
    out
}

/// The figures of `harness` so far (for the line each harness prints at its end).
pub fn harness_figures(harness: &str) -> HarnessFigures {
    figures()
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get(harness)
        .copied()
        .unwrap_or_default()
}

/// "harness: N inputs, slowest T ms, largest peak M MiB" for the test's output.
pub fn report(harness: &str) -> String {
    let f = harness_figures(harness);
    format!(
        "{harness}: {} inputs, slowest {:.1} ms (limit {} s), largest peak {:.2} MiB (limit {} MiB)",
        f.inputs,
        f.slowest.as_secs_f64() * 1e3,
        TIME_LIMIT.as_secs(),
        f.largest_peak as f64 / (1 << 20) as f64,
        MEMORY_LIMIT >> 20
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_input_that_holds_too_much_is_named() {
        let small = bounded("limits_self_test", b"ok", || vec![0u8; 1 << 20].len());
        assert_eq!(small, 1 << 20);
        let big = std::panic::catch_unwind(|| {
            bounded("limits_self_test", b"\x01\x02", || {
                // touched, so the pages are real, then freed before the check
                let v = vec![1u8; MEMORY_LIMIT + (1 << 20)];
                v.iter().map(|&b| b as usize).sum::<usize>()
            })
        });
        let e = big.expect_err("over the limit");
        let msg = e.downcast_ref::<String>().cloned().unwrap_or_default();
        assert!(
            msg.contains("limits_self_test") && msg.contains("MiB"),
            "{msg}"
        );
        let f = harness_figures("limits_self_test");
        assert_eq!(f.inputs, 2);
        assert!(f.largest_peak > MEMORY_LIMIT);
    }
}
