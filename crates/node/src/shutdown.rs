//! Shutdown: a token that SIGINT/SIGTERM (or the program) triggers, which both blocking code
//! and async code can wait on. A second signal after the first exits the process at once
//! (status 130), so a hung shutdown can always be interrupted.

use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::Duration;

/// Cheap to clone; all clones see the same trigger.
#[derive(Clone, Debug)]
pub struct ShutdownToken {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    flag: Mutex<bool>,
    condvar: Condvar,
    watch: tokio::sync::watch::Sender<bool>,
}

impl Default for ShutdownToken {
    fn default() -> Self {
        ShutdownToken::new()
    }
}

impl ShutdownToken {
    pub fn new() -> ShutdownToken {
        let (watch, _) = tokio::sync::watch::channel(false);
        ShutdownToken {
            inner: Arc::new(Inner {
                flag: Mutex::new(false),
                condvar: Condvar::new(),
                watch,
            }),
        }
    }

    /// Request shutdown; wakes every waiter. Idempotent.
    pub fn trigger(&self) {
        let mut f = self.inner.flag.lock().unwrap_or_else(|p| p.into_inner());
        *f = true;
        self.inner.condvar.notify_all();
        self.inner.watch.send_replace(true);
    }

    pub fn is_triggered(&self) -> bool {
        *self.inner.flag.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Block until triggered.
    pub fn wait(&self) {
        let mut f = self.inner.flag.lock().unwrap_or_else(|p| p.into_inner());
        while !*f {
            f = self
                .inner
                .condvar
                .wait(f)
                .unwrap_or_else(|p| p.into_inner());
        }
    }

    /// Block until triggered or `timeout` passes; returns whether it was triggered.
    pub fn wait_timeout(&self, timeout: Duration) -> bool {
        let f = self.inner.flag.lock().unwrap_or_else(|p| p.into_inner());
        let (f, _) = self
            .inner
            .condvar
            .wait_timeout_while(f, timeout, |triggered| !*triggered)
            .unwrap_or_else(|p| p.into_inner());
        *f
    }

    /// Resolves when triggered. Works on any executor (tokio's sync primitives need no runtime).
    pub async fn triggered(&self) {
        let mut rx = self.inner.watch.subscribe();
        let _ = rx.wait_for(|v| *v).await;
    }
}

/// Tokens that SIGINT/SIGTERM trigger.
fn signal_targets() -> &'static Mutex<Vec<ShutdownToken>> {
    static TARGETS: OnceLock<Mutex<Vec<ShutdownToken>>> = OnceLock::new();
    TARGETS.get_or_init(|| Mutex::new(Vec::new()))
}

/// Make SIGINT and SIGTERM trigger `token`. The first call starts one background thread that
/// waits for the signals (a small current-thread tokio runtime of its own, so callers need no runtime).
pub fn trigger_on_signals(token: &ShutdownToken) -> std::io::Result<()> {
    static STARTED: OnceLock<Result<(), String>> = OnceLock::new();
    signal_targets()
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .push(token.clone());
    let started = STARTED.get_or_init(|| {
        let (ready_tx, ready_rx) = std::sync::mpsc::channel::<Result<(), String>>();
        let spawned = std::thread::Builder::new()
            .name("metrocell-signals".into())
            .spawn(move || {
                let rt = match tokio::runtime::Builder::new_current_thread()
                    .enable_io()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(e) => {
                        let _ = ready_tx.send(Err(e.to_string()));
                        return;
                    }
                };
                rt.block_on(async move {
                    use tokio::signal::unix::{signal, SignalKind};
                    let (mut int, mut term) = match (
                        signal(SignalKind::interrupt()),
                        signal(SignalKind::terminate()),
                    ) {
                        (Ok(i), Ok(t)) => (i, t),
                        (Err(e), _) | (_, Err(e)) => {
                            let _ = ready_tx.send(Err(e.to_string()));
                            return;
                        }
                    };
                    let _ = ready_tx.send(Ok(()));
                    let mut count = 0;
                    loop {
                        tokio::select! {
                            _ = int.recv() => {}
                            _ = term.recv() => {}
                        }
                        count += 1;
                        if count > 1 {
                            eprintln!("second signal: exiting immediately");
                            std::process::exit(130);
                        }
                        for t in signal_targets()
                            .lock()
                            .unwrap_or_else(|p| p.into_inner())
                            .iter()
                        {
                            t.trigger();
                        }
                    }
                });
            });
        match spawned {
            Ok(_) => ready_rx
                .recv()
                .unwrap_or_else(|_| Err("signal thread died".into())),
            Err(e) => Err(e.to_string()),
        }
    });
    started.clone().map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    #[test]
    fn token_wakes_blocking_and_async_waiters() {
        let t = ShutdownToken::new();
        assert!(!t.wait_timeout(Duration::from_millis(10)));
        let t2 = t.clone();
        let waiter = std::thread::spawn(move || {
            let start = Instant::now();
            t2.wait();
            start.elapsed()
        });
        let t3 = t.clone();
        let async_waiter = std::thread::spawn(move || futures::executor::block_on(t3.triggered()));
        std::thread::sleep(Duration::from_millis(50));
        t.trigger();
        assert!(waiter.join().unwrap() >= Duration::from_millis(40));
        async_waiter.join().unwrap();
        assert!(t.is_triggered() && t.wait_timeout(Duration::ZERO));
    }

    #[test]
    fn sigterm_triggers_registered_token() {
        let t = ShutdownToken::new();
        trigger_on_signals(&t).unwrap();
        // SAFETY-free: raise SIGTERM at our own process; the handler thread turns it into a trigger.
        let status = std::process::Command::new("kill")
            .args(["-TERM", &std::process::id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        assert!(
            t.wait_timeout(Duration::from_secs(1)),
            "SIGTERM did not trigger the token within 1 s"
        );
    }
}
