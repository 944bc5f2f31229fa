//! Reading a whole input file into memory, refusing anything that is not a regular file.
//!
//! Every reader in this crate parses from bytes (`*_from` functions, which the fuzz
//! harness drives directly); the path readers get those bytes here. The metadata is
//! checked *before* opening because opening a FIFO for reading blocks until a writer
//! appears: a FIFO matched by a poses glob would otherwise hang a run forever. The file
//! is checked again after opening, so a path swapped in between is still refused.

use std::io::Read;
use std::path::Path;

use crate::error::IoError;

/// The bytes of the regular file at `path` (symlinks followed). A directory, FIFO,
/// socket or device is refused with [`IoError::NotAFile`] without being opened.
pub fn read_regular_file(path: &Path) -> Result<Vec<u8>, IoError> {
    let meta = std::fs::metadata(path).map_err(|e| IoError::io(path, e))?;
    check_regular(path, &meta)?;
    let mut file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let meta = file.metadata().map_err(|e| IoError::io(path, e))?;
    check_regular(path, &meta)?;
    // The size is a hint only (the file may grow or shrink while it is read).
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0).min(1 << 30));
    file.read_to_end(&mut bytes).map_err(|e| IoError::io(path, e))?;
    Ok(bytes)
}

/// The bytes of `path` as UTF-8 text; invalid UTF-8 is reported with its byte offset.
pub fn read_text_file(path: &Path) -> Result<String, IoError> {
    text_from(path, read_regular_file(path)?)
}

/// `bytes` as UTF-8 text, or a [`IoError::NotText`] naming the first bad byte.
pub(crate) fn text_from(path: &Path, bytes: Vec<u8>) -> Result<String, IoError> {
    String::from_utf8(bytes)
        .map_err(|e| IoError::NotText { path: path.to_owned(), offset: e.utf8_error().valid_up_to() })
}

fn check_regular(path: &Path, meta: &std::fs::Metadata) -> Result<(), IoError> {
    let file_type = meta.file_type();
    if file_type.is_file() {
        return Ok(());
    }
    Err(IoError::NotAFile { path: path.to_owned(), what: describe_type(&file_type) })
}

/// A name for a file type that is not a regular file.
pub(crate) fn describe_type(file_type: &std::fs::FileType) -> &'static str {
    if file_type.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if file_type.is_socket() {
            return "a socket";
        }
        if file_type.is_char_device() || file_type.is_block_device() {
            return "a device";
        }
    }
    "not a regular file"
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory is refused by its metadata, before any open.
    #[test]
    fn a_directory_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let err = read_regular_file(dir.path()).unwrap_err();
        assert!(matches!(err, IoError::NotAFile { what: "a directory", .. }), "{err}");
    }

    /// Invalid UTF-8 names the offset of the first bad byte.
    #[test]
    fn invalid_utf8_names_its_offset() {
        let err = text_from(Path::new("x.obj"), b"v 0 0\xff".to_vec()).unwrap_err();
        assert!(matches!(err, IoError::NotText { offset: 5, .. }), "{err}");
    }
}
