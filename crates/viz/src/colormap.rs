//! The viridis colour map (van der Walt, Smith & Firing, matplotlib 2.0, released
//! under CC0): perceptually uniform, readable in grey scale and by colour-blind
//! readers, unlike the rainbow "jet" maps common in mesh papers.
//!
//! The table samples matplotlib's 256-entry `_viridis_data` at 33 evenly spaced
//! points (t = k/32) as 8-bit sRGB; linear interpolation between them reproduces the
//! full table to within 2 levels of 255.

/// Viridis at `t = k / 32`, `k = 0..=32`, dark purple to yellow.
const VIRIDIS: [[u8; 3]; 33] = [
    [68, 1, 84],
    [71, 13, 96],
    [72, 24, 106],
    [72, 35, 116],
    [71, 45, 123],
    [69, 54, 129],
    [66, 64, 134],
    [63, 73, 137],
    [59, 82, 139],
    [55, 90, 141],
    [51, 99, 141],
    [47, 106, 142],
    [44, 114, 142],
    [41, 122, 142],
    [38, 129, 142],
    [35, 137, 142],
    [33, 144, 140],
    [31, 152, 139],
    [31, 159, 136],
    [33, 166, 133],
    [40, 174, 128],
    [49, 181, 123],
    [62, 188, 116],
    [76, 194, 108],
    [93, 201, 99],
    [110, 206, 88],
    [130, 211, 76],
    [150, 216, 63],
    [171, 220, 50],
    [192, 223, 36],
    [213, 226, 26],
    [234, 229, 26],
    [253, 231, 37],
];

/// The viridis colour of `t` in `[0, 1]` (clamped; NaN maps to 0), as 8-bit sRGB.
/// Used for heat maps and for PLY vertex colours.
pub fn colormap(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|c| (a[c] as f64 + f * (b[c] as f64 - a[c] as f64)).round() as u8)
}

/// Per-face colour-map values that draw part labels (`labels[v]` per vertex) one colour
/// each: a face takes the part of the majority of its corners (ties: its first corner's),
/// and part `k` the value `frac(k · φ)`, so parts with neighbouring ids get far-apart
/// colours. For [`crate::Scalar::PerFace`] over the range `[0, 1]`.
pub fn part_face_values(faces: &[[u32; 3]], labels: &[u32]) -> Vec<f64> {
    let golden = (5f64.sqrt() - 1.0) / 2.0;
    faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| labels[v as usize]);
            let part = if b == c { b } else { a };
            (part as f64 * golden).fract()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_samples_match_matplotlib() {
        // matplotlib's table: entry 0 = (0.267004, 0.004874, 0.329415), entry 255 =
        // (0.993248, 0.906157, 0.143936), entry 64 = (0.229739, 0.322361, 0.545706),
        // entry 128 = (0.127568, 0.566949, 0.550556).
        assert_eq!(colormap(0.0), [68, 1, 84]);
        assert_eq!(colormap(1.0), [253, 231, 37]);
        for (entry, rgb) in [(64.0, [0.229739, 0.322361, 0.545706]), (128.0, [0.127568, 0.566949, 0.550556])]
        {
            let got = colormap(entry / 255.0);
            for (g, want) in got.iter().zip(rgb) {
                assert!((*g as f64 - want * 255.0).abs() <= 2.0, "entry {entry}: {got:?}");
            }
        }
    }

    #[test]
    fn out_of_range_and_nan_are_clamped() {
        assert_eq!(colormap(-3.0), colormap(0.0));
        assert_eq!(colormap(7.0), colormap(1.0));
        assert_eq!(colormap(f64::NAN), colormap(0.0));
    }

    /// Viridis brightens monotonically, which is what makes it readable in grey.
    #[test]
    fn luminance_increases_monotonically() {
        let luminance = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        let values: Vec<f64> = (0..=100).map(|k| luminance(colormap(k as f64 / 100.0))).collect();
        assert!(values.windows(2).all(|w| w[1] >= w[0] - 0.5), "{values:?}");
    }
}

#[cfg(test)]
mod part_value_tests {
    use super::*;

    /// Two corners agreeing decide the face; otherwise the first corner does. Part 0 is
    /// value 0 and part 1 is `frac(φ)`.
    #[test]
    fn a_face_takes_its_majority_part_else_its_first_corner() {
        let golden = (5f64.sqrt() - 1.0) / 2.0;
        let labels = [0, 1, 1, 2];
        assert_eq!(part_face_values(&[[0, 1, 2]], &labels), vec![golden]);
        assert_eq!(part_face_values(&[[0, 1, 3]], &labels), vec![0.0]);
        assert_eq!(part_face_values(&[[3, 0, 0]], &labels), vec![0.0]);
    }
}
