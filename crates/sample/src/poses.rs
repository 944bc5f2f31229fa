//! The sample's pose table: each pose is a short list of bone turns (degrees about an
//! axis), resolved here into one local rotation per bone.
//!
//! Axes are those of the OBJ frame: **X** points to the body's left, **Y** up, **Z**
//! forward (the body faces +Z). Angles follow the right-hand rule, so for example
//! +Z raises the left arm sideways and -Z the right one, -X swings a thigh or an upper
//! arm forward, +X bends a knee, +Y turns the torso or head towards the body's left.
//! [`Axis::Hinge`] is the one bone-relative axis: the normal of the plane a bone makes
//! with its parent at rest (used for the elbows, which are already bent in the rest
//! pose); a positive angle bends the joint further.
//!
//! Several turns on one bone apply in list order. Rotations stay moderate (linear
//! blend skinning collapses volume near strongly bent joints); the generator checks
//! every pose for inverted faces and self-intersections.

use desal_mesh::Vec3;
use desal_mesh::math::UnitQuat;

use crate::error::SampleError;
use crate::skeleton::Skeleton;

/// The axis of a bone turn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// The OBJ X axis (towards the body's left).
    X,
    /// The OBJ Y axis (up).
    Y,
    /// The OBJ Z axis (forward).
    Z,
    /// `parent direction × bone direction` at rest, normalised: the joint's bending axis.
    Hinge,
}

/// One rotation of one bone about its head.
#[derive(Debug, Clone, PartialEq)]
pub struct Turn {
    pub bone: String,
    pub axis: Axis,
    pub degrees: f64,
}

/// A named pose: the turns that make it; bones not named stay at rest.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSpec {
    /// File stem of the pose (`poses/<name>.ply`).
    pub name: String,
    pub turns: Vec<Turn>,
}

impl PoseSpec {
    pub fn new(name: &str, turns: Vec<Turn>) -> Self {
        Self { name: name.to_owned(), turns }
    }
}

/// A turn of `bone`.
pub fn turn(bone: &str, axis: Axis, degrees: f64) -> Turn {
    Turn { bone: bone.to_owned(), axis, degrees }
}

/// The same turn on a left bone and its right mirror image. Mirroring in the X = 0
/// plane keeps angles about X and about a hinge, and negates angles about Y and Z.
pub fn both(left: &str, right: &str, axis: Axis, degrees: f64) -> Vec<Turn> {
    let mirrored = match axis {
        Axis::X | Axis::Hinge => degrees,
        Axis::Y | Axis::Z => -degrees,
    };
    vec![turn(left, axis, degrees), turn(right, axis, mirrored)]
}

/// The sample's poses, template first. Names sort in table order, so a sorted glob over
/// `poses/*.ply` lists them in this order with the template at index 0.
pub fn standard_poses() -> Vec<PoseSpec> {
    use Axis::{Hinge, X, Y, Z};
    // Limits found by the generator's checks (linear blend skinning on these weights):
    // hip flexion beyond ~30° folds the groin, knee flexion beyond ~35° the back of the
    // right knee, elbow flexion beyond ~25° past rest the inner elbow, and an arm swung
    // forward from the A pose by more than ~40° the armpit.
    vec![
        // The MakeHuman base mesh as modelled: an A pose, arms about 50° below horizontal.
        PoseSpec::new("00_rest", vec![]),
        PoseSpec::new("01_arms_out", both("LeftArm", "RightArm", Z, 45.0)),
        PoseSpec::new(
            "02_arms_up",
            [both("LeftShoulder", "RightShoulder", Z, 15.0), both("LeftArm", "RightArm", Z, 80.0)].concat(),
        ),
        PoseSpec::new(
            "03_elbows_bent",
            [both("LeftArm", "RightArm", X, -25.0), both("LeftForeArm", "RightForeArm", Hinge, 25.0)]
                .concat(),
        ),
        // The left arm out at shoulder height, then swung 45° forward.
        PoseSpec::new(
            "04_arm_forward",
            vec![turn("LeftArm", Z, 45.0), turn("LeftArm", Y, -45.0), turn("RightArm", X, 15.0)],
        ),
        PoseSpec::new(
            "05_half_squat",
            [
                both("LeftUpLeg", "RightUpLeg", X, -28.0),
                both("LeftLeg", "RightLeg", X, 35.0),
                both("LeftFoot", "RightFoot", X, -7.0),
                vec![turn("LowerBack", X, 15.0)],
                both("LeftArm", "RightArm", X, -30.0),
            ]
            .concat(),
        ),
        PoseSpec::new(
            "06_lunge",
            vec![
                turn("RightUpLeg", X, -25.0),
                turn("RightLeg", X, 35.0),
                turn("RightFoot", X, -10.0),
                turn("LeftUpLeg", X, 15.0),
                turn("LeftLeg", X, 25.0),
                turn("LeftFoot", X, -10.0),
            ],
        ),
        PoseSpec::new(
            "07_step",
            vec![
                turn("LeftUpLeg", X, -20.0),
                turn("LeftLeg", X, 15.0),
                turn("RightUpLeg", X, 15.0),
                turn("RightLeg", X, 15.0),
                turn("RightFoot", X, -10.0),
                turn("LeftArm", X, 20.0),
                turn("RightArm", X, -20.0),
            ],
        ),
        PoseSpec::new(
            "08_torso_twist",
            vec![turn("LowerBack", Y, 10.0), turn("Spine", Y, 15.0), turn("Spine1", Y, 10.0)],
        ),
        // The head tilts back a little: turned level, the chin cuts into the neck.
        PoseSpec::new(
            "09_head_turn",
            vec![turn("Neck", Y, 15.0), turn("Neck1", Y, 15.0), turn("Head", Y, 10.0), turn("Head", X, -8.0)],
        ),
        PoseSpec::new(
            "10_side_bend",
            [
                vec![turn("LowerBack", Z, -10.0), turn("Spine", Z, -10.0)],
                both("LeftArm", "RightArm", Z, 10.0),
            ]
            .concat(),
        ),
    ]
}

/// One local rotation per bone of `skeleton` (bone order) for `pose`.
pub fn local_rotations(skeleton: &Skeleton, pose: &PoseSpec) -> Result<Vec<UnitQuat>, SampleError> {
    let mut local = vec![UnitQuat::identity(); skeleton.bone_count()];
    for t in &pose.turns {
        let bone = skeleton
            .index_of(&t.bone)
            .ok_or_else(|| SampleError::UnknownPoseBone { pose: pose.name.clone(), bone: t.bone.clone() })?;
        let axis = match t.axis {
            Axis::X => Vec3::x(),
            Axis::Y => Vec3::y(),
            Axis::Z => Vec3::z(),
            Axis::Hinge => hinge_axis(skeleton, bone)
                .ok_or_else(|| SampleError::NoHinge { pose: pose.name.clone(), bone: t.bone.clone() })?,
        };
        let rotation = UnitQuat::from_scaled_axis(axis * t.degrees.to_radians());
        // Later turns apply after earlier ones.
        local[bone] = rotation * local[bone];
    }
    Ok(local)
}

/// `parent direction × bone direction`, normalised; `None` for the root or a bone
/// (nearly) parallel to its parent.
fn hinge_axis(skeleton: &Skeleton, bone: usize) -> Option<Vec3> {
    let parent = skeleton.bones[bone].parent?;
    let axis = skeleton.direction(parent).cross(&skeleton.direction(bone));
    // Below ~3° of bend the plane of the joint is too uncertain to bend about.
    (axis.norm() > 0.05).then(|| axis.normalize())
}
