//! Atomic file writes: bytes go to a temp file in the destination's directory, are
//! flushed to disk, then renamed over the destination. A reader (or a later run) sees
//! the old file or the complete new one, never a torn write.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::IoError;

/// Writes a file atomically with `fill`, which receives a buffered writer. Creates the
/// parent directory. On any error the temp file is removed and the destination is
/// untouched.
///
/// What may be replaced is [`crate::confine::write_target`]'s rule: a character device
/// (`-o /dev/null`) is written through, as `cp` does, never renamed over; a directory,
/// FIFO, socket or block device is refused before anything is written.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    if crate::confine::write_target(path)? == crate::confine::WriteTarget::Device {
        let result = (|| {
            let file = fs::OpenOptions::new().write(true).open(path)?;
            let mut w = BufWriter::with_capacity(1 << 16, file);
            fill(&mut w)?;
            w.flush()
        })();
        return result.map_err(|e| IoError::io(path, e));
    }
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    fs::create_dir_all(dir).map_err(|e| IoError::io(dir, e))?;
    let tmp = temp_path(path);
    let result = (|| {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        // Checked again at the last moment: never rename over what is not a regular file.
        if crate::confine::write_target(path).map_err(std::io::Error::other)?
            != crate::confine::WriteTarget::Replace
        {
            return Err(std::io::Error::other("became a device while it was written; not replaced"));
        }
        fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = fs::remove_file(&tmp);
        IoError::io(path, e)
    })
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes `value` as pretty JSON (with a trailing newline) to `path`, atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), IoError> {
    let mut text = serde_json::to_string_pretty(value)
        .map_err(|e| IoError::Json { path: path.to_owned(), reason: e.to_string() })?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Reads JSON from `path` into `T`.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, IoError> {
    let bytes = crate::file::read_regular_file(path)?;
    serde_json::from_slice(&bytes).map_err(|e| IoError::Json { path: path.to_owned(), reason: e.to_string() })
}

/// A number unique to this call in this process: with the process id, what makes every
/// temporary name desal builds (files here, folders in `dir.rs`) its own.
pub(crate) fn next_temp_number() -> u64 {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    COUNTER.fetch_add(1, Ordering::Relaxed)
}

/// A temp name beside `path`, unique per process and call, starting with '.' so that
/// globs over a folder do not pick it up. Left-overs of a killed run end in `.tmp`.
fn temp_path(path: &Path) -> PathBuf {
    let n = next_temp_number();
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}
