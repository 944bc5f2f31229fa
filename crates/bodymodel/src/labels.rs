//! Part labels from skinning weights: each vertex's dominant joint, merged along the
//! kinematic tree to about the number of parts asked for.
//!
//! The rule, deterministic:
//! 1. a vertex's dominant joint is the one with the largest weight, ties to the lower
//!    joint index (a vertex without weights goes to joint 0);
//! 2. every joint starts as its own part, rooted at itself; a part's size is the rest
//!    surface area of its vertices (a third of each incident triangle's), so a finely
//!    meshed face or hand does not count as a large part;
//! 3. while there are more parts than `target_parts`, or a part other than the root's holds
//!    no vertex, the smallest part other than the root's (ties to the later root joint, so
//!    deeper joints merge first) merges into the part holding its root joint's parent —
//!    together with its mirror image (`left_…` ↔ `right_…`), so both sides stay alike; a
//!    pair is as small as its larger side. A pair merging last can leave one part fewer
//!    than asked;
//! 4. parts that hold vertices are numbered in the order of their root joints and named
//!    after them (`left_elbow` is the forearm, with the hand once it merged in).
//!
//! On the CC0 SMPL-layout fixture, 16 asked gives 15 parts: the hip, the stomach (spine1),
//! spine2, the chest (spine3 with the collars and the neck), the head, and per side the
//! upper leg, the lower leg, the foot (ankle and toes), the upper arm, and the forearm
//! with the hand.

use desal_mesh::PartLabels;

use desal_mesh::Vec3;

use crate::model::{BodyModel, SparseRows};

/// One part per group of joints, at most `target_parts` of them (one fewer when a mirror
/// pair merges last; fewer when fewer joints hold vertices). `labels` are in the model's
/// vertex index space, `names` are root joint names.
pub fn labels_from_weights(model: &BodyModel, target_parts: usize) -> PartLabels {
    let names = model.kind.joint_names();
    let skin = Skin {
        rest: &model.v_template,
        faces: &model.faces,
        weights: &model.weights,
        parents: &model.parents,
        names: &names,
    };
    labels_from_skin(&skin, target_parts)
}

/// What the labels are made from: any skinned mesh's rest positions, triangles, weights
/// (rows per vertex), joint tree and joint names (a model outside the SMPL family: ANNY,
/// MHR through body-models).
#[derive(Debug, Clone, Copy)]
pub struct Skin<'a> {
    pub rest: &'a [Vec3],
    pub faces: &'a [[u32; 3]],
    pub weights: &'a SparseRows,
    /// `parents[joint]`: `None` for the root (joint 0) only, else an earlier joint.
    pub parents: &'a [Option<usize>],
    pub names: &'a [String],
}

impl Skin<'_> {
    /// What [`labels_from_skin`] relies on, checked: one weight row per vertex, weights
    /// finite and of known joints, one name per joint, a tree rooted at joint 0 whose
    /// parents come first, faces in range. The error names the element.
    pub fn check(&self) -> Result<(), String> {
        let (vertices, joints) = (self.rest.len(), self.parents.len());
        if joints == 0 || self.names.len() != joints {
            return Err(format!(
                "{} joint names for {joints} joints; give one name per joint",
                self.names.len()
            ));
        }
        if self.weights.row_count() != vertices {
            return Err(format!("{} weight rows for {vertices} vertices", self.weights.row_count()));
        }
        for (j, p) in self.parents.iter().enumerate() {
            match (j, p) {
                (0, None) => {}
                (0, Some(p)) => return Err(format!("joint 0 (the root) has parent {p}; the root has none")),
                (_, Some(p)) if *p < j => {}
                (_, p) => {
                    let p = p.map_or("none".to_owned(), |p| p.to_string());
                    return Err(format!(
                        "joint {j} has parent {p}; every joint but the root has an earlier parent"
                    ));
                }
            }
        }
        for v in 0..vertices {
            if let Some((j, w)) = self.weights.row(v).find(|&(j, w)| j >= joints || !w.is_finite()) {
                return Err(format!("vertex {v} has weight {w} on joint {j} ({joints} joints)"));
            }
        }
        if let Some((f, _)) =
            self.faces.iter().enumerate().find(|(_, t)| t.iter().any(|&i| i as usize >= vertices))
        {
            return Err(format!("face {f} references a vertex out of range ({vertices} vertices)"));
        }
        Ok(())
    }
}

