//! Which instant a frame read from a file is stamped with (`stamp_source` parameter). A frame's
//! stamp should be its capture time, so that detections, poses and every later fusion line up
//! with the machine's other streams; the time the node happened to read the file is not that.
//!
//! - `mtime` (default): the file's modification time, which a camera's acquisition software
//!   sets when it writes the frame (system clock, UTC epoch). Copying files without preserving
//!   times (`cp` without `-p`) destroys it; use `filename` then.
//! - `filename`: parsed from the file name with `stamp_pattern`, a literal name with exactly one
//!   placeholder: `{ns}`, `{us}`, `{ms}` (integer nanoseconds / microseconds / milliseconds since
//!   the epoch) or `{s}` (seconds, optional fraction, read to the nanosecond without rounding
//!   through floating point), e.g. `frame_{ns}.png` or `cam0_{s}.tiff`.
//! - `now`: the publication instant on the node's clock (sim time honoured), the old behaviour;
//!   the only choice that keeps stamps increasing when `loop` replays the same files.
//!
//! Frames that come from the simulator (`/camera/image_raw`) never pass through this node: the
//! fiducial node takes them directly and copies their header (the simulated capture stamp).

use std::path::Path;
use std::time::UNIX_EPOCH;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum StampError {
    #[error("parameter stamp_source: `{0}` is not one of mtime, now, filename")]
    UnknownSource(String),
    #[error("parameter stamp_pattern `{0}`: needs exactly one of {{ns}}, {{us}}, {{ms}}, {{s}}")]
    BadPattern(String),
    #[error("{path}: {reason}")]
    File { path: String, reason: String },
}

/// A file name template with one time placeholder.
#[derive(Debug, Clone, PartialEq)]
pub struct FilenamePattern {
    prefix: String,
    suffix: String,
    /// Nanoseconds per unit of the placeholder; 0 = `{s}` (decimal seconds).
    ns_per_unit: i64,
}

impl FilenamePattern {
    pub fn parse(pattern: &str) -> Result<Self, StampError> {
        let units = [
            ("{ns}", 1),
            ("{us}", 1_000),
            ("{ms}", 1_000_000),
            ("{s}", 0),
        ];
        let found: Vec<_> = units.iter().filter(|(p, _)| pattern.contains(p)).collect();
        let [(p, ns)] = found.as_slice() else {
            return Err(StampError::BadPattern(pattern.into()));
        };
        let (prefix, suffix) = pattern.split_once(p).expect("contains");
        if suffix.contains(p) {
            return Err(StampError::BadPattern(pattern.into()));
        }
        Ok(FilenamePattern {
            prefix: prefix.into(),
            suffix: suffix.into(),
            ns_per_unit: *ns,
        })
    }

