//! The byte sink under the MCAP writer: a buffered file that remembers how many bytes have
//! reached the operating system (`durable_len`, updated at every successful flush) and refuses
//! all writes after the first failure, so that nothing half-written follows a failure and the
//! file can be cut back and sealed.
//!
//! A flush hands the bytes to the OS at once — from then on they survive the process being
//! killed — and, with `sync_on_flush`, asks a syncer thread to fdatasync them to the device
//! (power loss). The fsync is off the caller's path on purpose: on a busy disk one took a
//! second (ext4 commits its whole journal on fsync), and a recorder waiting in it stops taking
//! samples, so a kill then lost a second of them instead of one flush interval. An fsync that
//! fails poisons the sink like a failed write. Dropping the sink waits for the last fsync.

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::sync::mpsc::{channel, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// State shared between the sink (owned by the MCAP writer) and the bag writer.
#[derive(Debug, Default)]
pub(crate) struct SinkState {
    /// Bytes handed to the sink so far (file position).
    pub position: u64,
    /// Bytes handed to the OS at the last successful flush (fsynced soon after if requested).
    pub durable_len: u64,
    /// Bytes known to be fsynced (with `sync_on_flush`).
    pub synced_len: u64,
    /// First error seen; once set every further write fails.
    pub failure: Option<io::Error>,
}

pub(crate) struct DurableFile {
    inner: BufWriter<File>,
    syncer: Option<Syncer>,
    fail_after_bytes: Option<u64>,
    pub(crate) state: Arc<Mutex<SinkState>>,
}

/// The thread that fdatasyncs the file when asked (requests carry the length flushed; a burst
/// of them costs one fsync).
struct Syncer {
    requests: Option<Sender<u64>>,
    thread: Option<JoinHandle<()>>,
}

impl Syncer {
    /// No thread could be made: `flush` fsyncs itself, as before the syncer existed.
    fn inline() -> Syncer {
        Syncer {
            requests: None,
            thread: None,
        }
    }

    fn start(file: &File, state: Arc<Mutex<SinkState>>) -> Option<Syncer> {
        // a second handle on the same open file: fdatasync syncs the file, whichever handle
        let file = file.try_clone().ok()?;
        let (requests, asked) = channel::<u64>();
        let thread = std::thread::Builder::new()
            .name("bag-fsync".into())
            .spawn(move || {
                while let Ok(mut len) = asked.recv() {
                    while let Ok(more) = asked.try_recv() {
                        len = len.max(more);
                    }
                    match file.sync_data() {
                        Ok(()) => {
                            let mut st = lock_state(&state);
                            st.synced_len = st.synced_len.max(len);
                        }
                        Err(e) => {
                            let mut st = lock_state(&state);
                            if st.failure.is_none() {
                                st.failure = Some(e);
                            }
                            return;
                        }
                    }
                }
            })
            .ok()?;
        Some(Syncer {
            requests: Some(requests),
            thread: Some(thread),
        })
    }
}

fn copy_error(e: &io::Error) -> io::Error {
    match e.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code),
        None => io::Error::new(e.kind(), e.to_string()),
    }
}

impl DurableFile {
    pub(crate) fn new(file: File, sync_on_flush: bool, fail_after_bytes: Option<u64>) -> Self {
        let state = Arc::new(Mutex::new(SinkState::default()));
        let syncer = sync_on_flush
            .then(|| Syncer::start(&file, state.clone()).unwrap_or_else(Syncer::inline));
        Self {
            inner: BufWriter::with_capacity(1 << 20, file),
            syncer,
            fail_after_bytes,
            state,
        }
    }

    fn lock(&self) -> MutexGuard<'_, SinkState> {
        lock_state(&self.state)
    }

    fn fail(&self, e: io::Error) -> io::Error {
        let copy = copy_error(&e);
        let mut st = self.lock();
        if st.failure.is_none() {
            st.failure = Some(e);
        }
        copy
    }

    fn check(&self) -> io::Result<()> {
        match &self.lock().failure {
            Some(e) => Err(copy_error(e)),
            None => Ok(()),
        }
    }
}

impl Write for DurableFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.check()?;
        let pos = self.lock().position;
        if let Some(limit) = self.fail_after_bytes {
            if pos + buf.len() as u64 > limit {
                // Simulated full disk: write what fits, as a real device would, then fail.
                let fits = limit.saturating_sub(pos) as usize;
                if fits > 0 {
                    let n = self.inner.write(&buf[..fits]).map_err(|e| self.fail(e))?;
                    self.lock().position += n as u64;
                    return Ok(n);
                }
                return Err(self.fail(io::Error::from_raw_os_error(28))); // ENOSPC
            }
        }
        let n = self.inner.write(buf).map_err(|e| self.fail(e))?;
        self.lock().position += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.check()?;
        self.inner.flush().map_err(|e| self.fail(e))?;
        let position = self.lock().position;
        match &self.syncer {
            Some(Syncer {
                requests: Some(r), ..
            }) => {
                // the syncer ended only after an fsync failed: the check above reports it
                let _ = r.send(position);
            }
            Some(_) => {
                // inline (no syncer thread)
                self.inner.get_ref().sync_data().map_err(|e| self.fail(e))?;
                self.lock().synced_len = position;
            }
            None => {}
        }
        self.lock().durable_len = position;
        Ok(())
    }
}

impl Seek for DurableFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        if let SeekFrom::Current(0) = pos {
            return Ok(self.lock().position);
        }
        self.check()?;
        self.inner.flush().map_err(|e| self.fail(e))?;
        let p = self.inner.get_mut().seek(pos).map_err(|e| self.fail(e))?;
        self.lock().position = p;
        Ok(p)
    }
}

impl Drop for DurableFile {
    /// The bytes still buffered go to the OS, and the last fsync is waited for, so a file the
    /// writer has finished is on the device when the writer returns.
    fn drop(&mut self) {
        let _ = self.inner.flush();
        if let Some(s) = &mut self.syncer {
            if let Some(r) = s.requests.take() {
                let position = lock_state(&self.state).position;
                let _ = r.send(position);
            }
            if let Some(t) = s.thread.take() {
                let _ = t.join();
            }
        }
    }
}

/// Lock the shared state; a poisoned lock (a panic elsewhere) still yields the data.
pub(crate) fn lock_state(state: &Mutex<SinkState>) -> MutexGuard<'_, SinkState> {
    state.lock().unwrap_or_else(|p| p.into_inner())
}
