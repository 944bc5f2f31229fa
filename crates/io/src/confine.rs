//! The three rules every reader and writer of desal follows, CLI and Python alike, so that
//! no file — however it is crafted — makes desal touch a path that is not its own:
//!
//! 1. **What may be read from inside data** ([`resolve_inside`], [`read_inside`]). A path
//!    a *file* names (a glTF buffer or image URI) is percent-decoded, joined to the
//!    folder of the file that names it, its symlinks resolved, and must then be a regular
//!    file inside that folder. Absolute paths, `..` that climbs out, URL schemes, devices,
//!    FIFOs and directories are refused by name. Paths the *user* names (flags, pipeline
//!    keys, Python arguments) are trusted and read through [`crate::file`].
//! 2. **Names that become paths** ([`file_stem_for`], [`file_stems_for`]). A name read from
//!    a file (an animation name inside a pose name, a joint name) becomes one file name in
//!    one folder: ordinary names (`f000_poses@0.0000`) are kept as they are, anything else
//!    is percent-encoded, so the rule is one-to-one (`a/b` and `a_b` never meet), never
//!    contains a separator, `..` or a leading dot, and [`file_stems_for`] keeps names that
//!    differ only in case apart on case-insensitive file systems.
//! 3. **What may be replaced** ([`write_target`]). A writer replaces a regular file (or a
//!    symlink, which the rename replaces without touching its target) by temp file and
//!    rename; it writes *through* to a character device (`-o /dev/null`), as `cp` does;
//!    it refuses directories, FIFOs, sockets and block devices and never renames over
//!    them. [`crate::atomic::write_atomic_with`] applies it to every write.

use std::path::{Component, Path, PathBuf};

use crate::error::IoError;

/// Where a write goes, by [`write_target`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteTarget {
    /// Nothing there, a regular file, or a symlink: temp file, then rename over it.
    Replace,
    /// A character device (`/dev/null`, a terminal): written through, never replaced.
    Device,
}

/// Rule 3: how a write to `path` may go. A directory, FIFO, socket or block device (or
/// a symlink to one) is refused with [`IoError::NotWritable`], before anything is written.
pub fn write_target(path: &Path) -> Result<WriteTarget, IoError> {
    let Ok(meta) = std::fs::metadata(path) else { return Ok(WriteTarget::Replace) };
    let file_type = meta.file_type();
    if file_type.is_file() {
        return Ok(WriteTarget::Replace);
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_char_device() {
            return Ok(WriteTarget::Device);
        }
    }
    Err(IoError::NotWritable { path: path.to_owned(), what: crate::file::describe_type(&file_type) })
}

/// Rule 1: the regular file that `uri`, found inside the file `source`, names: relative to
/// `source`'s folder, percent-decoded, symlinks resolved, and inside that folder.
/// `what` names the element for messages (e.g. "buffer 2").
pub fn resolve_inside(source: &Path, what: &str, uri: &str) -> Result<PathBuf, IoError> {
    let refuse = |reason: String| IoError::Confined {
        path: source.to_owned(),
        element: what.to_owned(),
        uri: uri.to_owned(),
        reason,
    };
    let decoded = percent_decode(uri).ok_or_else(|| refuse("is not valid percent-encoded UTF-8".into()))?;
    if decoded.is_empty() || decoded.contains('\0') {
        return Err(refuse("is empty or holds a NUL byte".into()));
    }
    if has_scheme(&decoded) {
        return Err(refuse("is a URL; only files beside the file that names them are read".into()));
    }
    let relative = Path::new(&decoded);
    if relative.is_absolute() || decoded.starts_with('\\') || decoded.contains(":\\") {
        return Err(refuse(
            "is an absolute path; only files beside the file that names them are read".into(),
        ));
    }
    if relative.components().any(|c| matches!(c, Component::RootDir | Component::Prefix(_))) {
        return Err(refuse("is an absolute path".into()));
    }
    let folder = source.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let folder = folder.canonicalize().map_err(|e| IoError::io(folder, e))?;
    let joined = folder.join(relative);
    let resolved = joined.canonicalize().map_err(|e| refuse(format!("cannot be opened: {e}")))?;
    if !resolved.starts_with(&folder) {
        return Err(refuse(format!(
            "resolves to {}, outside {}; only files inside the folder of the file that names them are read",
            resolved.display(),
            folder.display()
        )));
    }
    let meta = std::fs::metadata(&resolved).map_err(|e| IoError::io(&resolved, e))?;
    if !meta.file_type().is_file() {
        return Err(refuse(format!(
            "is {}, not a regular file",
            crate::file::describe_type(&meta.file_type())
        )));
    }
    Ok(resolved)
}

