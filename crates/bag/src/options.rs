//! Options of [`crate::BagWriter`].

use std::time::Duration;

/// Chunk compression of the MCAP file (rosbag2 "storage" compression; metadata.yaml then says
/// `compression_mode: ''`, as rosbag2 does for MCAP chunk compression).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkCompression {
    None,
    Zstd,
    Lz4,
}

impl ChunkCompression {
    pub(crate) fn to_mcap(self) -> Option<mcap::Compression> {
        match self {
            ChunkCompression::None => None,
            ChunkCompression::Zstd => Some(mcap::Compression::Zstd),
            ChunkCompression::Lz4 => Some(mcap::Compression::Lz4),
        }
    }
}

/// When to close the current `.mcap` file and continue in the next one (`_1.mcap`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SplitPolicy {
    /// Split once the current file holds at least this many bytes.
    pub max_file_bytes: Option<u64>,
    /// Split once a message's log time is this far past the first log time of the file.
    pub max_file_duration: Option<Duration>,
}

/// Writer options. Defaults: zstd level 1 chunks of 1 MiB (uncompressed), flush every 1 s
/// with `fdatasync`, no split.
#[derive(Debug, Clone)]
pub struct WriterOptions {
    pub compression: ChunkCompression,
    /// Target uncompressed chunk size in bytes; a chunk is closed once it exceeds this.
    pub chunk_size: u64,
    /// Crash-safety bound. Whenever `write`/`tick` runs and at least this much wall-clock time
    /// has passed since the last flush, the open chunk is closed, written, the OS buffers are
    /// flushed (and fsynced if `sync_on_flush`) and metadata.yaml is rewritten.
    /// Minimum 100 ms.
    pub flush_interval: Duration,
    /// fdatasync the .mcap file at every flush (survives power loss, not just process death).
    pub sync_on_flush: bool,
    pub split: SplitPolicy,
    /// zstd compression level (0 = zstd's default, 3); ignored for lz4 (always fast mode). Default 1: on the 2-core test machine
    /// level 3 compressed 1920x1080 mono8 frames at 64 MB/s, below a 30 Hz camera's 62 MB/s
    /// plus headroom, while level 1 ran at 230 MB/s for a 3 % larger file.
    pub compression_level: u32,
    /// zstd worker threads (0 = compress on the calling thread).
    pub compression_threads: u32,
    /// Test hook: the file sink fails with ENOSPC after this many bytes in total (per file).
    #[doc(hidden)]
    pub fail_after_bytes: Option<u64>,
}

impl Default for WriterOptions {
    fn default() -> Self {
        Self {
            compression: ChunkCompression::Zstd,
            chunk_size: 1 << 20,
            flush_interval: Duration::from_secs(1),
            sync_on_flush: true,
            split: SplitPolicy::default(),
            compression_level: 1,
            compression_threads: 0,
            fail_after_bytes: None,
        }
    }
}

/// Smallest accepted flush interval.
pub const MIN_FLUSH_INTERVAL: Duration = Duration::from_millis(100);
