//! TCP client for trackers that stream [`crate::line_protocol`] lines.
//!
//! A background thread connects, reads, splits lines (partial lines wait for their end),
//! parses them and sends [`DriverEvent`]s over a channel. When the connection drops or cannot
//! be made, it retries after an exponential back-off (doubling from `initial_backoff` up to
//! `max_backoff`; reset once a connection has delivered a line). Readings whose time stamp is
//! not after the last accepted one are dropped as repeats, across reconnects, so no reading
//! is accepted twice.

use std::io::Read;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::line_protocol::{parse_line, LineError, LineFramer, LineReading};

#[derive(Debug, Clone, PartialEq)]
pub struct TcpClientConfig {
    /// host:port of the instrument
    pub address: String,
    pub initial_backoff: Duration,
    pub max_backoff: Duration,
}

/// What the driver saw.
#[derive(Debug, Clone, PartialEq)]
pub enum DriverEvent {
    Connected(SocketAddr),
    /// connection lost or refused, with the reason; a retry follows after `retry_in`
    Disconnected { reason: String, retry_in: Duration },
    Reading(LineReading),
    /// a line that is not a reading
    Garbage(LineError),
    /// a reading at time `t` (s) not after the last accepted one
    Repeat(f64),
}

/// Exponential back-off between connection attempts.
#[derive(Debug, Clone)]
pub struct Backoff {
    initial: Duration,
    max: Duration,
    next: Duration,
}

impl Backoff {
    pub fn new(initial: Duration, max: Duration) -> Self {
        Self { initial, max, next: initial }
    }

    /// The wait before the next attempt; doubles each call up to the maximum.
    pub fn next_delay(&mut self) -> Duration {
        let d = self.next;
        self.next = (self.next * 2).min(self.max);
        d
    }

    pub fn reset(&mut self) {
        self.next = self.initial;
    }
}

/// Accepts each time stamp once: strictly increasing times only.
#[derive(Debug, Clone, Default)]
pub struct Deduplicator {
    last: Option<f64>,
}

impl Deduplicator {
    pub fn accept(&mut self, t: f64) -> bool {
        if self.last.is_some_and(|l| t <= l) {
            return false;
        }
        self.last = Some(t);
        true
    }
}

/// The running client; dropping it stops the thread.
pub struct TcpTrackerClient {
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    events: Receiver<DriverEvent>,
}

impl TcpTrackerClient {
    pub fn start(config: TcpClientConfig) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, events) = channel();
        let s = stop.clone();
        let handle = std::thread::Builder::new()
            .name("tracker-tcp".into())
            .spawn(move || run(config, s, tx))
            .ok();
        Self { stop, handle, events }
    }

    /// The next event, if one is waiting.
    pub fn try_next(&self) -> Option<DriverEvent> {
        self.events.try_recv().ok()
    }

    /// The next event within `timeout`.
    pub fn next_timeout(&self, timeout: Duration) -> Option<DriverEvent> {
        match self.events.recv_timeout(timeout) {
            Ok(e) => Some(e),
            Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => None,
        }
    }
}

impl Drop for TcpTrackerClient {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

const POLL: Duration = Duration::from_millis(50);

fn run(config: TcpClientConfig, stop: Arc<AtomicBool>, tx: Sender<DriverEvent>) {
    let mut backoff = Backoff::new(config.initial_backoff, config.max_backoff);
    let mut dedup = Deduplicator::default();
    let mut framer = LineFramer::new();
    while !stop.load(Ordering::Relaxed) {
        let reason = match connect(&config.address) {
            Ok((stream, addr)) => {
                if tx.send(DriverEvent::Connected(addr)).is_err() {
                    return;
                }
                framer.reset();
                match read_lines(stream, &stop, &tx, &mut framer, &mut dedup) {
                    Ok(delivered) => {
                        if delivered {
                            backoff.reset();
                        }
                        "connection closed by the instrument".to_string()
                    }
                    Err(e) => e,
                }
            }
            Err(e) => e,
        };
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let retry_in = backoff.next_delay();
        if tx.send(DriverEvent::Disconnected { reason, retry_in }).is_err() {
            return;
        }
        let until = Instant::now() + retry_in;
        while Instant::now() < until && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(POLL.min(until.saturating_duration_since(Instant::now())));
        }
    }
}

fn connect(address: &str) -> Result<(TcpStream, SocketAddr), String> {
    let addrs: Vec<SocketAddr> = address.to_socket_addrs().map_err(|e| format!("address '{address}': {e}"))?.collect();
    let mut last = format!("address '{address}' resolves to nothing");
    for a in addrs {
        match TcpStream::connect_timeout(&a, Duration::from_secs(2)) {
            Ok(s) => {
                s.set_read_timeout(Some(POLL)).map_err(|e| e.to_string())?;
                return Ok((s, a));
            }
            Err(e) => last = format!("connect to {a}: {e}"),
        }
    }
    Err(last)
}

/// Reads until EOF (Ok(whether any line arrived)), an error, or stop.
fn read_lines(mut stream: TcpStream, stop: &AtomicBool, tx: &Sender<DriverEvent>, framer: &mut LineFramer, dedup: &mut Deduplicator) -> Result<bool, String> {
    let mut buf = [0u8; 4096];
    let mut delivered = false;
    while !stop.load(Ordering::Relaxed) {
        let n = match stream.read(&mut buf) {
            Ok(0) => return Ok(delivered),
            Ok(n) => n,
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted) => continue,
            Err(e) => return Err(format!("read: {e}")),
        };
        for line in framer.feed(&buf[..n]) {
            delivered = true;
            let event = match line.and_then(|l| parse_line(&l)) {
                Ok(None) => continue,
                Ok(Some(r)) if dedup.accept(r.t) => DriverEvent::Reading(r),
                Ok(Some(r)) => DriverEvent::Repeat(r.t),
                Err(e) => DriverEvent::Garbage(e),
            };
            if tx.send(event).is_err() {
                return Ok(delivered);
            }
        }
    }
    Ok(delivered)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backoff_doubles_to_its_cap_and_resets() {
        let mut b = Backoff::new(Duration::from_millis(100), Duration::from_millis(500));
        let d: Vec<u128> = (0..5).map(|_| b.next_delay().as_millis()).collect();
        assert_eq!(d, vec![100, 200, 400, 500, 500]);
        b.reset();
        assert_eq!(b.next_delay().as_millis(), 100);
    }

    #[test]
    fn deduplicator_accepts_each_time_once() {
        let mut d = Deduplicator::default();
        assert!(d.accept(1.0) && d.accept(2.0));
        assert!(!d.accept(2.0) && !d.accept(1.5));
        assert!(d.accept(2.1));
    }
}