/// Rule 1, read: the bytes of [`resolve_inside`]'s file, at most `limit` bytes (a larger
/// file is refused before it is read).
pub fn read_inside(source: &Path, what: &str, uri: &str, limit: u64) -> Result<Vec<u8>, IoError> {
    let path = resolve_inside(source, what, uri)?;
    let size = std::fs::metadata(&path).map_err(|e| IoError::io(&path, e))?.len();
    if size > limit {
        return Err(IoError::Confined {
            path: source.to_owned(),
            element: what.to_owned(),
            uri: uri.to_owned(),
            reason: format!("is {size} bytes, more than the {limit} desal reads"),
        });
    }
    crate::file::read_regular_file(&path)
}

/// RFC 3986 percent-decoding into UTF-8; `None` for a bad escape or invalid UTF-8.
pub fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3)?;
            let hex = std::str::from_utf8(hex).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Whether `text` starts with a URI scheme (`http:`, `file:`, `data:`): letters, digits,
/// `+`, `-` or `.` after a first letter, then `:`. A one-letter scheme is a Windows drive.
fn has_scheme(text: &str) -> bool {
    let Some((scheme, _)) = text.split_once(':') else { return false };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
}

/// The longest stem [`file_stem_for`] writes: with an extension it stays under the 255
/// bytes of a file name on common file systems.
pub const MAX_STEM_BYTES: usize = 200;

/// Rule 2: the file stem for a name read from a file. Ordinary names — ASCII letters,
/// digits and `-_.@+=,` not starting with `.` — are returned unchanged; every other byte
/// (and `%` itself, and a leading `.`) is written `%XX`, so distinct names give distinct
/// stems. A stem over [`MAX_STEM_BYTES`] is cut and ends in `~` and a hash of the whole
/// name (`~` is never written otherwise). The empty name is `%`.
pub fn file_stem_for(name: &str) -> String {
    if name.is_empty() {
        return "%".into();
    }
    let mut out = String::with_capacity(name.len());
    for (i, &b) in name.as_bytes().iter().enumerate() {
        let plain = b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'@' | b'+' | b'=' | b',');
        if plain || (b == b'.' && i > 0) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    if out.len() > MAX_STEM_BYTES {
        let hash = blake3::hash(name.as_bytes()).to_hex();
        // Cut on a whole escape: the kept prefix is all ASCII, so any byte boundary is a
        // char boundary; step back over a partial `%XX`.
        let mut cut = MAX_STEM_BYTES - 17;
        if let Some(p) = out[cut.saturating_sub(2)..cut].rfind('%') {
            cut = cut - 2 + p;
        }
        out.truncate(cut);
        out.push('~');
        out.push_str(&hash[..16]);
    }
    out
}

