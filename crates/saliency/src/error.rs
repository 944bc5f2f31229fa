//! The error type of stage 2. Variants name the offending pose, vertex or parameter.

use thiserror::Error;

/// Why saliency could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SaliencyError {
    /// The residual table is not `poses × vertices` long, or names the wrong number of
    /// poses. A mismatched fit artifact; re-run stage 1.
    #[error(
        "the residual table has {len} values but {poses} poses × {vertices} vertices were announced; re-run the fit stage"
    )]
    TableSize { len: usize, poses: usize, vertices: usize },

    /// The template index is not one of the poses.
    #[error("template index {template} is out of range for {poses} poses")]
    TemplateOutOfRange { template: usize, poses: usize },

    /// `exclude_poses` names a pose that is not in the set.
    #[error("cannot exclude pose '{name}': no such pose (known poses: {known})")]
    UnknownPose { name: String, known: String },

    /// After excluding the template and the excluded poses, no pose is left.
    #[error(
        "no pose is left to measure deformation ({poses} poses, template and {excluded} excluded); exclude fewer poses"
    )]
    NoPosesLeft { poses: usize, excluded: usize },

    /// A residual is negative, NaN or infinite: a corrupt fit artifact.
    #[error(
        "residual of vertex {vertex} in pose '{pose}' is {value}, not a finite distance; re-run the fit stage"
    )]
    BadResidual { pose: String, vertex: usize, value: f32 },

    /// A configuration value is outside its documented range.
    #[error("saliency option `{option}` = {value} is out of range: {expected}")]
    BadOption { option: &'static str, value: f64, expected: &'static str },
}
