//! Four `f64` lanes, for costing four edges at once ([`crate::quadric::Quadric4`]).
//! Every operation is element-wise and IEEE-exact, with no fused multiply-add, so a
//! lane computes bit for bit what the scalar expression written in the same order
//! does; LLVM turns the element-wise arrays into vector instructions in the AVX2
//! clone of the listing sweep (`edges.rs`), with no `unsafe` and no intrinsics.

use std::ops::{Add, Div, Mul, Neg, Sub};

use desal_mesh::Vec3;

/// `[f(0), f(1), f(2), f(3)]`, written out and inlined by force: `std::array::from_fn`
/// and `[T; 4]::map` stayed calls per lane in the listing sweep (BENCHMARKS.md
/// "Issue 40").
#[inline(always)]
pub(crate) fn four<T>(mut f: impl FnMut(usize) -> T) -> [T; 4] {
    [f(0), f(1), f(2), f(3)]
}

/// Four `f64`, one per edge costed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lanes(pub(crate) [f64; 4]);

impl Lanes {
    #[inline]
    pub(crate) fn splat(x: f64) -> Self {
        Self([x; 4])
    }

    /// Lane `l` is `f(l)`.
    #[inline]
    pub(crate) fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Self(four(f))
    }

    #[inline]
    fn map2(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let (a, b) = (self.0, o.0);
        Self([f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])])
    }

    #[inline]
    pub(crate) fn sqrt(self) -> Self {
        let a = self.0;
        Self([a[0].sqrt(), a[1].sqrt(), a[2].sqrt(), a[3].sqrt()])
    }

    #[inline]
    pub(crate) fn abs(self) -> Self {
        let a = self.0;
        Self([a[0].abs(), a[1].abs(), a[2].abs(), a[3].abs()])
    }

    /// Lane-wise `self > o` (false where either is NaN).
    #[inline]
    pub(crate) fn gt(self, o: Self) -> [bool; 4] {
        let (a, b) = (self.0, o.0);
        [a[0] > b[0], a[1] > b[1], a[2] > b[2], a[3] > b[3]]
    }

    /// Lane-wise `self <= o` (false where either is NaN).
    #[inline]
    pub(crate) fn le(self, o: Self) -> [bool; 4] {
        let (a, b) = (self.0, o.0);
        [a[0] <= b[0], a[1] <= b[1], a[2] <= b[2], a[3] <= b[3]]
    }
}

impl Add for Lanes {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        self.map2(o, |a, b| a + b)
    }
}

impl Sub for Lanes {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self.map2(o, |a, b| a - b)
    }
}

impl Mul for Lanes {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        self.map2(o, |a, b| a * b)
    }
}

impl Div for Lanes {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        self.map2(o, |a, b| a / b)
    }
}

impl Neg for Lanes {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        let a = self.0;
        Self([-a[0], -a[1], -a[2], -a[3]])
    }
}

/// Four points, one per lane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Points {
    pub(crate) x: Lanes,
    pub(crate) y: Lanes,
    pub(crate) z: Lanes,
}

impl Points {
    /// Lane `l` is `*p[l]` (read in place: copying the points first costs a store and
    /// load each).
    #[inline]
    pub(crate) fn of(p: [&Vec3; 4]) -> Self {
        Self { x: Lanes::from_fn(|l| p[l].x), y: Lanes::from_fn(|l| p[l].y), z: Lanes::from_fn(|l| p[l].z) }
    }

    /// nalgebra's `dot`: `(x·x' + y·y') + z·z'`.
    #[inline]
    pub(crate) fn dot(&self, o: &Self) -> Lanes {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// nalgebra's `norm`: `sqrt(0 + ((x² + y²) + z²))`, where `0 +` changes nothing (a
    /// sum of squares is never `-0`).
    #[inline]
    pub(crate) fn norm(&self) -> Lanes {
        self.dot(self).sqrt()
    }

    /// The lane-wise Euclidean norm of `self - o`, as nalgebra computes
    /// `(self - o).norm()`.
    #[inline]
    pub(crate) fn distance(&self, o: &Self) -> Lanes {
        (*self - *o).norm()
    }
}

impl Sub for Points {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}
