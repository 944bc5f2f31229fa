//! The `rig` deformation model of `desal eval`, for `[dataset.rig]` datasets (issue 15):
//! what an engine does with the simplified rig. The pose set is the rig posed by linear
//! blend skinning at its sampled frames, so the full-resolution ground truth *is* the
//! full rig's LBS, and a simplified rig is judged by skinning it with its own weights
//! and the input's joint matrices at the same frame:
//!
//! - subset placement: every kept vertex keeps its exact weights (capped by
//!   `[dataset.rig] max_influences` if set), so it skins exactly as at full resolution and
//!   v2v against the full ground truth is 0 by construction. v2f, which also measures the
//!   full surface's distance to the coarse one, is what ranks the methods;
//! - optimal placement (and another tool's mesh without weights): the weights are
//!   refitted by least squares (`desal_rig::simplified_influences`) on the *training
//!   frames* of each fold only, so a held-out frame never reaches the weights it is
//!   skinned with;
//! - a method that brings its own skin (`gltfpack`): its weights, as written.
//!
//! The held-out split is the harness's k-fold over the frames. As for every model, the
//! simplification itself (saliency, `multipose`'s quadrics) saw every frame.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use desal_mesh::math::Mat4;
use desal_mesh::{PoseSet, TriMesh, Vec3};
use desal_rig::{Influences, PosedRig, Rig, SimplifiedInput, WeightOptions, Weld};
use rayon::prelude::*;

use crate::measure::{Deformed, MeshSplit, ModelRun};
use desal_driver::stages::rig::{PosesFrom, RigInput, RigParams, RigSource};

/// A rig dataset's input rig, posed at the pose set's frames.
#[derive(Debug)]
pub struct RigModel {
    pub file: PathBuf,
    pub rig: Rig,
    pub posed: PosedRig,
    pub options: WeightOptions,
    /// The `[dataset.rig] mesh` setting (which skinned mesh), for reading another tool's
    /// output of the same file.
    pub mesh: Option<Vec<String>>,
}

/// A simplified mesh that carries its own skin (another tool's rig).
#[derive(Debug, Clone)]
pub struct OwnSkin {
    /// Per simplified vertex (`simp` order), over the joints of `joints`.
    pub influences: Influences,
    /// `joints[pose][j]`: joint `j`'s skinning matrix at each pose of the pose set.
    pub joints: Vec<Vec<Mat4>>,
    /// Most influences of any vertex.
    pub max_influences: usize,
}

/// Another file's rig welded ([`RigModel::welded`]).
#[derive(Debug, Clone)]
pub struct WeldedRig {
    /// Its used welded vertices (bind pose) and faces.
    pub mesh: TriMesh,
    pub skin: OwnSkin,
    /// Per vertex of `mesh`, the split vertex of the file's [`Rig::mesh`] it was taken from.
    pub sources: Vec<u32>,
}

/// One simplified set as the rig model skins it.
#[derive(Debug, Clone, Copy)]
pub struct SkinnedSet<'a> {
    /// Bind-pose positions of the simplified vertices, as stage 3 (or the tool) left them.
    pub positions: &'a [Vec3],
    /// Stage 4's map to welded (pose-set) vertices.
    pub simp_to_welded: &'a [u32],
    /// Every vertex is an input vertex (stage 4 mapped it exactly): exact weights.
    pub subset: bool,
    /// The tool's own skin, which then replaces desal's weights.
    pub own: Option<&'a OwnSkin>,
    /// The simplified set's own poses (its ground truth), for the fit residual.
    pub poses: &'a PoseSet,
}

impl RigModel {
    /// Reads and poses the rig that `poses` was ingested from; refuses a rig whose frames
    /// are not the pose set's.
    pub fn load(source: &RigSource, poses: &PoseSet) -> Result<Self> {
        let input = RigInput { file: &source.file, params: &source.params };
        let (rig, posed) = input.load()?;
        if posed.poses.names != poses.names || posed.poses.vertex_count() != poses.vertex_count() {
            bail!("{}: the rig has changed since its pose set was made", source.file.display());
        }
        Ok(Self {
            file: source.file.clone(),
            rig,
            posed,
            options: source.params.weight_options()?,
            mesh: source.params.mesh.clone(),
        })
    }

