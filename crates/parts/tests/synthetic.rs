//! Part discovery on hand-made pose sets with exact answers: an articulated tube of four
//! rigid segments is split into exactly its segments; a pose set without motion gets
//! one part; the labels do not depend on the thread count.

use desal_mesh::math::{Mat3, Real, UnitQuat, Vec3};
use desal_mesh::{Face, PoseSet};
use desal_parts::{PartsConfig, adjusted_rand_index, discover_parts};

const RING: usize = 12;
const RINGS: usize = 40;
const SEGMENTS: usize = 4;
const SPACING: Real = 0.25;

/// An open tube along x: `RINGS` rings of `RING` vertices, radius 0.5.
fn tube() -> (Vec<Vec3>, Vec<Face>) {
    let mut positions = Vec::new();
    for r in 0..RINGS {
        for k in 0..RING {
            let a = k as Real / RING as Real * std::f64::consts::TAU;
            positions.push(Vec3::new(r as Real * SPACING, 0.5 * a.cos(), 0.5 * a.sin()));
        }
    }
    let mut faces = Vec::new();
    for r in 0..RINGS - 1 {
        for k in 0..RING {
            let (a, b) = ((r * RING + k) as u32, (r * RING + (k + 1) % RING) as u32);
            let (c, d) = (a + RING as u32, b + RING as u32);
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
    }
    (positions, faces)
}

/// Segment of each vertex: rings `10 s .. 10 s + 9` are segment `s`.
fn segment_of(v: usize) -> u32 {
    (v / RING / (RINGS / SEGMENTS)) as u32
}

/// Poses the tube by turning each joint (the plane between two segments) by
/// `angles[j]` (radians) about `axes[j]`, composed down the chain: every segment moves
/// rigidly, the triangles across a joint stretch.
fn pose(template: &[Vec3], angles: [Real; SEGMENTS - 1], axes: [Vec3; SEGMENTS - 1]) -> Vec<Vec3> {
    let mut rotations = vec![Mat3::identity()];
    let mut translations = vec![Vec3::zeros()];
    for j in 0..SEGMENTS - 1 {
        let joint = Vec3::new(((j + 1) * RINGS / SEGMENTS) as Real * SPACING - 0.5 * SPACING, 0.0, 0.0);
        let turn =
            UnitQuat::from_scaled_axis(axes[j].normalize() * angles[j]).to_rotation_matrix().into_inner();
        // x ↦ R_j (turn (x − joint) + joint) + t_j
        let (r, t) = (rotations[j], translations[j]);
        rotations.push(r * turn);
        translations.push(r * (joint - turn * joint) + t);
    }
    template
        .iter()
        .enumerate()
        .map(|(v, p)| {
            let s = segment_of(v) as usize;
            rotations[s] * p + translations[s]
        })
        .collect()
}

fn articulated() -> PoseSet {
    let (template, faces) = tube();
    let (z, y) = (Vec3::z(), Vec3::y());
    let poses = vec![
        template.clone(),
        pose(&template, [0.7, 0.0, 0.0], [z, z, z]),
        pose(&template, [0.0, 0.9, -0.5], [z, y, z]),
        pose(&template, [-0.35, 0.5, 1.0], [y, z, y]),
        pose(&template, [0.3, -0.6, 0.4], [z, z, y]),
    ];
    let names = (0..poses.len()).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, faces, 0).unwrap()
}

/// Given K = 4, and with K chosen at the knee, discovery returns the four segments
/// exactly (ARI 1: every vertex in its segment), and their residual is zero to rounding.
#[test]
fn an_articulated_tube_splits_into_exactly_its_segments() {
    let poses = articulated();
    let truth: Vec<u32> = (0..poses.vertex_count()).map(segment_of).collect();
    for parts in [Some(4), None] {
        let (labels, report) =
            discover_parts(&poses, &PartsConfig { parts, ..PartsConfig::default() }).unwrap();
        eprintln!(
            "parts {parts:?}: curve {:?}",
            report.curve.iter().map(|c| c.mean_residual).collect::<Vec<_>>()
        );
        assert_eq!(labels.part_count(), 4, "parts {parts:?}");
        assert_eq!(adjusted_rand_index(&labels.labels, &truth), 1.0, "parts {parts:?}");
        // Numbered by smallest vertex, the parts are the segments in order.
        assert_eq!(labels.labels, truth);
        assert!(report.mean_residual < 1e-9, "{}", report.mean_residual);
        assert_eq!(report.part_sizes, vec![RING * RINGS / SEGMENTS; SEGMENTS]);
        assert!(!report.motionless);
    }
}

/// A pose set whose poses all equal the template, and one with the template alone: no
/// motion, so one part and `motionless`, whatever K asks for (the documented choice).
#[test]
fn a_pose_set_without_motion_gets_one_part() {
    let (template, faces) = tube();
    let still =
        PoseSet::try_new(vec!["a".into(), "b".into()], vec![template.clone(); 2], faces.clone(), 0).unwrap();
    let alone = PoseSet::try_new(vec!["a".into()], vec![template], faces, 0).unwrap();
    for poses in [&still, &alone] {
        for parts in [None, Some(16)] {
            let (labels, report) =
                discover_parts(poses, &PartsConfig { parts, ..PartsConfig::default() }).unwrap();
            assert_eq!(labels.part_count(), 1);
            assert!(labels.labels.iter().all(|&k| k == 0));
            assert!(report.motionless);
            // Identical poses: the fit is the identity up to rounding of the centring.
            assert!(report.mean_residual < 1e-12, "{}", report.mean_residual);
        }
    }
}

/// The tube with a smooth non-rigid bulge added, so that borders are real choices:
/// one and two rayon threads give the same labels and the same curve, bit for bit.
#[test]
fn labels_do_not_depend_on_the_thread_count() {
    let mut poses = articulated();
    for (p, pose) in poses.poses.iter_mut().enumerate().skip(1) {
        for q in pose.iter_mut() {
            *q += Vec3::new(0.0, 0.02 * (p as Real * q.x).sin(), 0.015 * (q.y * 3.0).cos());
        }
    }
    let config = PartsConfig { parts: Some(6), ..PartsConfig::default() };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| discover_parts(&poses, &config).unwrap())
    };
    let ((one, report_one), (two, report_two)) = (run(1), run(2));
    assert_eq!(one, two);
    let bits =
        |r: &desal_parts::PartsReport| r.curve.iter().map(|c| c.mean_residual.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&report_one), bits(&report_two));
    assert_eq!(report_one.mean_residual.to_bits(), report_two.mean_residual.to_bits());
}
