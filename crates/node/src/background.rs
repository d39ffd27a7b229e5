//! The node's background thread: a small current-thread tokio runtime that runs ros2-client's
//! Spinner (discovery bookkeeping, parameter services), the 1 Hz diagnostics heartbeat and the
//! `/clock` reader when `use_sim_time` is set. It ends when the node stops it (see `Background::stop`).

use std::sync::atomic::{AtomicBool, AtomicI64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use futures::FutureExt;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::rosgraph_msgs::msg::Clock;

use crate::diagnostics::Diagnostics;
use crate::shutdown::ShutdownToken;

/// Latest simulated time received on `/clock`.
#[derive(Clone, Debug, Default)]
pub struct SimTime {
    nanos: Arc<AtomicI64>,
    received: Arc<AtomicBool>,
}

impl SimTime {
    pub fn set(&self, nanos: i64) {
        self.nanos.store(nanos, Ordering::SeqCst);
        self.received.store(true, Ordering::SeqCst);
    }
    /// Nanoseconds since the epoch of the last `/clock` message, `None` before the first one.
    pub fn get(&self) -> Option<i64> {
        self.received
            .load(Ordering::SeqCst)
            .then(|| self.nanos.load(Ordering::SeqCst))
    }
}

pub(crate) struct BackgroundTasks {
    pub spinner: ros2_client::Spinner,
    pub heartbeat: Option<(
        ros2_client::Publisher<DiagnosticArray>,
        Diagnostics,
        Duration,
    )>,
    /// The `/clock` reader, the node's simulated time, and ros2-client's (which stamps its
    /// parameter events; its Spinner no longer reads `/clock` itself).
    pub clock: Option<(
        ros2_client::Subscription<Clock>,
        SimTime,
        std::sync::Arc<std::sync::Mutex<ros2_client::ROSTime>>,
    )>,
}

pub(crate) struct Background {
    stop: ShutdownToken,
    thread: Option<JoinHandle<()>>,
}

impl Background {
    pub fn start(tasks: BackgroundTasks, fqn: &str) -> std::io::Result<Background> {
        let stop = ShutdownToken::new();
        let stop_in = stop.clone();
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .build()?;
        let thread = std::thread::Builder::new()
            .name(format!("node{fqn}"))
            .spawn(move || {
                rt.block_on(run(tasks, stop_in));
            })?;
        Ok(Background {
            stop,
            thread: Some(thread),
        })
    }

    /// Stop heartbeat and clock tasks and wait for the thread (the caller stops the Spinner first).
    pub fn stop(&mut self) {
        self.stop.trigger();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

async fn run(tasks: BackgroundTasks, stop: ShutdownToken) {
    let BackgroundTasks {
        spinner,
        heartbeat,
        clock,
    } = tasks;
    let spin = async {
        futures::select! {
            r = spinner.spin().fuse() => if let Err(e) = r { eprintln!("ros2-client spinner stopped: {e:?}") },
            _ = stop.triggered().fuse() => {}
        }
    };
    let beat = async {
        let Some((publisher, diagnostics, period)) = heartbeat else {
            return;
        };
        loop {
            let msg = diagnostics.to_message(crate::logging::system_time_ns());
            // Best effort: a full send window must not stop the heartbeat.
            let _ = publisher.publish(msg);
            futures::select! {
                _ = tokio::time::sleep(period).fuse() => {}
                _ = stop.triggered().fuse() => return,
            }
        }
    };
    let clock_task = async {
        let Some((subscription, sim_time, ros2_client_time)) = clock else {
            return;
        };
        loop {
            futures::select! {
                r = subscription.async_take().fuse() => if let Ok((c, _)) = r {
                    sim_time.set(c.clock.nanos());
                    if let Ok(mut t) = ros2_client_time.lock() {
                        *t = ros2_client::ROSTime::from_nanos(c.clock.nanos());
                    }
                },
                _ = stop.triggered().fuse() => return,
            }
        }
    };
    futures::join!(spin, beat, clock_task);
}

impl Drop for Background {
    fn drop(&mut self) {
        self.stop();
    }
}
