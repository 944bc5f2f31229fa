//! Issue 39: hostile files and mistyped flags. No name read from a file, and no flag, makes
//! desal write, rename or delete outside its own folders (the output folder, the cache),
//! and what may be replaced is a regular file: a character device is written through, a
//! folder or FIFO refused. The rows are the (D5, D6, D7, D17); the rig reader's
//! own rows are tested in `crates/rig`.

use std::path::{Path, PathBuf};

use desal_rig::ReadOptions;

use crate::support::{desal, run_ok, stderr, write_tube_dataset};

/// Every path under `dir`, relative, sorted (symlinks not followed).
fn tree(dir: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries.flatten() {
            let path = entry.path();
            out.push(path.strip_prefix(root).unwrap().to_owned());
            if entry.file_type().unwrap().is_dir() {
                walk(root, &path, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// D5: animation names become pose names, and pose names become file names through one
/// rule: a name holding `/../..` writes nothing outside `out/`, a `/` makes no folder,
/// and `a/b` and `a_b` land on two files.
#[test]
fn d5_animation_names_never_leave_the_output_folder() {
    let dir = tempfile::tempdir().unwrap();
    let escape = dir.path().join("escaped");
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data-samples/rig.glb");
    let mut rig = desal_rig::read_rig(&sample, &ReadOptions::default()).unwrap();
    let depth = "/..".repeat(12);
    let hostile = format!("{depth}{}/PWNED", escape.display());
    let first = rig.animations[0].clone();
    for (k, name) in [hostile.as_str(), "a/b", "a_b"].into_iter().enumerate() {
        let animation = desal_rig::model::Animation { name: Some(name.to_owned()), ..first.clone() };
        if k == 0 {
            rig.animations[0] = animation;
        } else {
            rig.animations.push(animation);
        }
    }
    std::fs::write(dir.path().join("avatar.glb"), desal_rig::write_glb(&rig).unwrap()).unwrap();
    let pipeline = dir.path().join("rig.toml");
    std::fs::write(
        &pipeline,
        "schema = 1\nout = \"out\"\n[[dataset]]\nname = \"avatar\"\n[dataset.rig]\nfile = \"avatar.glb\"\nposes = \"animations\"\nframes = 6\n[dataset.simplify]\nratio = 0.3\n",
    )
    .unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!escape.exists(), "a pose name wrote outside the output folder");
    let top: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(top.len(), 3, "only the rig, the pipeline and out/: {top:?}");
    let simplified = dir.path().join("out/avatar/simplified");
    let files = tree(&simplified);
    assert!(files.iter().all(|f| simplified.join(f).is_file()), "no folder is made: {files:?}");
    let plys: Vec<String> =
        files.iter().map(|f| f.to_string_lossy().into_owned()).filter(|f| f.ends_with(".ply")).collect();
    assert!(plys.iter().any(|f| f.contains("a%2Fb")) && plys.iter().any(|f| f.contains("_a_b@")), "{plys:?}");
    assert!(plys.iter().any(|f| f.contains("%2F..%2F..")), "{plys:?}");
}

/// D6: `desal cache gc` with `--cache-dir` naming a folder of user files refuses it,
/// before running anything, and deletes nothing.
#[test]
fn d6_cache_gc_refuses_a_folder_of_user_files() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let user = dir.path().join("documents");
    for file in ["letters/2026/a.txt", "photos/trip/b.jpg", "notes.txt"] {
        std::fs::create_dir_all(user.join(file).parent().unwrap()).unwrap();
        std::fs::write(user.join(file), file).unwrap();
    }
    let before = tree(&user);
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap(), "--cache-dir", user.to_str().unwrap()]);
    assert!(!out.status.success(), "gc accepted a folder of user files");
    assert!(stderr(&out).contains("is not a desal cache"), "{}", stderr(&out));
    assert_eq!(tree(&user), before, "nothing written or deleted");
}

/// D6: a symlink in the cache root, or in a stage folder, is never followed: the folders
/// it points to keep their subfolders. A real cache is still tidied.
#[test]
fn d6_cache_gc_never_follows_symlinks() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let cache = dir.path().join("out/.cache");
    assert!(cache.join("CACHEDIR.TAG").is_file(), "a run marks its cache");
    let victim = dir.path().join("victim");
    std::fs::create_dir_all(victim.join("sub/subsub")).unwrap();
    std::fs::write(victim.join("sub/subsub/keep.txt"), "mine").unwrap();
    std::os::unix::fs::symlink(&victim, cache.join("linked-stage")).unwrap();
    std::os::unix::fs::symlink(victim.join("sub"), cache.join("simplify").join("linked-entry")).unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, format!("{text}[dataset.simplify]\nratio = 0.5\n")).unwrap();
    run_ok(&pipeline, &[]);
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("removed 2"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(victim.join("sub/subsub/keep.txt").is_file(), "a symlink was followed");
}

