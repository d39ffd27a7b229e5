//! TCP client for trackers that stream [`crate::line_protocol`] lines.
//!
//! A background thread connects, reads, splits lines (partial lines wait for their end),
//! parses them and sends [`DriverEvent`]s over a channel. When the connection drops or cannot
//! be made, it retries after an exponential back-off (doubling from `initial_backoff` up to
//! `max_backoff`; reset once a connection has delivered a line). Readings whose time stamp is
//! not after the last accepted one are dropped as repeats, across reconnects, so no reading
//! is accepted twice.
//!
//! [`LineFormat::LeicaGsi`]: the lines are Leica GSI blocks from a total station
//! ([`crate::total_station_gsi`]), one measurement per line. GSI blocks carry no time stamp of
//! the measurement: each is stamped with the wall clock (Unix time) when its line arrived, kept
//! strictly increasing, and none is dropped as a repeat (a buffer resent after a reconnect comes
//! through again; total stations send a block once per measurement).

use std::io::Read;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::line_protocol::{parse_line, LineError, LineFramer, LineReading};
use crate::total_station_gsi::{parse_gsi_line, GsiBlock};

/// What the instrument's lines are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineFormat {
    /// a laser tracker's `t_s,target,range_m,azimuth_rad,elevation_rad[,…]` ([`crate::line_protocol`])
    #[default]
    TrackerCsv,
    /// a total station's Leica GSI-8 / GSI-16 measurement blocks ([`crate::total_station_gsi`])
    LeicaGsi,
}

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
    Disconnected {
        reason: String,
        retry_in: Duration,
    },
    Reading(LineReading),
    /// a total station's measurement block ([`LineFormat::LeicaGsi`]), stamped when its line
    /// arrived (ns since the Unix epoch)
    TotalStation {
        received_ns: i64,
        block: GsiBlock,
    },
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
        Self {
            initial,
            max,
            next: initial,
        }
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
    /// A laser tracker streaming [`crate::line_protocol`] lines.
    pub fn start(config: TcpClientConfig) -> Self {
        Self::start_with(config, LineFormat::TrackerCsv)
    }

    /// An instrument streaming lines of `format`.
    pub fn start_with(config: TcpClientConfig, format: LineFormat) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, events) = channel();
        let s = stop.clone();
        let handle = std::thread::Builder::new()
            .name("tracker-tcp".into())
            .spawn(move || run(config, format, s, tx))
            .ok();
        Self {
            stop,
            handle,
            events,
        }
    }

    /// The next event, if one is waiting.
    pub fn try_next(&self) -> Option<DriverEvent> {
        self.events.try_recv().ok()
    }

    /// The next event within `timeout`.
    pub fn next_timeout(&self, timeout: Duration) -> Option<DriverEvent> {
        self.events.recv_timeout(timeout).ok()
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

fn run(
    config: TcpClientConfig,
    format: LineFormat,
    stop: Arc<AtomicBool>,
    tx: Sender<DriverEvent>,
) {
    let mut backoff = Backoff::new(config.initial_backoff, config.max_backoff);
    let mut parser = LineParser {
        format,
        dedup: Deduplicator::default(),
        last_received_ns: i64::MIN,
    };
    let mut framer = LineFramer::new();
    while !stop.load(Ordering::Relaxed) {
        let reason = match connect(&config.address) {
            Ok((stream, addr)) => {
                if tx.send(DriverEvent::Connected(addr)).is_err() {
                    return;
                }
                framer.reset();
                match read_lines(stream, &stop, &tx, &mut framer, &mut parser) {
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
        if tx
            .send(DriverEvent::Disconnected { reason, retry_in })
            .is_err()
        {
            return;
        }
        let until = Instant::now() + retry_in;
        while Instant::now() < until && !stop.load(Ordering::Relaxed) {
            std::thread::sleep(POLL.min(until.saturating_duration_since(Instant::now())));
        }
    }
}

fn connect(address: &str) -> Result<(TcpStream, SocketAddr), String> {
    let addrs: Vec<SocketAddr> = address
        .to_socket_addrs()
        .map_err(|e| format!("address '{address}': {e}"))?
        .collect();
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

/// Lines → events, in the client's format; the state that outlives a connection.
struct LineParser {
    format: LineFormat,
    dedup: Deduplicator,
    last_received_ns: i64,
}

impl LineParser {
    /// The event of one framed line; None for blank and comment lines.
    fn event(&mut self, line: Result<String, LineError>) -> Option<DriverEvent> {
        let line = match line {
            Ok(l) => l,
            Err(e) => return Some(DriverEvent::Garbage(e)),
        };
        match self.format {
            LineFormat::TrackerCsv => match parse_line(&line) {
                Ok(None) => None,
                Ok(Some(r)) if self.dedup.accept(r.t) => Some(DriverEvent::Reading(r)),
                Ok(Some(r)) => Some(DriverEvent::Repeat(r.t)),
                Err(e) => Some(DriverEvent::Garbage(e)),
            },
            LineFormat::LeicaGsi => match parse_gsi_line(&line) {
                Ok(None) => None,
                Ok(Some(block)) => {
                    let now = std::time::SystemTime::now()
                        .duration_since(std::time::UNIX_EPOCH)
                        .map(|d| d.as_nanos() as i64)
                        .unwrap_or(0);
                    self.last_received_ns = now.max(self.last_received_ns.saturating_add(1));
                    Some(DriverEvent::TotalStation {
                        received_ns: self.last_received_ns,
                        block,
                    })
                }
                Err(error) => Some(DriverEvent::Garbage(LineError::Gsi {
                    line: line.trim_end().chars().take(120).collect(),
                    error,
                })),
            },
        }
    }
}

/// Reads until EOF (Ok(whether any line arrived)), an error, or stop.
fn read_lines(
    mut stream: TcpStream,
    stop: &AtomicBool,
    tx: &Sender<DriverEvent>,
    framer: &mut LineFramer,
    parser: &mut LineParser,
) -> Result<bool, String> {
    let mut buf = [0u8; 4096];
    let mut delivered = false;
    while !stop.load(Ordering::Relaxed) {
        let n = match stream.read(&mut buf) {
            Ok(0) => return Ok(delivered),
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                continue
            }
            Err(e) => return Err(format!("read: {e}")),
        };
        for line in framer.feed(&buf[..n]) {
            delivered = true;
            let Some(event) = parser.event(line) else {
                continue;
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
    fn gsi_lines_become_stamped_blocks_and_named_garbage() {
        let mut p = LineParser {
            format: LineFormat::LeicaGsi,
            dedup: Deduplicator::default(),
            last_received_ns: i64::MIN,
        };
        let line = "*110001+0000000000000001 21.022+0000000010000000 22.022+0000000010000000 31..00+0000000000002000 ";
        let (a, b) = (p.event(Ok(line.into())), p.event(Ok(line.into())));
        let (
            Some(DriverEvent::TotalStation {
                received_ns: ta,
                block,
            }),
            Some(DriverEvent::TotalStation {
                received_ns: tb, ..
            }),
        ) = (a, b)
        else {
            panic!("two blocks")
        };
        assert_eq!(block.slope_distance, Some(2.0));
        assert!(tb > ta, "stamps strictly increase: {ta} {tb}");
        assert_eq!(p.event(Ok("410001+00130027".into())), None);
        let Some(DriverEvent::Garbage(LineError::Gsi { line, error })) = p.event(Ok(
            "21.022+1000000x 22.022+10000000 31..00+00002000\r".into(),
        )) else {
            panic!("garbage")
        };
        assert_eq!(line, "21.022+1000000x 22.022+10000000 31..00+00002000");
        assert!(
            error.to_string().starts_with("GSI word 1 at column 1"),
            "{error}"
        );
    }

    #[test]
    fn deduplicator_accepts_each_time_once() {
        let mut d = Deduplicator::default();
        assert!(d.accept(1.0) && d.accept(2.0));
        assert!(!d.accept(2.0) && !d.accept(1.5));
        assert!(d.accept(2.1));
    }
}