/// Rule 2 for a set of names that share a folder: [`file_stem_for`] each, then names whose
/// stems differ only in ASCII case get `~2`, `~3`, … (in order) after all but the first,
/// so no two land on one file on a case-insensitive file system either.
pub fn file_stems_for<S: AsRef<str>>(names: &[S]) -> Vec<String> {
    let mut seen = std::collections::HashMap::<String, usize>::new();
    names
        .iter()
        .map(|name| {
            let stem = file_stem_for(name.as_ref());
            let count = seen.entry(stem.to_ascii_lowercase()).or_insert(0);
            *count += 1;
            if *count == 1 { stem } else { format!("{stem}~{count}") }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinary_names_are_kept() {
        for name in ["f000_poses@0.0000", "f012_Wave@1.2500", "mesh_000", "a-b+c=d,e", "x.y"] {
            assert_eq!(file_stem_for(name), name);
        }
    }

    #[test]
    fn separators_dots_and_escapes_are_encoded_one_to_one() {
        assert_eq!(file_stem_for("a/b"), "a%2Fb");
        assert_eq!(file_stem_for("a_b"), "a_b");
        assert_eq!(file_stem_for(".."), "%2E.");
        assert_eq!(file_stem_for("/../../tmp/x/PWNED"), "%2F..%2F..%2Ftmp%2Fx%2FPWNED");
        assert_eq!(file_stem_for("%2F"), "%252F");
        assert_eq!(file_stem_for("a\\b"), "a%5Cb");
        assert_eq!(file_stem_for("é"), "%C3%A9");
        assert_eq!(file_stem_for(""), "%");
        for stem in [file_stem_for(".."), file_stem_for("a/b"), file_stem_for("x\ny")] {
            assert!(!stem.contains('/') && !stem.starts_with('.') && !stem.contains('\n'), "{stem}");
        }
    }

    #[test]
    fn long_names_are_cut_with_a_hash() {
        let a = "é".repeat(300);
        let b = format!("{}x", "é".repeat(300));
        let (sa, sb) = (file_stem_for(&a), file_stem_for(&b));
        assert!(sa.len() <= MAX_STEM_BYTES && sb.len() <= MAX_STEM_BYTES, "{} {}", sa.len(), sb.len());
        assert_ne!(sa, sb);
        assert!(sa.contains('~'));
    }

    #[test]
    fn names_differing_in_case_get_distinct_stems() {
        let stems = file_stems_for(&["Run", "run", "RUN", "walk"]);
        assert_eq!(stems, ["Run", "run~2", "RUN~3", "walk"]);
    }

    #[test]
    fn uris_resolve_inside_their_folder_only() {
        let dir = tempfile::tempdir().unwrap();
        let inner = dir.path().join("in");
        std::fs::create_dir(&inner).unwrap();
        std::fs::write(inner.join("a b.bin"), b"x").unwrap();
        std::fs::write(dir.path().join("outside.bin"), b"y").unwrap();
        let source = inner.join("rig.gltf");
        assert!(resolve_inside(&source, "buffer 0", "a%20b.bin").is_ok());
        assert!(read_inside(&source, "buffer 0", "a%20b.bin", 1).is_ok());
        assert!(read_inside(&source, "buffer 0", "a%20b.bin", 0).is_err());
        for bad in [
            "../outside.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "http://x/y",
            "%2e%2e/outside.bin",
            "a%zz",
            "",
        ] {
            let err = resolve_inside(&source, "buffer 0", bad).unwrap_err();
            assert!(err.to_string().contains("buffer 0"), "{bad}: {err}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(dir.path().join("outside.bin"), inner.join("link.bin")).unwrap();
            assert!(resolve_inside(&source, "buffer 0", "link.bin").is_err());
            std::os::unix::fs::symlink("/dev/zero", inner.join("zero.bin")).unwrap();
            assert!(resolve_inside(&source, "buffer 0", "zero.bin").is_err());
        }
        std::fs::create_dir(inner.join("sub")).unwrap();
        assert!(resolve_inside(&source, "buffer 0", "sub").is_err());
    }

    #[test]
    fn devices_are_written_through_and_folders_refused() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(write_target(&dir.path().join("new")).unwrap(), WriteTarget::Replace);
        assert!(write_target(dir.path()).is_err());
        #[cfg(unix)]
        assert_eq!(write_target(Path::new("/dev/null")).unwrap(), WriteTarget::Device);
    }
}
