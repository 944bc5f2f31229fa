//! Stage 1 + stage 2 on synthetic pose sets whose answer is known: a rigidly moved
//! body has no saliency anywhere, and a bending cylinder (two rigid halves with a
//! blended joint, as in linear blend skinning) is salient at the joint only.

use std::f64::consts::PI;

use desal_fit::{FitConfig, FitResult, fit_pose_set};
use desal_mesh::math::{Mat3, Real, UnitQuat, Vec3};
use desal_mesh::{NoProgress, PartLabels, PoseSet};
use desal_saliency::{ResidualTable, Saliency, SaliencyConfig, compute_saliency};

const RINGS: usize = 41;
const SEGMENTS: usize = 24;
const LENGTH: Real = 2.0;
const RADIUS: Real = 0.2;
/// The joint sits halfway along the axis; the skinning blend spans `JOINT ± BLEND`.
const JOINT: Real = 1.0;
const BLEND: Real = 0.25;

/// An open cylinder along +z, ring-major vertices (`ring * SEGMENTS + segment`).
fn cylinder() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = Vec::with_capacity(RINGS * SEGMENTS);
    for ring in 0..RINGS {
        let z = LENGTH * ring as Real / (RINGS - 1) as Real;
        for s in 0..SEGMENTS {
            let a = 2.0 * PI * s as Real / SEGMENTS as Real;
            positions.push(Vec3::new(RADIUS * a.cos(), RADIUS * a.sin(), z));
        }
    }
    let mut faces = Vec::new();
    for ring in 0..RINGS - 1 {
        for s in 0..SEGMENTS {
            let (a, b) = ((ring * SEGMENTS + s) as u32, (ring * SEGMENTS + (s + 1) % SEGMENTS) as u32);
            let (c, d) = (a + SEGMENTS as u32, b + SEGMENTS as u32);
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
    }
    (positions, faces)
}

fn halves(positions: &[Vec3]) -> PartLabels {
    let ids = positions.iter().map(|p| u32::from(p.z >= JOINT)).collect();
    PartLabels::try_new(ids, vec!["lower".into(), "upper".into()]).unwrap()
}

fn smoothstep(x: Real) -> Real {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The cylinder bent by `angle` about the x axis through the joint, blending the two
/// halves' transforms over the joint region.
fn bend(positions: &[Vec3], angle: Real) -> Vec<Vec3> {
    let rotation = UnitQuat::from_scaled_axis(Vec3::x() * angle);
    let joint = Vec3::new(0.0, 0.0, JOINT);
    positions
        .iter()
        .map(|p| {
            let alpha = smoothstep((p.z - (JOINT - BLEND)) / (2.0 * BLEND));
            (1.0 - alpha) * p + alpha * (rotation * (p - joint) + joint)
        })
        .collect()
}

fn fit_and_saliency(poses: &PoseSet, labels: &PartLabels) -> (FitResult, Saliency) {
    let fit = fit_pose_set(poses, labels, &FitConfig::default(), &NoProgress).unwrap();
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count,
        pose_names: &fit.pose_names,
        template: Some(fit.template),
        length_scale: poses.template_mesh().diagonal(),
    };
    let saliency = compute_saliency(&table, &SaliencyConfig::default()).unwrap();
    (fit, saliency)
}

fn pose_set(poses: Vec<Vec<Vec3>>, faces: Vec<[u32; 3]>) -> PoseSet {
    let names = (0..poses.len()).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, faces, 0).unwrap()
}

#[test]
fn a_rigidly_moved_body_has_zero_saliency() {
    let (template, faces) = cylinder();
    let labels = halves(&template);
    let moved = |axis: Vec3, angle: Real, shift: Vec3| -> Vec<Vec3> {
        let r: Mat3 = UnitQuat::from_scaled_axis(axis.normalize() * angle).to_rotation_matrix().into_inner();
        template.iter().map(|p| r * p + shift).collect()
    };
    // Whole-body motions, and one pose where each half moves by its own rigid motion
    // (a joint with no skin: still no deformation within a part).
    let mut split = moved(Vec3::new(1.0, 2.0, 3.0), 0.7, Vec3::new(0.1, 0.2, 0.3));
    let upper = moved(Vec3::new(-1.0, 0.5, 0.2), 2.0, Vec3::new(3.0, -1.0, 0.0));
    for (v, p) in split.iter_mut().enumerate() {
        if labels.labels[v] == 1 {
            *p = upper[v];
        }
    }
    let poses = vec![
        template.clone(),
        moved(Vec3::z(), 1.0, Vec3::new(5.0, 0.0, 0.0)),
        moved(Vec3::new(0.3, -1.0, 0.0), -2.5, Vec3::new(0.0, -4.0, 1.0)),
        split,
    ];
    let (fit, saliency) = fit_and_saliency(&pose_set(poses, faces), &labels);
    assert!(fit.residuals.iter().all(|&r| r < 1e-12), "max {}", fit.summary.max_residual);
    assert!(saliency.report.rigid);
    assert!(saliency.saliency.iter().all(|&s| s == 0.0));
    assert!(saliency.weights.iter().all(|&w| w == saliency.report.weight_floor));
}

#[test]
fn a_bending_cylinder_is_salient_at_its_joint() {
    let (template, faces) = cylinder();
    let labels = halves(&template);
    let mut poses = vec![template.clone()];
    poses.extend([20.0, 45.0, 70.0, 95.0].map(|deg: Real| bend(&template, deg.to_radians())));
    let (_, saliency) = fit_and_saliency(&pose_set(poses, faces), &labels);
    assert!(!saliency.report.rigid);

    let ring_mean = |ring: usize| -> Real {
        saliency.saliency[ring * SEGMENTS..(ring + 1) * SEGMENTS].iter().sum::<Real>() / SEGMENTS as Real
    };
    let ring_z = |ring: usize| LENGTH * ring as Real / (RINGS - 1) as Real;
    let means: Vec<Real> = (0..RINGS).map(ring_mean).collect();
    let peak = (0..RINGS).fold(0, |best, r| if means[r] > means[best] { r } else { best });
    eprintln!("ring means: {:?}", means.iter().map(|m| (m * 100.0).round() / 100.0).collect::<Vec<_>>());

    // The peak is inside the blended joint region, and the most salient single vertex too.
    assert!((ring_z(peak) - JOINT).abs() <= BLEND, "peak ring {peak} at z = {}", ring_z(peak));
    let top_vertex = (0..saliency.saliency.len())
        .fold(0, |best, v| if saliency.saliency[v] > saliency.saliency[best] { v } else { best });
    assert!((template[top_vertex].z - JOINT).abs() <= BLEND);
    // Outside the blend the halves move rigidly; what little saliency they get comes from
    // each part's fit being pulled by its blended vertices. It must be an order of
    // magnitude below the joint's.
    for ring in (0..RINGS).filter(|&r| (ring_z(r) - JOINT).abs() > BLEND) {
        assert!(means[ring] < 0.1 * means[peak], "ring {ring}: {} vs peak {}", means[ring], means[peak]);
    }
}
