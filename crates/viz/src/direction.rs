//! [`Direction`]: a signed coordinate axis, for the renderer's up and front and for the
//! errors that name them (below both).

use desal_mesh::math::Vec3;

/// A coordinate axis with a sign, for up and front directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl Direction {
    /// The unit vector.
    pub fn vector(self) -> Vec3 {
        match self {
            Direction::PosX => Vec3::x(),
            Direction::NegX => -Vec3::x(),
            Direction::PosY => Vec3::y(),
            Direction::NegY => -Vec3::y(),
            Direction::PosZ => Vec3::z(),
            Direction::NegZ => -Vec3::z(),
        }
    }

    /// The axis index: 0 for x, 1 for y, 2 for z.
    pub fn axis(self) -> usize {
        match self {
            Direction::PosX | Direction::NegX => 0,
            Direction::PosY | Direction::NegY => 1,
            Direction::PosZ | Direction::NegZ => 2,
        }
    }

    /// The positive direction along axis `axis` (0, 1, 2).
    pub fn positive(axis: usize) -> Self {
        [Direction::PosX, Direction::PosY, Direction::PosZ][axis]
    }

    /// The opposite direction.
    pub fn opposite(self) -> Self {
        match self {
            Direction::PosX => Direction::NegX,
            Direction::NegX => Direction::PosX,
            Direction::PosY => Direction::NegY,
            Direction::NegY => Direction::PosY,
            Direction::PosZ => Direction::NegZ,
            Direction::NegZ => Direction::PosZ,
        }
    }

    /// A caption such as `+Z`.
    pub fn label(self) -> &'static str {
        match self {
            Direction::PosX => "+X",
            Direction::NegX => "-X",
            Direction::PosY => "+Y",
            Direction::NegY => "-Y",
            Direction::PosZ => "+Z",
            Direction::NegZ => "-Z",
        }
    }
}