/// [`labels_from_weights`] for any [`Skin`]. Mirror pairs are found by name:
/// `left_…`/`right_…`, `l_…`/`r_…` (any case), `….L`/`….R` and `…_l`/`…_r`.
///
/// # Panics
/// When `parents` gives a parent to joint 0, none to another joint, or a later joint as
/// a parent, or a weight names a joint out of range (callers check the skin first:
/// [`Skin::check`]).
pub fn labels_from_skin(skin: &Skin, target_parts: usize) -> PartLabels {
    let joint_count = skin.parents.len();
    let dominant: Vec<usize> = (0..skin.rest.len())
        .map(|v| {
            skin.weights
                .row(v)
                .fold((0, f64::NEG_INFINITY), |best, (j, w)| if w > best.1 { (j, w) } else { best })
                .0
        })
        .collect();
    let names = skin.names;
    let mirror = mirror_joints(names);

    // `part_of[joint]`: the root joint of the part the joint is in.
    let mut part_of: Vec<usize> = (0..joint_count).collect();
    let mut vertices = vec![0usize; joint_count];
    let mut area = vec![0.0f64; joint_count];
    let vertex_area = vertex_areas(skin.rest, skin.faces);
    for (v, &j) in dominant.iter().enumerate() {
        vertices[j] += 1;
        area[j] += vertex_area[v];
    }
    let mut alive: Vec<bool> = vec![true; joint_count];
    loop {
        let count = alive.iter().filter(|&&a| a).count();
        let pair_area = |j: usize| match mirror[j] {
            Some(m) if alive[m] => area[j].max(area[m]),
            _ => area[j],
        };
        let smallest = (1..joint_count)
            .filter(|&j| alive[j])
            .min_by(|&a, &b| pair_area(a).total_cmp(&pair_area(b)).then(b.cmp(&a)));
        let Some(part) = smallest else { break };
        let empty = (1..joint_count).any(|j| alive[j] && vertices[j] == 0);
        if count <= target_parts && !empty {
            break;
        }
        // An empty part merges alone: its mirror may hold vertices.
        let partner = mirror[part].filter(|&m| alive[m] && !(vertices[part] == 0 && count <= target_parts));
        for joint in std::iter::once(part).chain(partner) {
            let parent = skin.parents[joint].expect("only joint 0 has no parent");
            let into = part_of[parent];
            for p in part_of.iter_mut().filter(|p| **p == joint) {
                *p = into;
            }
            vertices[into] += vertices[joint];
            area[into] += area[joint];
            alive[joint] = false;
        }
    }

    let kept: Vec<usize> = (0..joint_count).filter(|&j| alive[j] && vertices[j] > 0).collect();
    let mut id_of_root = vec![u32::MAX; joint_count];
    for (id, &root) in kept.iter().enumerate() {
        id_of_root[root] = id as u32;
    }
    let labels = dominant.iter().map(|&j| id_of_root[part_of[j]]).collect();
    let names = kept.iter().map(|&j| names.get(j).cloned().unwrap_or_else(|| format!("joint{j}"))).collect();
    PartLabels::try_new(labels, names).expect("every vertex's part holds it, so it is kept")
}

/// The mirror joint of each joint by name (`left_…` ↔ `right_…`, `l_…` ↔ `r_…` in any
/// case, `….L` ↔ `….R`, `…_l` ↔ `…_r`); `None` for joints without one.
fn mirror_joints(names: &[String]) -> Vec<Option<usize>> {
    const PREFIXES: [(&str, &str); 4] = [("left_", "right_"), ("l_", "r_"), ("L_", "R_"), ("Left", "Right")];
    const SUFFIXES: [(&str, &str); 3] = [(".L", ".R"), ("_l", "_r"), ("_L", "_R")];
    let find = |name: String| names.iter().position(|n| *n == name);
    let other = |n: &str| -> Option<usize> {
        for (a, b) in PREFIXES {
            for (from, to) in [(a, b), (b, a)] {
                if let Some(rest) = n.strip_prefix(from) {
                    return find(format!("{to}{rest}"));
                }
            }
        }
        for (a, b) in SUFFIXES {
            for (from, to) in [(a, b), (b, a)] {
                if let Some(rest) = n.strip_suffix(from) {
                    return find(format!("{rest}{to}"));
                }
            }
        }
        None
    };
    names.iter().map(|n| other(n)).collect()
}

/// Each vertex's share of the rest surface: a third of the area of every triangle at it.
fn vertex_areas(p: &[Vec3], faces: &[[u32; 3]]) -> Vec<f64> {
    let mut out = vec![0.0; p.len()];
    for &[a, b, c] in faces {
        let (a, b, c) = (a as usize, b as usize, c as usize);
        let third = (p[b] - p[a]).cross(&(p[c] - p[a])).norm() / 6.0;
        for v in [a, b, c] {
            out[v] += third;
        }
    }
    out
}
