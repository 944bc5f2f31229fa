//! Whole-folder replacement: the one primitive behind every output folder desal writes
//! (a dataset's folder, `eval/`, a single-stage command's `--out-dir`).
//!
//! [`replace_dir`] builds the new folder beside the old one (`.NAME.tmp-PID-N` in the
//! same parent, so the final step is a rename on one file system), carries the
//! subfolders the caller keeps (hard links, so nothing is rewritten), then swaps the two
//! folders in one `renameat2(RENAME_EXCHANGE)` and deletes the old one. At every instant
//! either the old or the new complete folder is at its path, and a kept subfolder is in
//! both until the swap. Where the exchange is not available (not Linux, or a file system
//! without it) the swap is two renames, with a moment between them in which the path is
//! empty.
//!
//! A run killed midway leaves `.NAME.tmp-PID-N` (or, after the swap, `.NAME.old-…`)
//! beside the folder. [`replace_dir`] removes the leftovers of processes that are no
//! longer alive before it starts, and says so on stderr; a live run's are never touched.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use crate::error::IoError;

/// Replaces the folder `target` by one that `fill` writes. `fill` receives an empty
/// folder; when it fails, the folder is removed and `target` is left as it was. The
/// subfolders named in `keep` are carried from the old folder into the new one (when
/// `fill` did not write them itself).
pub fn replace_dir<E: From<IoError>>(
    target: &Path,
    keep: &[&str],
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let (parent, name) = split(target)?;
    fs::create_dir_all(&parent).map_err(|e| IoError::io(&parent, e))?;
    remove_leftovers(&parent);
    let (tmp, n) = temp_dir_beside(&parent, &name);
    let _ = fs::remove_dir_all(&tmp);
    fs::create_dir(&tmp).map_err(|e| IoError::io(&tmp, e))?;
    let filled = fill(&tmp).and_then(|()| {
        for sub in keep {
            let old = target.join(sub);
            let new = tmp.join(sub);
            if old.is_dir() && !new.exists() {
                link_tree(&old, &new)?;
            }
        }
        Ok(())
    });
    if let Err(e) = filled {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    swap_into_place(&tmp, target, &parent, &name, n)?;
    Ok(())
}

/// A temporary folder's name in `parent` for the folder `name`, unique per process and
/// call (with its number): hidden, and ending the way `remove_leftovers` knows.
fn temp_dir_beside(parent: &Path, name: &str) -> (PathBuf, u64) {
    let n = crate::atomic::next_temp_number();
    (parent.join(format!(".{name}.tmp-{}-{n}", std::process::id())), n)
}

/// Creates the folder `target` with what `fill` writes, unless it exists: the first
/// complete writer wins (a cache entry stored by two shards at once). The folder is
/// built beside `target` and renamed into place, so `target` never exists half-written.
/// Returns whether this call created it.
pub fn create_dir_once<E: From<IoError>>(
    target: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<bool, E> {
    let (parent, name) = split(target)?;
    fs::create_dir_all(&parent).map_err(|e| IoError::io(&parent, e))?;
    if target.exists() {
        return Ok(false);
    }
    remove_leftovers(&parent);
    let (tmp, _) = temp_dir_beside(&parent, &name);
    let _ = fs::remove_dir_all(&tmp);
    fs::create_dir(&tmp).map_err(|e| IoError::io(&tmp, e))?;
    if let Err(e) = fill(&tmp) {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    // rename(2) onto an existing non-empty folder fails: then another writer won.
    match fs::rename(&tmp, target) {
        Ok(()) => Ok(true),
        Err(_) if target.exists() => {
            let _ = fs::remove_dir_all(&tmp);
            Ok(false)
        }
        Err(e) => {
            let _ = fs::remove_dir_all(&tmp);
            Err(IoError::io(target, e).into())
        }
    }
}

/// Moves the complete folder `tmp` to `target`, replacing what is there.
fn swap_into_place(tmp: &Path, target: &Path, parent: &Path, name: &str, n: u64) -> Result<(), IoError> {
    if fs::symlink_metadata(target).is_err() {
        return fs::rename(tmp, target).map_err(|e| IoError::io(target, e));
    }
    if exchange(tmp, target).is_ok() {
        // `tmp` now holds the previous folder.
        remove_old(tmp);
        return Ok(());
    }
    let old = parent.join(format!(".{name}.old-{}-{n}", std::process::id()));
    fs::rename(target, &old).map_err(|e| IoError::io(target, e))?;
    if let Err(e) = fs::rename(tmp, target) {
        // Put the previous folder back rather than leave nothing.
        let _ = fs::rename(&old, target);
        return Err(IoError::io(target, e));
    }
    remove_old(&old);
    Ok(())
}

/// Deletes the previous folder once the new one is in place. Failing that is not an
/// error of the run (its outputs are complete) but is said, with the path.
fn remove_old(old: &Path) {
    if let Err(e) = fs::remove_dir_all(old) {
        eprintln!("warning: the previous folder, now at {}, could not be removed: {e}", old.display());
    }
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> io::Result<()> {
    Err(io::Error::from(io::ErrorKind::Unsupported))
}

/// Copies the tree `from` to `to` as hard links (files are never rewritten in place by
/// desal: every write is a rename), falling back to copies across file systems.
fn link_tree(from: &Path, to: &Path) -> Result<(), IoError> {
    fs::create_dir_all(to).map_err(|e| IoError::io(to, e))?;
    for entry in fs::read_dir(from).map_err(|e| IoError::io(from, e))? {
        let entry = entry.map_err(|e| IoError::io(from, e))?;
        let source = entry.path();
        let dest = to.join(entry.file_name());
        let kind = entry.file_type().map_err(|e| IoError::io(&source, e))?;
        if kind.is_dir() {
            link_tree(&source, &dest)?;
        } else if fs::hard_link(&source, &dest).is_err() {
            fs::copy(&source, &dest).map_err(|e| IoError::io(&source, e))?;
        }
    }
    Ok(())
}

/// Removes, in `dir`, what interrupted desal runs left behind — temp and old folders
/// (`.NAME.tmp-PID-N`, `.NAME.old-PID-N`) and atomic-write temp files
/// (`.NAME.PID.N.tmp`, `.NAME.partial-PID`) — when the process that made them is gone,
/// with a line on stderr for each. A live run's are never touched, nor is anything
/// else.
pub fn remove_leftovers(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = leftover_pid(&file_name) else { continue };
        if pid == std::process::id() || process_alive(pid) {
            continue;
        }
        let path = entry.path();
        let removed = if path.is_dir() { fs::remove_dir_all(&path) } else { fs::remove_file(&path) };
        if removed.is_ok() {
            eprintln!("removed {} (left by an interrupted run, process {pid})", path.display());
        }
    }
}

/// The process id in a leftover's name, for the four patterns of [`remove_leftovers`].
fn leftover_pid(file_name: &str) -> Option<u32> {
    let rest = file_name.strip_prefix('.')?;
    let number =
        |s: &str| s.parse::<u64>().ok().filter(|_| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    // `.NAME.tmp-PID-N` / `.NAME.old-PID-N`
    for marker in [".tmp-", ".old-"] {
        if let Some(at) = rest.rfind(marker) {
            let (pid, n) = rest[at + marker.len()..].split_once('-')?;
            number(n)?;
            return number(pid).and_then(|p| u32::try_from(p).ok());
        }
    }
    // `.NAME.partial-PID`
    if let Some(at) = rest.rfind(".partial-") {
        return number(&rest[at + ".partial-".len()..]).and_then(|p| u32::try_from(p).ok());
    }
    // `.NAME.PID.N.tmp`
    let stem = rest.strip_suffix(".tmp")?;
    let (head, n) = stem.rsplit_once('.')?;
    number(n)?;
    let (_, pid) = head.rsplit_once('.')?;
    number(pid).and_then(|p| u32::try_from(p).ok())
}

/// Whether process `pid` is alive. Without `/proc` (not Linux) every process counts as
/// alive, so nothing is removed that might be in use.
fn process_alive(pid: u32) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    Path::new("/proc").join(pid.to_string()).exists()
}

fn split(target: &Path) -> Result<(PathBuf, String), IoError> {
    let invalid = || IoError::io(target, io::Error::new(io::ErrorKind::InvalidInput, "not a folder path"));
    let name = target.file_name().ok_or_else(invalid)?.to_string_lossy().into_owned();
    let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Ok((parent.to_owned(), name))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(path: &Path) -> String {
        fs::read_to_string(path).unwrap()
    }

    /// A new folder replaces the old one whole; the kept subfolder comes along, the rest
    /// of the old folder does not, and nothing is left beside it.
    #[test]
    fn replaces_whole_and_carries_kept_subfolders() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("out");
        fs::create_dir_all(target.join("eval/deep")).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        fs::write(target.join("eval/deep/e.txt"), "eval").unwrap();
        replace_dir::<IoError>(&target, &["eval"], |dir| {
            fs::write(dir.join("new.txt"), "new").map_err(|e| IoError::io(dir, e))
        })
        .unwrap();
        assert_eq!(read(&target.join("new.txt")), "new");
        assert!(!target.join("old.txt").exists());
        assert_eq!(read(&target.join("eval/deep/e.txt")), "eval");
        let names: Vec<_> = fs::read_dir(root.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["out"], "no temp or old folder is left");
    }

    /// A failing fill leaves the old folder exactly as it was, and no temp folder.
    #[test]
    fn a_failed_fill_changes_nothing() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("out");
        fs::create_dir_all(&target).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        let err = replace_dir::<IoError>(&target, &[], |dir| {
            fs::write(dir.join("half.txt"), "half").unwrap();
            Err(IoError::io(dir, io::Error::other("disk full")))
        });
        assert!(err.is_err());
        assert_eq!(read(&target.join("old.txt")), "old");
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
    }

    /// Leftovers of a dead process are removed, whichever folder they belong to; a live
    /// process's (pid 1 stands for a live one) are kept, as are unrelated names.
    #[test]
    fn leftovers_of_dead_runs_are_removed_and_live_ones_kept() {
        let root = tempfile::tempdir().unwrap();
        let dead = root.path().join(format!(".out.tmp-{}-0", u32::MAX - 1));
        let dead_old = root.path().join(format!(".out.old-{}-3", u32::MAX - 2));
        let live = root.path().join(".out.tmp-1-0");
        let other = root.path().join(format!(".other.tmp-{}-0", u32::MAX - 1));
        let unrelated = root.path().join(".out.tmp-notapid");
        for d in [&dead, &dead_old, &live, &other, &unrelated] {
            fs::create_dir_all(d).unwrap();
        }
        let dead_file = root.path().join(format!(".report.json.{}.0.tmp", u32::MAX - 1));
        fs::write(&dead_file, "x").unwrap();
        replace_dir::<IoError>(&root.path().join("out"), &[], |_| Ok(())).unwrap();
        assert!(!dead.exists() && !dead_old.exists() && !other.exists() && !dead_file.exists());
        assert!(live.exists() && unrelated.exists());
        assert!(root.path().join("out").is_dir());
    }

    /// The first complete writer wins; a second one's folder is discarded, not merged.
    #[test]
    fn create_once_keeps_the_first_writer() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("entry");
        let write = |text: &'static str| {
            move |dir: &Path| fs::write(dir.join("a.txt"), text).map_err(|e| IoError::io(dir, e))
        };
        assert!(create_dir_once::<IoError>(&target, write("first")).unwrap());
        assert!(!create_dir_once::<IoError>(&target, write("second")).unwrap());
        assert_eq!(read(&target.join("a.txt")), "first");
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 1);
    }

    #[test]
    fn leftover_names_parse() {
        assert_eq!(leftover_pid(".out.tmp-42-7"), Some(42));
        assert_eq!(leftover_pid(".out.old-42-0"), Some(42));
        assert_eq!(leftover_pid(".fit.json.42.3.tmp"), Some(42));
        assert_eq!(leftover_pid(".saliency.png.partial-42"), Some(42));
        assert_eq!(leftover_pid(".out.tmp-42"), None);
        assert_eq!(leftover_pid("out.tmp-42-0"), None, "not hidden: not ours");
        assert_eq!(leftover_pid(".cache"), None);
    }
}
