//! Comparing two partitions of the same vertices: the adjusted Rand index (Hubert &
//! Arabie 1985, "Comparing partitions"), 1 for identical partitions up to renaming,
//! about 0 for independent ones.

use desal_mesh::math::Real;

/// The adjusted Rand index of two labellings of the same vertices (any ids; only which
/// vertices share an id matters). 1 when both put every vertex in one class.
///
/// # Panics
/// When the slices differ in length.
pub fn adjusted_rand_index(a: &[u32], b: &[u32]) -> Real {
    assert_eq!(a.len(), b.len(), "both labellings cover the same vertices");
    let rows = a.iter().copied().max().map_or(0, |m| m as usize + 1);
    let cols = b.iter().copied().max().map_or(0, |m| m as usize + 1);
    let mut table = vec![0u64; rows * cols];
    for (&x, &y) in a.iter().zip(b) {
        table[x as usize * cols + y as usize] += 1;
    }
    let pairs = |n: u64| (n * n.saturating_sub(1) / 2) as Real;
    let together: Real = table.iter().map(|&n| pairs(n)).sum();
    let row_pairs: Real = table.chunks(cols.max(1)).map(|row| pairs(row.iter().sum())).sum();
    let col_pairs: Real = (0..cols).map(|j| pairs((0..rows).map(|i| table[i * cols + j]).sum())).sum();
    let expected = row_pairs * col_pairs / pairs(a.len() as u64);
    let best = 0.5 * (row_pairs + col_pairs);
    if best == expected {
        return 1.0;
    }
    (together - expected) / (best - expected)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renamed_partitions_agree_exactly() {
        assert_eq!(adjusted_rand_index(&[0, 0, 1, 1, 2], &[5, 5, 3, 3, 0]), 1.0);
    }

    /// a = {0,1,2}{3,4,5}, b = {0,1}{2,3}{4,5}: pairs together in both 2, row pairs 6,
    /// column pairs 3, all pairs 15, expected 6·3/15 = 1.2, best 4.5:
    /// (2 − 1.2) / (4.5 − 1.2) = 0.8 / 3.3.
    #[test]
    fn a_hand_computed_case() {
        let ari = adjusted_rand_index(&[0, 0, 0, 1, 1, 1], &[0, 0, 1, 1, 2, 2]);
        assert!((ari - 0.8 / 3.3).abs() < 1e-12, "{ari}");
    }
}