    /// The stamp (ns since the epoch) in `name`, or why not.
    pub fn stamp_ns(&self, name: &str) -> Result<i64, String> {
        let mismatch = || {
            format!(
                "file name does not match stamp_pattern `{}{{…}}{}`",
                self.prefix, self.suffix
            )
        };
        let middle = name
            .strip_prefix(&self.prefix)
            .and_then(|r| r.strip_suffix(&self.suffix))
            .ok_or_else(mismatch)?;
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        let overflow = || format!("time `{middle}` in the file name is out of range");
        if self.ns_per_unit > 0 {
            if !digits(middle) {
                return Err(format!(
                    "`{middle}` in the file name is not an integer time"
                ));
            }
            let v: i64 = middle.parse().map_err(|_| overflow())?;
            return v.checked_mul(self.ns_per_unit).ok_or_else(overflow);
        }
        let (int, frac) = middle.split_once('.').unwrap_or((middle, ""));
        if !digits(int) || !(frac.is_empty() || digits(frac)) {
            return Err(format!(
                "`{middle}` in the file name is not a time in seconds"
            ));
        }
        // Nanosecond resolution: digits past the ninth are dropped (truncation, not rounding).
        let frac9: String = frac.chars().chain(std::iter::repeat('0')).take(9).collect();
        let s: i64 = int.parse().map_err(|_| overflow())?;
        s.checked_mul(1_000_000_000)
            .and_then(|v| v.checked_add(frac9.parse::<i64>().ok()?))
            .ok_or_else(overflow)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum StampSource {
    Mtime,
    Now,
    Filename(FilenamePattern),
}

impl StampSource {
    /// From the `stamp_source` and `stamp_pattern` parameters.
    pub fn parse(source: &str, pattern: &str) -> Result<Self, StampError> {
        match source.trim().to_ascii_lowercase().as_str() {
            "mtime" => Ok(StampSource::Mtime),
            "now" => Ok(StampSource::Now),
            "filename" => Ok(StampSource::Filename(FilenamePattern::parse(pattern)?)),
            other => Err(StampError::UnknownSource(other.into())),
        }
    }

    /// The capture stamp of `path` (ns since the epoch), or `None` for `now` (the caller stamps
    /// with its clock at publication).
    pub fn file_stamp_ns(&self, path: &Path) -> Result<Option<i64>, StampError> {
        let err = |reason: String| StampError::File {
            path: path.display().to_string(),
            reason,
        };
        match self {
            StampSource::Now => Ok(None),
            StampSource::Mtime => {
                let modified = std::fs::metadata(path)
                    .and_then(|m| m.modified())
                    .map_err(|e| err(format!("no modification time ({e})")))?;
                let d = modified
                    .duration_since(UNIX_EPOCH)
                    .map_err(|_| err("modification time before 1970".into()))?;
                Ok(Some(d.as_nanos() as i64))
            }
            StampSource::Filename(p) => {
                let name = path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                p.stamp_ns(&name).map(Some).map_err(err)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_name_patterns_parse_exactly_and_mismatches_are_named() {
        let p = FilenamePattern::parse("frame_{ns}.png").unwrap();
        assert_eq!(
            p.stamp_ns("frame_1700000000123456789.png"),
            Ok(1_700_000_000_123_456_789)
        );
        assert!(p.stamp_ns("frame_17x.png").unwrap_err().contains("17x"));
        assert!(p
            .stamp_ns("img_1.png")
            .unwrap_err()
            .contains("does not match"));
        let ms = FilenamePattern::parse("{ms}.tiff").unwrap();
        assert_eq!(
            ms.stamp_ns("1700000000123.tiff"),
            Ok(1_700_000_000_123_000_000)
        );
        let s = FilenamePattern::parse("cam0_{s}.png").unwrap();
        // 0.1 is not exact in binary: parsing through f64 would give ...100000001 or ...099999999.
        assert_eq!(
            s.stamp_ns("cam0_1700000000.1.png"),
            Ok(1_700_000_000_100_000_000)
        );
        assert_eq!(
            s.stamp_ns("cam0_1700000000.1234567899.png"),
            Ok(1_700_000_000_123_456_789)
        );
        assert_eq!(s.stamp_ns("cam0_12.png"), Ok(12_000_000_000));
        assert!(s.stamp_ns("cam0_.5.png").is_err());
        assert!(FilenamePattern::parse("frame.png").is_err());
        assert!(FilenamePattern::parse("{ns}_{ms}.png").is_err());
        assert!(FilenamePattern::parse("{ns}_{ns}.png").is_err());
        assert!(ms
            .stamp_ns("99999999999999999999.tiff")
            .unwrap_err()
            .contains("out of range"));
    }

    #[test]
    fn sources_parse_and_mtime_is_the_files() {
        assert_eq!(StampSource::parse("now", ""), Ok(StampSource::Now));
        assert!(StampSource::parse("exif", "")
            .unwrap_err()
            .to_string()
            .contains("exif"));
        assert!(StampSource::parse("filename", "x.png")
            .unwrap_err()
            .to_string()
            .contains("stamp_pattern"));
        let dir =
            std::env::temp_dir().join(format!("metrocell-camera-stamp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("frame_42.png");
        std::fs::write(&f, b"x").unwrap();
        let t = UNIX_EPOCH + std::time::Duration::new(1_600_000_000, 250_000_000);
        std::fs::File::options()
            .write(true)
            .open(&f)
            .unwrap()
            .set_modified(t)
            .unwrap();
        assert_eq!(
            StampSource::Mtime.file_stamp_ns(&f),
            Ok(Some(1_600_000_000_250_000_000))
        );
        assert_eq!(
            StampSource::parse("filename", "frame_{ms}.png")
                .unwrap()
                .file_stamp_ns(&f),
            Ok(Some(42_000_000))
        );
        assert_eq!(StampSource::Now.file_stamp_ns(&f), Ok(None));
        let e = StampSource::Mtime
            .file_stamp_ns(&dir.join("gone.png"))
            .unwrap_err();
        assert!(e.to_string().contains("gone.png"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
