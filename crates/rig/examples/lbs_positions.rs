//! desal's own linear blend skinning of rigs at one time of their first animation, for
//! the viewer check (`tests/gltf/view.mjs`), which compares it with three.js's skinning.
//!
//! `lbs_positions TIME RIG.glb...` prints one JSON object to stdout:
//! `{"time": TIME, "rigs": [{"file": ..., "vertices": n, "positions": [x0, y0, z0, x1, ...]}]}`,
//! every vertex of each rig's skinned mesh in the file's order (split, not welded), posed
//! at `TIME` seconds of the rig's first animation with its own weights and inverse bind
//! matrices: `p' = Σ_j w_j · G_j · B_j · p` (`desal_rig::pose`).

use std::path::Path;
use std::process::ExitCode;

use desal_mesh::Vec3;
use desal_rig::pose::animated_locals;
use desal_rig::{ReadOptions, joint_matrices, skin_points};

fn posed(file: &str, time: f64) -> Result<serde_json::Value, String> {
    let rig = desal_rig::read_rig(Path::new(file), &ReadOptions::default()).map_err(|e| e.to_string())?;
    let animation = rig.animations.first().ok_or_else(|| format!("{file}: the rig has no animation"))?;
    let joints = joint_matrices(&rig, &animated_locals(&rig, animation, time));
    let rest: Vec<Vec3> =
        rig.mesh.positions.iter().map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into())).collect();
    let positions: Vec<f64> =
        skin_points(&rest, &rig.mesh.influences, &joints).iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    Ok(serde_json::json!({"file": file, "vertices": rest.len(), "positions": positions}))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(time) = args.first().and_then(|t| t.parse::<f64>().ok()).filter(|t| t.is_finite()) else {
        eprintln!("usage: lbs_positions TIME RIG.glb...");
        return ExitCode::from(2);
    };
    if args.len() < 2 {
        eprintln!("usage: lbs_positions TIME RIG.glb...");
        return ExitCode::from(2);
    }
    match args[1..].iter().map(|f| posed(f, time)).collect::<Result<Vec<_>, _>>() {
        Ok(rigs) => {
            println!("{}", serde_json::json!({"time": time, "rigs": rigs}));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
