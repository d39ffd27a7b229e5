//! The taker: a thread that does nothing but move samples out of the DDS readers into memory,
//! so that the recording loop's stalls (a flush and fsync, compressing a chunk, a CPU-starved
//! moment on a busy machine) never leave a reader's keep-last queue to overflow. rosbag2 does
//! the same with its message cache and writer thread.
//!
//! Samples wait in a queue bounded in bytes (`max_cache_size`). When it is full the taker stops
//! taking, so samples wait in the readers' queues as they would without it: the cache bounds
//! memory and never drops anything itself.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use metrocell_node::{RawMessage, RawSubscription};

/// After `stop`: how long the readers must stay empty before the taker ends (samples in
/// flight, or being repaired, arrive meanwhile).
const DRAIN_QUIET: Duration = Duration::from_millis(100);
/// After `stop`: the longest the taker goes on taking samples. A publisher that keeps sending
/// would otherwise hold the recorder up; a node is expected to stop within a second of SIGINT
/// (tests/system/node_shutdown.rs), and a caller that must have every message waits for the
/// recorder's counts before it stops it, as `metrocell demo` does.
const DRAIN_LIMIT: Duration = Duration::from_millis(300);

/// What the taker hands over, in the order it took it; `topic` is the index of the subscription
/// in the order they were added.
pub enum Taken {
    Message {
        topic: usize,
        message: RawMessage,
    },
    /// A sample that could not be taken (not CDR): the reader's error.
    Unreadable {
        topic: usize,
        error: String,
    },
}

pub struct Taker {
    subscriptions: Sender<RawSubscription>,
    taken: Receiver<Taken>,
    cached_bytes: Arc<AtomicUsize>,
    /// Set when the cache was found full since the last `take_cache_full`.
    cache_was_full: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Taker {
    pub fn start(max_cache_bytes: usize) -> std::io::Result<Taker> {
        let (add, added) = channel::<RawSubscription>();
        let (hand_over, taken) = channel::<Taken>();
        let cached_bytes = Arc::new(AtomicUsize::new(0));
        let cache_was_full = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let (bytes, full, stopping) = (cached_bytes.clone(), cache_was_full.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name("recorder-taker".into())
            .spawn(move || {
                take_until_stopped(
                    &added,
                    &hand_over,
                    &bytes,
                    &full,
                    &stopping,
                    max_cache_bytes.max(1),
                );
            })?;
        Ok(Taker {
            subscriptions: add,
            taken,
            cached_bytes,
            cache_was_full,
            stop,
            thread: Some(thread),
        })
    }

    /// Take from this reader too; its samples are handed over with the next index.
    pub fn add(&self, subscription: RawSubscription) {
        // The taker thread lives until `stop`, so the channel is open.
        let _ = self.subscriptions.send(subscription);
    }

    /// The next sample taken, waiting at most `timeout`; `Err(true)` once the taker has ended
    /// (after `stop`) and everything it took has been handed over.
    pub fn next(&self, timeout: Duration) -> Result<Taken, bool> {
        match self.taken.recv_timeout(timeout) {
            Ok(t) => {
                if let Taken::Message { message, .. } = &t {
                    self.cached_bytes
                        .fetch_sub(message.payload.len(), Ordering::Relaxed);
                }
                Ok(t)
            }
            Err(RecvTimeoutError::Timeout) => Err(false),
            Err(RecvTimeoutError::Disconnected) => Err(true),
        }
    }

    /// Bytes of payload taken and not yet handed over.
    pub fn cached_bytes(&self) -> usize {
        self.cached_bytes.load(Ordering::Relaxed)
    }

    /// Whether the cache was full at some moment since the last call.
    pub fn take_cache_full(&self) -> bool {
        self.cache_was_full.swap(false, Ordering::Relaxed)
    }

    /// Take what is still arriving (until the readers stay empty for 100 ms, at most 300 ms),
    /// then end; `next` hands over the rest.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

impl Drop for Taker {
    fn drop(&mut self) {
        self.stop();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn take_until_stopped(
    added: &Receiver<RawSubscription>,
    hand_over: &Sender<Taken>,
    cached_bytes: &AtomicUsize,
    cache_was_full: &AtomicBool,
    stop: &AtomicBool,
    max_cache_bytes: usize,
) {
    let mut subscriptions: Vec<RawSubscription> = Vec::new();
    let mut draining_since: Option<Instant> = None;
    let mut last_taken = Instant::now();
    loop {
        subscriptions.extend(added.try_iter());
        if draining_since.is_none() && stop.load(Ordering::Relaxed) {
            draining_since = Some(Instant::now());
        }
        let mut taken = 0usize;
        for (topic, sub) in subscriptions.iter().enumerate() {
            loop {
                if cached_bytes.load(Ordering::Relaxed) >= max_cache_bytes {
                    cache_was_full.store(true, Ordering::Relaxed);
                    break;
                }
                let t = match sub.take() {
                    Ok(Some(message)) => {
                        cached_bytes.fetch_add(message.payload.len(), Ordering::Relaxed);
                        Taken::Message { topic, message }
                    }
                    Ok(None) => break,
                    Err(e) => Taken::Unreadable {
                        topic,
                        error: e.to_string(),
                    },
                };
                let unreadable = matches!(t, Taken::Unreadable { .. });
                taken += 1;
                if hand_over.send(t).is_err() {
                    return; // the recording loop has gone
                }
                if unreadable {
                    break;
                }
            }
        }
        if taken > 0 {
            last_taken = Instant::now();
        }
        if let Some(since) = draining_since {
            if (taken == 0 && last_taken.elapsed() >= DRAIN_QUIET) || since.elapsed() >= DRAIN_LIMIT
            {
                return;
            }
        }
        if taken == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}
