//! gltfpack (meshoptimizer's glTF pipeline) as a `desal eval` method for rig datasets:
//! the tool engine and avatar engineers use for skinned LODs. It runs on the dataset's
//! own `.glb` as a user would run it, `gltfpack -i IN -o OUT -si R -noq` (`-noq`: no
//! quantisation, so positions stay the input's f32), and `gltfpack-sa` adds `-sa`
//! (simplify to the target ratio whatever the error). Its skin is kept: the rig model
//! skins its vertices with gltfpack's own weights (at most 4; it drops the rest).
//!
//! gltfpack takes a triangle ratio and stops early at its error limit, so the ratio is
//! bisected (at most [`MAX_RUNS`] runs) for the welded vertex count closest to the
//! target from below; when no ratio gets there, the fewest vertices it reached is kept
//! and the note says so. Stage 4 then maps the welded vertices back as for any other
//! tool's mesh.
//!
//! The command is `$DESAL_GLTFPACK` (split on whitespace, e.g. `node path/to/cli.js`),
//! else `gltfpack` on the `PATH`; npm's `gltfpack` package provides it
//! (`tests/gltf/node_modules/.bin/gltfpack` after `npm ci` there).

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};
use desal_mesh::TriMesh;
use desal_rig::{ReadOptions, Rig, SourceDocument, Weld};

use crate::rig::{OwnSkin, RigModel};

/// Most gltfpack runs of one bisection.
pub const MAX_RUNS: usize = 12;

/// The two ways of running gltfpack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// `-si R`: gltfpack's default error limit applies.
    Plain,
    /// `-si R -sa`: aggressive, disregarding quality.
    Aggressive,
}

impl Variant {
    pub const ALL: [Variant; 2] = [Variant::Plain, Variant::Aggressive];

    pub fn name(self) -> &'static str {
        match self {
            Variant::Plain => "gltfpack",
            Variant::Aggressive => "gltfpack-sa",
        }
    }

    /// The flags besides `-i`, `-o` and `-si`.
    pub fn flags(self) -> &'static [&'static str] {
        match self {
            Variant::Plain => &["-noq"],
            Variant::Aggressive => &["-noq", "-sa"],
        }
    }
}

/// gltfpack's simplified rig, welded, with its skin.
#[derive(Debug)]
pub struct Output {
    /// The welded mesh (bind pose), its vertices in the order of `skin.influences`.
    pub mesh: TriMesh,
    pub skin: OwnSkin,
    pub note: String,
    /// The welded vertex count is at most the target.
    pub reached: bool,
}

/// `$DESAL_GLTFPACK` or `gltfpack`, as a program and its leading arguments.
fn command() -> Vec<String> {
    std::env::var("DESAL_GLTFPACK")
        .ok()
        .map(|c| c.split_whitespace().map(str::to_owned).collect::<Vec<_>>())
        .filter(|c| !c.is_empty())
        .unwrap_or_else(|| vec!["gltfpack".into()])
}

fn run(args: &[&str]) -> Result<std::process::Output> {
    let command = command();
    Command::new(&command[0]).args(&command[1..]).args(args).output().with_context(|| {
        format!(
            "cannot run gltfpack ('{}'): install it (npm install -g gltfpack) or set $DESAL_GLTFPACK",
            command.join(" ")
        )
    })
}

/// gltfpack's version line (`gltfpack 1.3`).
pub fn version() -> Result<String> {
    let out = run(&["-v"])?;
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    Ok(text.lines().next().unwrap_or("gltfpack (unknown version)").trim().to_owned())
}

/// Runs gltfpack on the model's file at `ratio` into `out`, and reads the result with
/// its document (for its morph targets).
fn simplify_at(model: &RigModel, variant: Variant, ratio: f64, out: &Path) -> Result<(Rig, SourceDocument)> {
    let input = model.file.to_str().context("the rig's path is not UTF-8")?;
    let output = out.to_str().context("the temporary path is not UTF-8")?;
    let ratio_text = format!("{ratio:.6}");
    let mut args = vec!["-i", input, "-o", output, "-si", ratio_text.as_str()];
    args.extend(variant.flags());
    let result = run(&args)?;
    if !result.status.success() {
        bail!(
            "gltfpack {} failed ({}): {}",
            args.join(" "),
            result.status,
            String::from_utf8_lossy(&result.stderr).trim()
        );
    }
    let bytes = desal_io::file::read_regular_file(out)?;
    let options = ReadOptions { mesh: model.mesh.clone() };
    desal_rig::read_rig_and_document(out, &bytes, &options)
        .or_else(|_| desal_rig::read_rig_and_document(out, &bytes, &ReadOptions::default()))
        .with_context(|| format!("reading gltfpack's output (-si {ratio_text})"))
}

