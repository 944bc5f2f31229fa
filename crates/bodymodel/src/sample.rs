//! Sampling a model over shapes and poses, streamed: [`Sampler`] yields one posed surface
//! at a time, so 2048 samples of a 10k-vertex model never sit in memory together (it
//! evaluates up to [`BATCH`] poses of a shape together and holds them until taken).
//!
//! The sequence (the crate docs give the distributions): sample 0 is the template — the
//! mean shape in the zero pose, group 0 — then for each shape `s` in `0..shapes`, its
//! `poses` poses, group `s + 1`. Draws come from one ChaCha8 stream seeded by
//! [`SampleConfig::seed`], in this order: a shape's betas when its first pose is made,
//! then per pose the joint rotations (joints 1.. in order, x y z), the turn about the up
//! axis, then the expression. The same seed and settings give the same samples, bit for
//! bit.

use std::collections::VecDeque;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use desal_mesh::Vec3;

use crate::error::BodyModelError;
use crate::eval::{PoseItem, Shaped};
use crate::model::{BodyModel, JointClass};

const FITS: &str = "sampled parameters fit the model by construction";

/// Poses of one shape evaluated together (each row of the pose correctives is then read
/// once for all of them); also the most samples held at once besides the one returned.
pub const BATCH: usize = 8;

/// How shapes and poses are drawn. The defaults are the crate docs' distributions.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleConfig {
    /// Random shapes. Default 8.
    pub shapes: usize,
    /// Poses per shape. Default 8.
    pub poses: usize,
    /// Seed of the one random stream. Default 0.
    pub seed: u64,
    /// Betas drawn per shape (the first ones; at most the model's). Default 10.
    pub shape_components: usize,
    /// Each beta is clipped to ±this. Default 2.5.
    pub beta_clip: f64,
    /// Spread (rad, per axis) of body joints' axis-angles. Default 0.3.
    pub body_sigma: f64,
    /// Spread (rad, per axis) of hand, jaw and eye joints. Default 0.2.
    pub hand_sigma: f64,
    /// When set, the spread of every joint, overriding the two above.
    pub pose_sigma: Option<f64>,
    /// The global turn about the up axis is uniform in ±this (rad). Default π (any
    /// heading); 0 keeps every sample facing the template's way.
    pub max_turn: f64,
    /// The up axis of the model's frame (unit length). Default +Y, the SMPL family's.
    pub up: Vec3,
    /// Draw an expression per pose (SMPL-X, FLAME). Default false.
    pub expressions: bool,
    /// Expression coefficients drawn per pose (the first ones; at most the model's).
    /// Default 10.
    pub expression_components: usize,
}

impl Default for SampleConfig {
    fn default() -> Self {
        Self {
            shapes: 8,
            poses: 8,
            seed: 0,
            shape_components: 10,
            beta_clip: 2.5,
            body_sigma: 0.3,
            hand_sigma: 0.2,
            pose_sigma: None,
            max_turn: std::f64::consts::PI,
            up: Vec3::y(),
            expressions: false,
            expression_components: 10,
        }
    }
}

impl SampleConfig {
    /// Refuses spreads that are negative or not finite, a clip that is not positive, an
    /// up axis that is not unit length, and expressions for a model without them.
    pub fn validate(&self, model: &BodyModel) -> Result<(), BodyModelError> {
        let bad = |name, reason: &str| Err(BodyModelError::BadSetting { name, reason: reason.into() });
        for (name, v) in [
            ("body_sigma", self.body_sigma),
            ("hand_sigma", self.hand_sigma),
            ("pose_sigma", self.pose_sigma.unwrap_or(0.0)),
            ("max_turn", self.max_turn),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, "must be finite and not negative");
            }
        }
        if !(self.beta_clip.is_finite() && self.beta_clip > 0.0) {
            return bad("beta_clip", "must be finite and positive");
        }
        if (self.up.norm() - 1.0).abs() > 1e-9 {
            return bad("up", "must be a unit vector");
        }
        if self.expressions && model.expression_count == 0 {
            return bad(
                "expressions",
                &format!("this {} model has no expression blend shapes", model.kind.name()),
            );
        }
        if self.shapes.checked_mul(self.poses).and_then(|n| n.checked_add(1)).is_none() {
            return bad("shapes", "shapes × poses overflows");
        }
        Ok(())
    }
}

/// One sample with the parameters that made it.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// 0 for the template, `s + 1` for the poses of random shape `s`.
    pub group: usize,
    pub betas: Vec<f64>,
    pub expression: Vec<f64>,
    /// One axis-angle per joint (joint 0: the turn about the up axis).
    pub pose: Vec<Vec3>,
    pub vertices: Vec<Vec3>,
}

/// The stream of samples; `Iterator<Item = (group, vertices)>`, or [`Sampler::next_sample`]
/// for the parameters too.
#[derive(Debug)]
pub struct Sampler<'m> {
    model: &'m BodyModel,
    config: SampleConfig,
    rng: ChaCha8Rng,
    /// Index of the next sample to make, in `0..=len`.
    next: usize,
    len: usize,
    /// The current shape's betas and rest surface.
    shaped: Option<(Vec<f64>, Shaped)>,
    /// Samples made but not yet taken (at most [`BATCH`]).
    pending: VecDeque<Sample>,
}