    /// The rig of `source` posed at frames no stage saw: random joint turns drawn with the
    /// dataset's seed + 1, as many frames as it samples per source (`crate::lods`), with
    /// its morph targets.
    pub fn held_out(source: &RigSource) -> Result<(Self, Vec<desal_rig::MorphTarget>)> {
        let params = RigParams {
            poses: PosesFrom::Random,
            seed: source.params.seed.wrapping_add(1),
            ..source.params.clone()
        };
        let input = RigInput { file: &source.file, params: &params };
        let (rig, document, posed) = input.load_with_document()?;
        let targets = desal_rig::morph_targets(&rig, &document)?;
        let model = Self {
            file: source.file.clone(),
            rig,
            posed,
            options: source.params.weight_options()?,
            mesh: source.params.mesh.clone(),
        };
        Ok((model, targets))
    }

    /// Skins `set` at every pose: in-sample with weights from all poses, and per fold of
    /// `folds` with weights from the fold's training poses only.
    pub fn deform(&self, set: &SkinnedSet, folds: &[Vec<usize>]) -> Result<Deformed> {
        let pose_count = self.posed.poses.pose_count();
        if set.simp_to_welded.len() != set.positions.len() {
            bail!(
                "{} mapped vertices for {} simplified vertices",
                set.simp_to_welded.len(),
                set.positions.len()
            );
        }
        let all: Vec<usize> = (0..pose_count).collect();
        let (in_sample_run, in_sample) = self.fit_and_skin(set, None, &all, &all)?;
        let mut models = vec![in_sample_run];
        let mut held_out = vec![None; pose_count];
        let mut fold_of_pose = vec![None; pose_count];
        for (k, test) in folds.iter().enumerate() {
            let training = desal_measures::training_poses(pose_count, test);
            let (run, skinned) = self.fit_and_skin(set, Some(k), &training, test)?;
            for (&pose, positions) in test.iter().zip(skinned) {
                held_out[pose] = Some(positions);
                fold_of_pose[pose] = Some(k);
            }
            models.push(run);
        }
        Ok(Deformed { in_sample, held_out, fold_of_pose, models, rotation_seconds: 0.0 })
    }

    /// The weights from `training` (unless the set keeps exact or its own ones), then the
    /// poses `test` skinned with them.
    fn fit_and_skin(
        &self,
        set: &SkinnedSet,
        fold: Option<usize>,
        training: &[usize],
        test: &[usize],
    ) -> Result<(ModelRun, Vec<Vec<Vec3>>)> {
        let started = Instant::now();
        let fitted;
        let (influences, joints): (&Influences, &[Vec<Mat4>]) = match set.own {
            Some(own) => (&own.influences, &own.joints),
            None => {
                // Subset placement keeps exact weights and reads no targets: none are copied.
                let fitted_on = if set.subset { &[][..] } else { training };
                let joints: Vec<Vec<Mat4>> =
                    fitted_on.iter().map(|&p| self.posed.joints[p].clone()).collect();
                let positions: Vec<Vec<Vec3>> =
                    fitted_on.iter().map(|&p| self.posed.poses.poses[p].clone()).collect();
                let targets = desal_rig::PoseTargets { joints: &joints, positions: &positions };
                let input = SimplifiedInput {
                    positions: set.positions,
                    faces: &[],
                    simp_to_welded: set.simp_to_welded,
                    subset: set.subset,
                };
                let (rows, _) = desal_rig::simplified_influences(
                    &self.rig.mesh,
                    &self.posed.weld,
                    &input,
                    &targets,
                    &self.options,
                );
                let mut table = Influences::new();
                for row in rows {
                    table.push_row(row);
                }
                fitted = table;
                (&fitted, &self.posed.joints)
            }
        };
        let fit_seconds = started.elapsed().as_secs_f64();
        let skin = |p: usize| desal_rig::skin_points(set.positions, influences, &joints[p]);
        // The fit's residual: the skinned training poses against the set's own poses.
        let residual: f64 = training
            .par_iter()
            .map(|&p| {
                skin(p).iter().zip(&set.poses.poses[p]).map(|(a, b)| (a - b).norm_squared()).sum::<f64>()
            })
            .sum::<f64>()
            / (training.len() * set.positions.len()) as f64;
        let started = Instant::now();
        let skinned: Vec<Vec<Vec3>> = test.par_iter().map(|&p| skin(p)).collect();
        let synthesis_seconds = started.elapsed().as_secs_f64();
        if let Some(k) = skinned.iter().position(|p| !p.iter().all(|q| q.iter().all(|c| c.is_finite()))) {
            bail!("skinning pose {} gave non-finite positions", self.posed.poses.names[test[k]]);
        }
        let run = ModelRun {
            fold,
            training_poses: training.to_vec(),
            test_poses: test.to_vec(),
            joint_count: joints.first().map_or(0, Vec::len),
            mean_q_residual: residual,
            factor_nonzeros: 0,
            fit_seconds,
            synthesis_seconds,
        };
        Ok((run, skinned))
    }