/// What a bisection of gltfpack's ratio aims at, from below.
#[derive(Debug, Clone, Copy)]
pub enum Aim {
    /// Welded vertices (the eval's `--target-vertices`).
    Vertices(usize),
    /// Welded faces (a LOD level's face count).
    Faces(usize),
}

impl Aim {
    fn target(self) -> usize {
        match self {
            Aim::Vertices(n) | Aim::Faces(n) => n,
        }
    }

    fn count(self, rig: &Rig) -> usize {
        let weld = Weld::new(&rig.mesh);
        match self {
            Aim::Vertices(_) => weld.welded_count(),
            Aim::Faces(_) => weld.faces.len(),
        }
    }
}

/// gltfpack's output at the ratio whose count is closest to the aim from below (else
/// the smallest count it reached).
#[derive(Debug)]
pub struct Bisected {
    pub ratio: f64,
    pub count: usize,
    pub rig: Rig,
    pub document: SourceDocument,
    /// gltfpack runs made.
    pub runs: usize,
    /// gltfpack's version line.
    pub version: String,
}

impl Bisected {
    /// The count is at most the aim.
    pub fn reached(&self, aim: Aim) -> bool {
        self.count <= aim.target()
    }
}

/// Bisects gltfpack's ratio (at most [`MAX_RUNS`] runs) for `aim`.
pub fn bisect(model: &RigModel, variant: Variant, aim: Aim) -> Result<Bisected> {
    let version = version()?;
    let dir = tempfile::tempdir().context("a temporary folder for gltfpack")?;
    let target = aim.target();
    let full = match aim {
        Aim::Vertices(_) => model.posed.poses.vertex_count(),
        Aim::Faces(_) => model.posed.poses.face_count(),
    };
    // (ratio, count, rig) of the best run so far: at most the target and the most, else
    // the fewest.
    let mut best: Option<(f64, usize, (Rig, SourceDocument))> = None;
    let (mut low, mut high) = (0.0f64, 1.0f64);
    let mut ratio = (target as f64 / full as f64).clamp(1e-4, 1.0);
    let mut runs = 0;
    for run in 0..MAX_RUNS {
        runs = run + 1;
        let out = simplify_at(model, variant, ratio, &dir.path().join(format!("run{run}.glb")))?;
        let n = aim.count(&out.0);
        let better = match &best {
            None => true,
            Some((_, b, _)) => (n <= target && (*b > target || n > *b)) || (*b > target && n < *b),
        };
        if n <= target {
            low = ratio;
        } else {
            high = ratio;
        }
        if better {
            best = Some((ratio, n, out));
        }
        if n == target || high - low < 1e-5 {
            break;
        }
        ratio = 0.5 * (low + high);
    }
    let (ratio, count, (rig, document)) = best.expect("at least one run");
    Ok(Bisected { ratio, count, rig, document, runs, version })
}

/// gltfpack's rig at the welded vertex count closest to `target` from below.
pub fn simplify(model: &RigModel, variant: Variant, target: usize) -> Result<Output> {
    let aim = Aim::Vertices(target);
    let out = bisect(model, variant, aim)?;
    let reached = out.reached(aim);
    let (ratio, runs, version) = (out.ratio, out.runs, &out.version);
    let welded = model.welded(&out.rig, &format!("gltfpack's output (-si {ratio:.6})"))?;
    let (positions, faces) = (&welded.mesh.positions, &welded.mesh.faces);
    let max_influences = welded.skin.max_influences;
    let note = format!(
        "{version} `-si {ratio:.6} {}`: {} welded vertices, {} faces, at most {max_influences} influences (target {target}; {runs} runs bisecting its ratio){}",
        variant.flags().join(" "),
        positions.len(),
        faces.len(),
        if reached {
            String::new()
        } else {
            format!(
                "; it stopped early: no ratio took it to {target} vertices (desal's methods reach the target; \
                 --target-vertices {} compares them at gltfpack's count)",
                positions.len()
            )
        }
    );
    Ok(Output { mesh: welded.mesh, skin: welded.skin, note, reached })
}
