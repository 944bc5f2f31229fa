//! Choosing the part count at the knee of the residual curve: the point farthest below
//! the chord from the curve's first to its last point, both axes scaled to `[0, 1]`
//! (Satopää et al. 2011, "Finding a 'Kneedle' in a haystack", for a decreasing convex
//! curve).

use desal_mesh::math::Real;

use crate::report::CurvePoint;

/// Index into `curve` of its knee. Ties go to the fewer parts; a curve of one or two
/// points, or a flat one, has its knee at the last point.
pub(crate) fn knee_index(curve: &[CurvePoint]) -> usize {
    let last = curve.len().saturating_sub(1);
    if curve.len() < 3 {
        return last;
    }
    let (k0, k1) = (curve[0].parts as Real, curve[last].parts as Real);
    let hi = curve.iter().map(|c| c.mean_residual).fold(Real::NEG_INFINITY, Real::max);
    let lo = curve.iter().map(|c| c.mean_residual).fold(Real::INFINITY, Real::min);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) || k1 <= k0 {
        return last;
    }
    let (y0, y1) = ((curve[0].mean_residual - lo) / (hi - lo), (curve[last].mean_residual - lo) / (hi - lo));
    // Points less than this (in scaled units) below the chord are on it: rounding must
    // not make a knee of a straight line.
    let mut best = (1e-9, last);
    for (i, c) in curve.iter().enumerate() {
        let x = (c.parts as Real - k0) / (k1 - k0);
        let y = (c.mean_residual - lo) / (hi - lo);
        let below = y0 + (y1 - y0) * x - y;
        if below > best.0 {
            best = (below, i);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(values: &[Real]) -> Vec<CurvePoint> {
        values.iter().enumerate().map(|(i, &r)| CurvePoint { parts: i + 1, mean_residual: r }).collect()
    }

    /// 10, 4, 2, 1.5, 1 scale to 1, 1/3, 1/9, 1/18, 0 against a chord at 1, 3/4, 1/2,
    /// 1/4, 0: they sit 0, 0.417, 0.389, 0.194, 0 below it, so the knee is at 2 parts
    /// (index 1). 10, 8, 2, 1.5, 1 moves it to 3 parts.
    #[test]
    fn the_knee_is_the_point_farthest_below_the_chord() {
        assert_eq!(knee_index(&curve(&[10.0, 4.0, 2.0, 1.5, 1.0])), 1);
        assert_eq!(knee_index(&curve(&[10.0, 8.0, 2.0, 1.5, 1.0])), 2);
    }

    /// A straight line has no point below its chord; short curves have no knee.
    #[test]
    fn lines_and_short_curves_take_the_last_point() {
        assert_eq!(knee_index(&curve(&[4.0, 3.0, 2.0, 1.0])), 3);
        assert_eq!(knee_index(&curve(&[4.0, 1.0])), 1);
        assert_eq!(knee_index(&curve(&[4.0])), 0);
        assert_eq!(knee_index(&curve(&[1.0, 1.0, 1.0])), 2);
    }
}
