//! Times `subset_model` (the joint regressor's solve) at a shape basis as wide as real
//! models': `cargo run --release -p desal-bodymodel --example subset_timing --
//! [COMPONENTS] [STEP]`. Builds the CC0 fixture from `data-samples/source`, replaces its
//! 10 shape directions by `COMPONENTS` (default 300, SMPL 1.1's) smooth synthetic ones
//! (products of sines of the rest position, scaled down with the component's index as
//! PCA bases decay), keeps every `STEP`th vertex (default 9, ~1500 vertices) and prints
//! the time, the support and the residual.

use std::time::Instant;

use desal_bodymodel::{BodyModel, SubsetConfig, subset_model};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let components: usize = args.next().map_or(Ok(300), |s| s.parse())?;
    let step: usize = args.next().map_or(Ok(9), |s| s.parse())?;
    let assets = desal_sample::SourceAssets::load(&desal_sample::source::repository_source_dir())?;
    let npz = desal_sample::smpl_layout::smpl_layout_model(&assets)?.npz()?;
    let mut model = BodyModel::from_npz_bytes(std::path::Path::new("fixture.npz"), &npz)?;
    model.shapedirs = synthetic_directions(&model, components);
    model.shape_count = components;
    let kept: Vec<u32> = (0..model.vertex_count() as u32).step_by(step).collect();
    let start = Instant::now();
    let (_, report) = subset_model(&model, &kept, &[], &SubsetConfig::default())?;
    let support = report.joints.iter().map(|j| j.support);
    println!(
        "{components} shape components, {} of {} vertices: {:.1} s; support {}..{} vertices; residual {:.1e} m; \
         largest |weight| {:.3}",
        kept.len(),
        model.vertex_count(),
        start.elapsed().as_secs_f64(),
        support.clone().min().unwrap_or(0),
        support.max().unwrap_or(0),
        report.max_residual_m,
        report.joints.iter().map(|j| j.max_abs_weight).fold(0.0, f64::max),
    );
    Ok(())
}

/// `(V, 3, components)` row-major: component `k`, coordinate `a` at rest position `p` is
/// `s_k sin(f·p + φ)`, its frequencies and phases from `k` and `a`, `s_k = 0.02 / (1 + k/10)`.
fn synthetic_directions(model: &BodyModel, components: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(model.vertex_count() * 3 * components);
    for p in &model.v_template {
        for a in 0..3 {
            for k in 0..components {
                let (kf, af) = (k as f64, a as f64);
                let f = [
                    1.0 + (kf * 0.37).sin() * 3.0,
                    1.0 + (kf * 0.61 + af).cos() * 3.0,
                    1.0 + (kf * 0.83).sin() * 3.0,
                ];
                let phase = kf * 1.3 + af * 0.7;
                out.push(0.02 / (1.0 + kf / 10.0) * (f[0] * p.x + f[1] * p.y + f[2] * p.z + phase).sin());
            }
        }
    }
    out
}
