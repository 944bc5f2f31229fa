//! Body-part labels: each vertex gets its dominant bone (largest skinning weight, ties
//! to the lower bone index), and bones merge into SCAPE's 16 parts with SCAPE's ids and
//! names (`../shared/datasets/scape/vertex_part_labels_16.txt`), so tools and reports
//! read both data sets alike. Stray islands (a few vertices whose dominant bone
//! belongs to a part elsewhere) are then given to the part around them.

use desal_mesh::{Face, PartLabels};

use crate::error::SampleError;
use crate::skeleton::Skeleton;
use crate::skinning::SkinWeights;

/// Part names by id, as in SCAPE's 16-part labels.
pub const PART_NAMES: [&str; 16] = [
    "lefthand",
    "leftlowerarm",
    "leftupperarm",
    "righthand",
    "rightlowerarm",
    "rightupperarm",
    "leftfoot",
    "leftlowerleg",
    "leftupperleg",
    "rightfoot",
    "rightlowerleg",
    "rightupperleg",
    "head",
    "chest",
    "stomach",
    "hip",
];

/// Which part each `cmu_mb` bone's vertices belong to. Judgement calls: the clavicles
/// (`*Shoulder`) join the chest; `Spine` (navel to lower ribs) joins the chest, which
/// keeps the stomach (`LowerBack`: lower belly and waist) and the chest closer to
/// SCAPE's proportions than the other split; the neck joins the head; the hip-joint
/// bones join the hip.
const BONE_PARTS: [(&str, u32); 31] = [
    ("LeftHand", 0),
    ("LThumb", 0),
    ("LeftFingerBase", 0),
    ("LeftHandFinger1", 0),
    ("LeftForeArm", 1),
    ("LeftArm", 2),
    ("RightHand", 3),
    ("RThumb", 3),
    ("RightFingerBase", 3),
    ("RightHandFinger1", 3),
    ("RightForeArm", 4),
    ("RightArm", 5),
    ("LeftFoot", 6),
    ("LeftToeBase", 6),
    ("LeftLeg", 7),
    ("LeftUpLeg", 8),
    ("RightFoot", 9),
    ("RightToeBase", 9),
    ("RightLeg", 10),
    ("RightUpLeg", 11),
    ("Head", 12),
    ("Neck1", 12),
    ("Neck", 12),
    ("Spine1", 13),
    ("Spine", 13),
    ("LeftShoulder", 13),
    ("RightShoulder", 13),
    ("LowerBack", 14),
    ("Hips", 15),
    ("LHipJoint", 15),
    ("RHipJoint", 15),
];

/// The part of every bone of `skeleton`, in bone order.
pub fn bone_parts(skeleton: &Skeleton) -> Result<Vec<u32>, SampleError> {
    skeleton
        .bones
        .iter()
        .map(|bone| {
            BONE_PARTS
                .iter()
                .find(|(name, _)| *name == bone.name)
                .map(|&(_, part)| part)
                .ok_or_else(|| SampleError::UnmappedBone { bone: bone.name.clone() })
        })
        .collect()
}

/// Labels every vertex of `weights` with the part of its dominant bone.
pub fn label_parts(skeleton: &Skeleton, weights: &SkinWeights) -> Result<PartLabels, SampleError> {
    let parts = bone_parts(skeleton)?;
    let labels = (0..weights.vertex_count()).map(|v| parts[weights.dominant_bone(v)]).collect();
    Ok(PartLabels::try_new(labels, PART_NAMES.iter().map(|s| s.to_string()).collect())?)
}

/// Vertex count of every part; errors on the first part below `minimum`.
pub fn check_part_sizes(labels: &PartLabels, minimum: usize) -> Result<Vec<usize>, SampleError> {
    let counts: Vec<usize> = labels.members().iter().map(Vec::len).collect();
    if let Some((part, &vertices)) = counts.iter().enumerate().find(|&(_, &n)| n < minimum) {
        return Err(SampleError::PartTooSmall {
            part: part as u32,
            name: labels.names[part].clone(),
            vertices,
            minimum,
        });
    }
    Ok(counts)
}

/// Number of connected pieces of every part: vertices of one part are connected when
/// an edge of `faces` joins them. A clean segmentation has one piece per part.
pub fn part_pieces(labels: &PartLabels, faces: &[Face]) -> Vec<usize> {
    let piece = piece_roots(labels, faces);
    let mut pieces = vec![0; labels.part_count()];
    for (v, &root) in piece.iter().enumerate() {
        if root as usize == v {
            pieces[labels.labels[v] as usize] += 1;
        }
    }
    pieces
}

/// Gives every piece of a part other than its largest to the part that borders it
/// most (counted over edges leaving the piece; ties to the lower part id), so that
/// stray islands of a dominant bone do not split a part. Returns the number of
/// vertices relabelled.
pub fn absorb_stray_pieces(labels: &mut PartLabels, faces: &[Face]) -> usize {
    let piece = piece_roots(labels, faces);
    let n = labels.vertex_count();
    let mut piece_size = vec![0usize; n];
    for &root in &piece {
        piece_size[root as usize] += 1;
    }
    // The largest piece of each part (ties to the lower root index) stays.
    let mut keep: Vec<Option<u32>> = vec![None; labels.part_count()];
    for v in 0..n {
        if piece[v] as usize == v {
            let part = labels.labels[v] as usize;
            if keep[part].is_none_or(|k| piece_size[v] > piece_size[k as usize]) {
                keep[part] = Some(v as u32);
            }
        }
    }
    let is_stray = |v: usize| keep[labels.labels[v] as usize] != Some(piece[v]);
    // Border votes per stray piece: votes[root][part].
    let mut votes: std::collections::BTreeMap<u32, Vec<usize>> = std::collections::BTreeMap::new();
    for face in faces {
        for k in 0..3 {
            let (a, b) = (face[k] as usize, face[(k + 1) % 3] as usize);
            for (inside, outside) in [(a, b), (b, a)] {
                if is_stray(inside) && piece[inside] != piece[outside] {
                    let row = votes.entry(piece[inside]).or_insert_with(|| vec![0; labels.part_count()]);
                    row[labels.labels[outside] as usize] += 1;
                }
            }
        }
    }
    let new_part: std::collections::BTreeMap<u32, u32> = votes
        .iter()
        .map(|(&root, row)| {
            let best = (0..row.len()).max_by_key(|&p| (row[p], std::cmp::Reverse(p))).unwrap_or(0);
            (root, best as u32)
        })
        .collect();
    let mut relabelled = 0;
    for (label, root) in labels.labels.iter_mut().zip(&piece) {
        if let Some(&part) = new_part.get(root) {
            *label = part;
            relabelled += 1;
        }
    }
    relabelled
}

/// For every vertex, the smallest vertex index of its piece (its part's vertices
/// connected by edges of `faces`): union by smaller index, so the result does not
/// depend on face order.
fn piece_roots(labels: &PartLabels, faces: &[Face]) -> Vec<u32> {
    let n = labels.vertex_count();
    let mut root: Vec<u32> = (0..n as u32).collect();
    fn find(root: &mut [u32], mut v: u32) -> u32 {
        while root[v as usize] != v {
            root[v as usize] = root[root[v as usize] as usize];
            v = root[v as usize];
        }
        v
    }
    for face in faces {
        for k in 0..3 {
            let (a, b) = (face[k], face[(k + 1) % 3]);
            if labels.labels[a as usize] == labels.labels[b as usize] {
                let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                root[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    (0..n as u32).map(|v| find(&mut root, v)).collect()
}