/// D6: a cache made before the marker existed is recognised by its layout, tidied, and
/// marked.
#[test]
fn d6_a_cache_without_the_marker_is_recognised_by_its_layout() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let marker = dir.path().join("out/.cache/CACHEDIR.TAG");
    std::fs::remove_file(&marker).unwrap();
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(marker.is_file());
    // A stray user file in an unmarked root makes it not a cache.
    std::fs::remove_file(&marker).unwrap();
    std::fs::write(dir.path().join("out/.cache/fit/stray.txt"), "x").unwrap();
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("stray.txt"), "{}", stderr(&out));
}

/// D7: an output path that is a character device is written through, as `cp` does, and
/// stays the device; a folder or a FIFO is refused, naming it, without blocking.
#[test]
fn d7_a_device_is_written_through_and_a_fifo_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let p = |name: &str| dir.path().join("out/tube").join(name).to_string_lossy().into_owned();
    let fit = |output: &str| {
        desal(&["fit", "--poses", &p("poses.dsa"), "--labels", &p("labels.dsa"), "-o", output])
    };
    let out = fit("/dev/null");
    assert!(out.status.success(), "{}", stderr(&out));
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device(), "/dev/null was replaced");
    let out = fit(dir.path().to_str().unwrap());
    assert!(!out.status.success() && stderr(&out).contains("a directory"), "{}", stderr(&out));
    let fifo = dir.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let out = fit(fifo.to_str().unwrap());
    assert!(!out.status.success() && stderr(&out).contains("FIFO"), "{}", stderr(&out));
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO was replaced");
}

/// D17: a FIFO as a pose file or a pipeline file is refused by name, without hanging.
#[test]
fn d17_a_fifo_as_pose_file_or_pipeline_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let fifo = dir.path().join("poses/p9.ply");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success() && stderr(&out).contains("p9.ply"), "{}", stderr(&out));
    let fifo = dir.path().join("pipe.toml");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let out = desal(&["run", fifo.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success() && stderr(&out).contains("FIFO"), "{}", stderr(&out));
}

/// D8: `rig.frames` past desal's cap is refused when the pipeline is read, before the
/// rig is posed (a billion frames used to abort at 48 GB), and nothing is written.
#[test]
fn d8_a_billion_frames_are_refused_before_posing() {
    let dir = tempfile::tempdir().unwrap();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("data-samples/rig.glb");
    std::fs::copy(sample, dir.path().join("avatar.glb")).unwrap();
    let pipeline = dir.path().join("rig.toml");
    std::fs::write(
        &pipeline,
        "schema = 1\nout = \"out\"\n[[dataset]]\nname = \"avatar\"\n[dataset.rig]\nfile = \"avatar.glb\"\nframes = 1000000000\n",
    )
    .unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("MAX_FRAMES"), "{}", stderr(&out));
    assert!(!dir.path().join("out/avatar").exists());
}

/// D6: a `CACHEDIR.TAG` another tool wrote (cargo, borg, …) does not make a folder a desal
/// cache: gc refuses it and writes nothing there.
#[test]
fn d6_another_tools_cachedir_tag_is_not_a_desal_cache() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let other = dir.path().join("other");
    std::fs::create_dir_all(other.join("photos")).unwrap();
    std::fs::write(other.join("photos/a.jpg"), "precious").unwrap();
    std::fs::write(
        other.join("CACHEDIR.TAG"),
        "Signature: 8a477f597d28d172789f06886806bc55\n# by another tool\n",
    )
    .unwrap();
    let before = tree(&other);
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap(), "--cache-dir", other.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("another tool"), "{}", stderr(&out));
    assert_eq!(tree(&other), before);
}

/// Results on standard output: a full device is a clean error naming standard output,
/// a closed pipe ends quietly; neither is a panic (exit 101).
#[test]
fn standard_output_that_cannot_be_written_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let poses = dir.path().join("out/tube/poses.dsa");
    let inspect = || {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_desal"));
        command.args(["inspect", poses.to_str().unwrap()]);
        command
    };
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let out = inspect().stdout(full).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("standard output"), "{}", stderr(&out));
    let mut child =
        inspect().stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_ne!(out.status.code(), Some(101), "{}", stderr(&out));
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
}
