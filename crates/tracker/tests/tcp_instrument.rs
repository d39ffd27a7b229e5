//! The TCP driver against a small server that plays the instrument badly: lines split across
//! writes, garbage, a beam break, an out-of-range angle, a connection dropped mid-line, the
//! buffer resent after a reconnect, and a refused connection. Everything is reported and
//! survived; each reading is accepted exactly once.
//!
//! Run: `cargo test -p metrocell-laser-tracker --test tcp_instrument` (localhost only, no DDS).

use std::io::Write;
use std::net::TcpListener;
use std::time::{Duration, Instant};

use metrocell_compensation::SphericalNoise;
use metrocell_laser_tracker::line_protocol::LineError;
use metrocell_laser_tracker::reading::{AirSource, EdlenForm, ReadingError, ReadingProcessor};
use metrocell_laser_tracker::tcp_client::{DriverEvent, TcpClientConfig, TcpTrackerClient};

fn line(t: u32) -> String {
    format!("{t}.0,nest,2.{t:06},0.5,0.1,20.0,101325,0.45\n")
}

#[test]
fn instrument_misbehaviour_is_reported_and_survived() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap();
    let server = std::thread::spawn(move || {
        // connection 1: readings 1..5 with a split line, garbage, a beam break, a bad angle,
        // then a partial line and a dropped connection
        let (mut s, _) = listener.accept().unwrap();
        for t in 1..=3 {
            s.write_all(line(t).as_bytes()).unwrap();
        }
        let l4 = line(4);
        s.write_all(&l4.as_bytes()[..10]).unwrap();
        s.flush().unwrap();
        std::thread::sleep(Duration::from_millis(120));
        s.write_all(&l4.as_bytes()[10..]).unwrap();
        s.write_all(b"GARBAGE \x01\x02 not a reading\n").unwrap();
        s.write_all(b"4.5,nest,BREAK,0.5,0.1\n").unwrap();
        s.write_all(b"4.6,nest,2.0,0.5,3.5\n").unwrap(); // elevation beyond ±π/2
        s.write_all(line(5).as_bytes()).unwrap();
        s.write_all(b"4.9,nest,2.0,0.5,0.1\n").unwrap(); // time runs backwards: a repeat
        s.write_all(b"6.0,nest,2.0").unwrap(); // cut mid-line
        drop(s);
        // connection 2: the instrument resends from 4 on
        let (mut s, _) = listener.accept().unwrap();
        for t in 4..=8 {
            s.write_all(line(t).as_bytes()).unwrap();
        }
        drop(s);
        drop(listener); // then nobody listens: connection refused, back-off
    });

    let client = TcpTrackerClient::start(TcpClientConfig {
        address: address.to_string(),
        initial_backoff: Duration::from_millis(50),
        max_backoff: Duration::from_millis(200),
    });
    let processor = ReadingProcessor {
        noise: SphericalNoise {
            radial_base: 4e-6,
            radial_per_metre: 0.8e-6,
            angular: 3e-6,
        },
        air: AirSource::Station,
        form: EdlenForm::ShopFloor,
        max_range: 80.0,
    };
    let (mut accepted, mut beam_breaks, mut rejected, mut garbage, mut repeats, mut connects) =
        (Vec::new(), 0, Vec::new(), Vec::new(), Vec::new(), 0);
    let mut retries = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline && retries.len() < 4 {
        match client.next_timeout(Duration::from_millis(100)) {
            Some(DriverEvent::Connected(a)) => {
                assert_eq!(a, address);
                connects += 1;
            }
            Some(DriverEvent::Disconnected { retry_in, .. }) => retries.push(retry_in),
            Some(DriverEvent::Reading(r)) => match processor.process(&r.to_raw(1.00027)) {
                Ok(p) => accepted.push(p.time_ns),
                Err(ReadingError::BeamBreak(_)) => beam_breaks += 1,
                Err(e) => rejected.push(e),
            },
            Some(DriverEvent::Garbage(e)) => garbage.push(e),
            Some(DriverEvent::Repeat(t)) => repeats.push(t),
            Some(DriverEvent::TotalStation { block, .. }) => {
                panic!("a GSI block from a tracker's line stream: {block:?}")
            }
            None => {}
        }
    }
    server.join().unwrap();
    let secs: Vec<i64> = accepted.iter().map(|t| t / 1_000_000_000).collect();
    assert_eq!(
        secs,
        vec![1, 2, 3, 4, 5, 6, 7, 8],
        "each reading once, in order"
    );
    assert_eq!(beam_breaks, 1);
    assert_eq!(rejected.len(), 1);
    assert!(matches!(
        rejected[0],
        ReadingError::OutOfRange {
            field: "elevation",
            ..
        }
    ));
    assert_eq!(garbage.len(), 1);
    assert!(
        matches!(garbage[0], LineError::FieldCount(1)),
        "{:?}",
        garbage[0]
    );
    assert_eq!(
        repeats,
        vec![4.9, 4.0, 5.0],
        "backwards time and the resent buffer are dropped"
    );
    assert_eq!(connects, 2);
    // after connection 2 delivered lines the back-off restarted at 50 ms, then doubled while refused
    assert_eq!(
        retries[1..]
            .iter()
            .map(|d| d.as_millis())
            .collect::<Vec<_>>(),
        vec![50, 100, 200]
    );
}
