//! Writes the CC0 body model in SMPL's layout (`desal_sample::smpl_layout`) as
//! `model.npz` and `model.pkl` into a folder, from this repository's
//! `data-samples/source` (or `--source DIR`).
//!
//! Usage: `cargo run --release -p desal-sample --example make_smpl_fixture -- OUT_DIR [--source DIR]`.
//! desal-bodymodel's `tests/against_body_models.py` runs it; the files are not committed
//! (about 40 MB each, mostly `posedirs`).

use std::path::PathBuf;
use std::process::ExitCode;

use desal_sample::SourceAssets;
use desal_sample::smpl_layout::smpl_layout_model;

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let Some(out) = args.next().map(PathBuf::from) else {
        eprintln!("usage: make_smpl_fixture OUT_DIR [--source DIR]");
        return ExitCode::FAILURE;
    };
    let source = match (args.next(), args.next()) {
        (Some(flag), Some(dir)) if flag == "--source" => PathBuf::from(dir),
        _ => desal_sample::source::repository_source_dir(),
    };
    let run = || -> Result<(), String> {
        let assets = SourceAssets::load(&source).map_err(|e| e.to_string())?;
        let model = smpl_layout_model(&assets).map_err(|e| e.to_string())?;
        std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
        desal_io::write_atomic(&out.join("model.npz"), &model.npz()?).map_err(|e| e.to_string())?;
        desal_io::write_atomic(&out.join("model.pkl"), &model.pkl()).map_err(|e| e.to_string())?;
        println!("wrote {} and {}", out.join("model.npz").display(), out.join("model.pkl").display());
        Ok(())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