    /// `other` (another file's rig of the same skeleton: gltfpack's output, a LOD level as
    /// written) welded as [`crate::rig`] skins it: its used welded vertices in the bind
    /// pose, its faces, its own weights and its joints' matrices at this model's poses.
    /// `what` names it in errors.
    pub fn welded(&self, other: &Rig, what: &str) -> Result<WeldedRig> {
        let weld = Weld::new(&other.mesh);
        let representatives = weld.representatives();
        let (kept, faces) = desal_mesh::used_vertices(weld.welded_count(), &weld.faces);
        let sources: Vec<u32> = kept.iter().map(|&w| representatives[w as usize]).collect();
        let positions = sources
            .iter()
            .map(|&s| {
                let p = other.mesh.positions[s as usize];
                Vec3::new(p[0].into(), p[1].into(), p[2].into())
            })
            .collect();
        let mut influences = Influences::new();
        for &s in &sources {
            influences.push_row(other.mesh.influences.of(s as usize).map(|(j, w)| (j as u16, w)));
        }
        let joints = self.joints_for(other, what)?;
        let max_influences = influences.max_influences();
        Ok(WeldedRig {
            mesh: TriMesh { positions, faces },
            skin: OwnSkin { influences, joints, max_influences },
            sources,
        })
    }

    /// The glTF mesh of each welded vertex, when the rig has more than one
    /// ([`crate::measure::MeshSplit`]); welding never joins vertices of two meshes.
    pub fn mesh_split(&self) -> Option<MeshSplit> {
        let meshes = &self.rig.meshes;
        if meshes.len() < 2 {
            return None;
        }
        // The meshes' runs cover the split vertices in order.
        let of_vertex = self
            .posed
            .weld
            .representatives()
            .into_iter()
            .map(|split| meshes.partition_point(|m| m.vertices.end <= split) as u32)
            .collect();
        Some(MeshSplit { of_vertex, mesh_count: meshes.len() })
    }

    /// The input's skinning matrices re-expressed for another file's skin of the same
    /// skeleton: for each of `other`'s joints, matched to the input's by node name,
    /// `world · other_ibm = input_skinning · input_ibm⁻¹ · other_ibm`, per pose.
    pub fn joints_for(&self, other: &Rig, what: &str) -> Result<Vec<Vec<Mat4>>> {
        let names: Vec<String> = (0..self.rig.skin.joints.len()).map(|j| self.rig.joint_name(j)).collect();
        let mut conversions = Vec::with_capacity(other.skin.joints.len());
        for j in 0..other.skin.joints.len() {
            let name = other.joint_name(j);
            let Some(input_joint) = names.iter().position(|n| *n == name) else {
                bail!("{what}: joint '{name}' is not a joint of {}", self.file.display());
            };
            let inverse =
                self.rig.skin.inverse_bind_matrix(input_joint).try_inverse().with_context(|| {
                    format!("{}: joint '{name}' has a singular inverse bind matrix", self.file.display())
                })?;
            conversions.push((input_joint, inverse * other.skin.inverse_bind_matrix(j)));
        }
        Ok(self
            .posed
            .joints
            .iter()
            .map(|pose| conversions.iter().map(|(j, c)| pose[*j] * c).collect())
            .collect())
    }
}
