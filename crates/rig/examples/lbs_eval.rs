//! Held-out LBS error of simplified rigs against the full-resolution rig (issue 15's
//! measure), for `docs/rig/eval.sh`.
//!
//! `lbs_eval INPUT.glb STEP OFFSET COUNT NAME=SIMPLIFIED.glb...`: the frames are the
//! input's animation at times `OFFSET + k·STEP` (k < COUNT). At each, the full rig and
//! every simplified rig are posed by linear blend skinning with their *own* weights and
//! inverse bind matrices but the *input's* joint world matrices (joints matched by node
//! name), both welded by position and weights; then v2f (symmetric mean squared
//! point-to-surface distance, the primary measure) and v2v (mean squared distance of
//! the simplified vertices to the nearest full vertex) in the input's units squared.
//! The last NAME is the reference for the paired per-frame comparison (two-sided sign
//! test on v2f). `lbs_eval INPUT.glb --count SIMPLIFIED.glb` prints a rig's welded
//! vertex count.

use std::collections::HashMap;
use std::path::Path;

use desal_mesh::math::Mat4;
use desal_mesh::{TriMesh, Vec3};
use desal_rig::pose::{animated_locals, world_matrices};
use desal_rig::{ReadOptions, Rig, Weld, skin_points};

fn read(path: &str) -> Rig {
    desal_rig::read_rig(Path::new(path), &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The welded mesh of `rig` posed with joint world matrices by node name.
fn posed(rig: &Rig, weld: &Weld, world_by_name: &HashMap<String, Mat4>) -> TriMesh {
    let joints: Vec<Mat4> = (0..rig.skin.joints.len())
        .map(|j| {
            let name = rig.joint_name(j);
            let world =
                world_by_name.get(&name).unwrap_or_else(|| panic!("joint '{name}' is not in the input rig"));
            world * rig.skin.inverse_bind_matrix(j)
        })
        .collect();
    let reps = weld.representatives();
    let rest: Vec<Vec3> = reps
        .iter()
        .map(|&s| {
            let p = rig.mesh.positions[s as usize];
            Vec3::new(p[0].into(), p[1].into(), p[2].into())
        })
        .collect();
    let mut influences = desal_rig::Influences::new();
    for &s in &reps {
        influences.push_row(rig.mesh.influences.of(s as usize).map(|(j, w)| (j as u16, w)));
    }
    TriMesh { positions: skin_points(&rest, &influences, &joints), faces: weld.faces.clone() }
}

/// Two-sided sign test p-value for `wins` out of `n`.
fn sign_test(wins: usize, n: usize) -> f64 {
    let k = wins.min(n - wins);
    let mut tail = 0.0;
    let mut c = 1.0f64; // C(n, i)
    for i in 0..=k {
        if i > 0 {
            c = c * (n - i + 1) as f64 / i as f64;
        }
        tail += c;
    }
    (2.0 * tail / 2f64.powi(n as i32)).min(1.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() == 3 && args[1] == "--count" {
        println!("{}", Weld::new(&read(&args[2]).mesh).welded_count());
        return;
    }
    assert!(args.len() >= 5, "usage: lbs_eval INPUT.glb STEP OFFSET COUNT NAME=FILE.glb...");
    let input = read(&args[0]);
    let (step, offset, count): (f64, f64, usize) =
        (args[1].parse().unwrap(), args[2].parse().unwrap(), args[3].parse().unwrap());
    let methods: Vec<(String, Rig)> = args[4..]
        .iter()
        .map(|a| {
            let (name, file) = a.split_once('=').expect("NAME=FILE");
            (name.to_owned(), read(file))
        })
        .collect();
    let input_weld = Weld::new(&input.mesh);
    let welds: Vec<Weld> = methods.iter().map(|(_, r)| Weld::new(&r.mesh)).collect();
    let animation = &input.animations[0];
    // errors[method][frame] = (v2f, v2v)
    let mut errors = vec![Vec::new(); methods.len()];
    for k in 0..count {
        let t = offset + step * k as f64;
        let world = world_matrices(&input, &animated_locals(&input, animation, t));
        let by_name: HashMap<String, Mat4> = input
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(n, node)| Some((node.name.clone()?, world[n])))
            .collect();
        let full = posed(&input, &input_weld, &by_name);
        for (m, ((_, rig), weld)) in methods.iter().zip(&welds).enumerate() {
            let mesh = posed(rig, weld, &by_name);
            errors[m].push((
                desal_measures::metrics::v2f(&mesh, &full),
                desal_measures::metrics::v2v(&mesh, &full),
            ));
        }
    }
    let reference = methods.len() - 1;
    println!(
        "held-out frames: {count} (t = {offset} + k·{step} s of '{}'); full rig {} welded vertices",
        animation.name.clone().unwrap_or_default(),
        input_weld.welded_count()
    );
    println!();
    println!(
        "| method | welded vertices | written vertices | faces | v2f mean (m²) | v2f / {} | v2v mean (m²) | frames better than {} (v2f) | sign-test p |",
        methods[reference].0, methods[reference].0
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mean = |m: usize, f: fn(&(f64, f64)) -> f64| errors[m].iter().map(f).sum::<f64>() / count as f64;
    let ref_v2f = mean(reference, |e| e.0);
    for (m, (name, rig)) in methods.iter().enumerate() {
        let v2f = mean(m, |e| e.0);
        let wins = errors[m].iter().zip(&errors[reference]).filter(|(a, b)| a.0 < b.0).count();
        let (wins_text, p) = if m == reference {
            ("—".to_owned(), "—".to_owned())
        } else {
            (format!("{wins}/{count}"), format!("{:.2e}", sign_test(wins, count)))
        };
        println!(
            "| {name} | {} | {} | {} | {v2f:.3e} | {:.3} | {:.3e} | {wins_text} | {p} |",
            welds[m].welded_count(),
            rig.mesh.vertex_count(),
            rig.mesh.triangles.len(),
            v2f / ref_v2f,
            mean(m, |e| e.1),
        );
    }
}