impl<'m> Sampler<'m> {
    pub fn new(model: &'m BodyModel, config: SampleConfig) -> Result<Self, BodyModelError> {
        config.validate(model)?;
        let len = 1 + config.shapes * config.poses;
        let rng = ChaCha8Rng::seed_from_u64(config.seed);
        Ok(Self { model, config, rng, next: 0, len, shaped: None, pending: VecDeque::new() })
    }

    /// The next sample and its parameters, `None` after the last.
    pub fn next_sample(&mut self) -> Option<Sample> {
        if self.pending.is_empty() && self.next < self.len {
            self.make_batch();
        }
        self.pending.pop_front()
    }

    /// The next samples, from `self.next`: the template alone, or up to [`BATCH`] poses of
    /// one shape, evaluated together. Their parameters are drawn in sample order, so the
    /// stream does not depend on the batching; they fit the model by construction
    /// (component counts capped at the model's, one rotation per joint), so evaluation
    /// cannot fail.
    fn make_batch(&mut self) {
        let model = self.model;
        let index = self.next;
        if index == 0 {
            let shaped = model.shape(&[], &[]).expect(FITS);
            let pose = vec![Vec3::zeros(); model.joint_count()];
            let posed = model.pose(&shaped, &pose, Vec3::zeros()).expect(FITS);
            let vertices = posed.vertices;
            self.pending.push_back(Sample {
                group: 0,
                betas: Vec::new(),
                expression: Vec::new(),
                pose,
                vertices,
            });
            self.next = 1;
            return;
        }
        let (shape, pose_index) = ((index - 1) / self.config.poses, (index - 1) % self.config.poses);
        if pose_index == 0 {
            let betas = self.draw_betas();
            let shaped = model.shape(&betas, &[]).expect(FITS);
            self.shaped = Some((betas, shaped));
        }
        let count = BATCH.min(self.config.poses - pose_index);
        let draws: Vec<(Vec<Vec3>, Vec<f64>)> =
            (0..count).map(|_| (self.draw_pose(), self.draw_expression())).collect();
        let (betas, shaped) = self.shaped.as_ref().expect("a shape is drawn before its poses");
        // An expression changes the rest surface (and, through the regressor, the joints).
        let with_expression: Vec<Option<Shaped>> =
            draws.iter().map(|(_, e)| (!e.is_empty()).then(|| model.shape(betas, e).expect(FITS))).collect();
        let items: Vec<PoseItem> = draws
            .iter()
            .zip(&with_expression)
            .map(|((pose, _), own)| PoseItem {
                shaped: own.as_ref().unwrap_or(shaped),
                pose,
                translation: Vec3::zeros(),
            })
            .collect();
        let posed = model.pose_batch(&items).expect(FITS);
        for ((pose, expression), posed) in draws.into_iter().zip(posed) {
            let vertices = posed.vertices;
            self.pending.push_back(Sample {
                group: shape + 1,
                betas: betas.clone(),
                expression,
                pose,
                vertices,
            });
        }
        self.next += count;
    }

    fn normal(&mut self) -> f64 {
        self.rng.sample(StandardNormal)
    }

    fn draw_betas(&mut self) -> Vec<f64> {
        let n = self.config.shape_components.min(self.model.shape_count);
        let clip = self.config.beta_clip;
        (0..n).map(|_| self.normal().clamp(-clip, clip)).collect()
    }

    fn draw_pose(&mut self) -> Vec<Vec3> {
        let model = self.model;
        let mut pose = Vec::with_capacity(model.joint_count());
        pose.push(Vec3::zeros());
        for joint in 1..model.joint_count() {
            let sigma = self.config.pose_sigma.unwrap_or(match model.kind.joint_class(joint) {
                JointClass::Hand | JointClass::Face => self.config.hand_sigma,
                JointClass::Body | JointClass::Root => self.config.body_sigma,
            });
            let noise = Vec3::new(self.normal(), self.normal(), self.normal()) * sigma;
            pose.push(model.pose_mean[joint] + noise);
        }
        let turn = self.config.max_turn * (2.0 * self.rng.r#gen::<f64>() - 1.0);
        pose[0] = self.config.up * turn;
        pose
    }

    fn draw_expression(&mut self) -> Vec<f64> {
        if !self.config.expressions {
            return Vec::new();
        }
        let n = self.config.expression_components.min(self.model.expression_count);
        (0..n).map(|_| self.normal()).collect()
    }
}

impl Iterator for Sampler<'_> {
    type Item = (usize, Vec<Vec3>);

    fn next(&mut self) -> Option<Self::Item> {
        self.next_sample().map(|s| (s.group, s.vertices))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.len - self.next + self.pending.len();
        (left, Some(left))
    }
}

impl ExactSizeIterator for Sampler<'_> {}
