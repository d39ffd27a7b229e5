//! The byte sink under the MCAP writer: a buffered file that remembers how many bytes are
//! known to be on disk (`durable_len`, updated at every successful flush) and refuses all
//! writes after the first failure, so that nothing half-written follows a failure and the
//! file can be cut back to `durable_len` and sealed.

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::sync::{Arc, Mutex, MutexGuard};

/// State shared between the sink (owned by the MCAP writer) and the bag writer.
#[derive(Debug, Default)]
pub(crate) struct SinkState {
    /// Bytes handed to the sink so far (file position).
    pub position: u64,
    /// Bytes flushed (and fsynced if requested) at the last successful flush.
    pub durable_len: u64,
    /// First error seen; once set every further write fails.
    pub failure: Option<io::Error>,
}

pub(crate) struct DurableFile {
    inner: BufWriter<File>,
    sync_on_flush: bool,
    fail_after_bytes: Option<u64>,
    pub(crate) state: Arc<Mutex<SinkState>>,
}

fn copy_error(e: &io::Error) -> io::Error {
    match e.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code),
        None => io::Error::new(e.kind(), e.to_string()),
    }
}

impl DurableFile {
    pub(crate) fn new(file: File, sync_on_flush: bool, fail_after_bytes: Option<u64>) -> Self {
        Self {
            inner: BufWriter::with_capacity(1 << 20, file),
            sync_on_flush,
            fail_after_bytes,
            state: Arc::new(Mutex::new(SinkState::default())),
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
        if self.sync_on_flush {
            self.inner.get_ref().sync_data().map_err(|e| self.fail(e))?;
        }
        let mut st = self.lock();
        st.durable_len = st.position;
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

/// Lock the shared state; a poisoned lock (a panic elsewhere) still yields the data.
pub(crate) fn lock_state(state: &Mutex<SinkState>) -> MutexGuard<'_, SinkState> {
    state.lock().unwrap_or_else(|p| p.into_inner())
}
