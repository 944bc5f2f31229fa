//! A small compressed-sparse-row matrix: what D, U and A are, and the few operations a
//! hierarchy needs (build from triplets, multiply, apply to points, export as COO).
//!
//! Columns within a row are strictly increasing and no stored value is an exact zero, so
//! two matrices with the same entries are equal field by field, and the COO export is in
//! row-major order: the same bytes whatever the thread count that built it.

use desal_mesh::{Real, Vec3};

use crate::error::HierarchyError;

/// A `rows × cols` sparse matrix in CSR form.
///
/// **Invariants:** `row_ptr.len() == rows + 1`, `row_ptr[0] == 0`, non-decreasing,
/// `row_ptr[rows] == col_idx.len() == values.len()`; within a row `col_idx` is strictly
/// increasing and `< cols`; no value is `0.0`.
#[derive(Debug, Clone, PartialEq)]
pub struct CsrMatrix {
    pub rows: usize,
    pub cols: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<u32>,
    pub values: Vec<Real>,
}

/// A [`CsrMatrix`] built row by row, as [`CsrMatrix::from_rows`] builds it, without
/// holding every row first.
#[derive(Debug, Clone)]
pub struct CsrBuilder {
    cols: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<u32>,
    values: Vec<Real>,
}

impl CsrBuilder {
    pub fn new(cols: usize) -> Self {
        Self { cols, row_ptr: vec![0], col_idx: Vec::new(), values: Vec::new() }
    }

    /// Appends the next row: entries summed per column, zeros left out. Errors: a column
    /// past the width.
    pub fn push_row(&mut self, mut row: Vec<(u32, Real)>) -> Result<(), HierarchyError> {
        let r = self.row_ptr.len() - 1;
        if let Some(&(c, _)) = row.iter().find(|&&(c, _)| c as usize >= self.cols) {
            return Err(HierarchyError::ColumnOutOfRange { row: r, col: c, cols: self.cols });
        }
        row.sort_by_key(|&(c, _)| c);
        let mut i = 0;
        while i < row.len() {
            let c = row[i].0;
            let mut sum = 0.0;
            while i < row.len() && row[i].0 == c {
                sum += row[i].1;
                i += 1;
            }
            if sum != 0.0 {
                self.col_idx.push(c);
                self.values.push(sum);
            }
        }
        self.row_ptr.push(self.col_idx.len());
        Ok(())
    }

    pub fn finish(self) -> CsrMatrix {
        CsrMatrix {
            rows: self.row_ptr.len() - 1,
            cols: self.cols,
            row_ptr: self.row_ptr,
            col_idx: self.col_idx,
            values: self.values,
        }
    }
}

/// The matrix as coordinate triplets in row-major order (scipy's `coo_matrix` layout).
#[derive(Debug, Clone, PartialEq)]
pub struct Coo {
    pub rows: usize,
    pub cols: usize,
    pub row: Vec<u32>,
    pub col: Vec<u32>,
    pub data: Vec<Real>,
}

impl CsrMatrix {
    /// Builds a matrix from one sparse row per matrix row, each a list of
    /// `(column, value)`; duplicates in a row are summed and exact zeros dropped.
    ///
    /// Errors: a column `>= cols`.
    pub fn from_rows(cols: usize, rows: Vec<Vec<(u32, Real)>>) -> Result<Self, HierarchyError> {
        let mut builder = CsrBuilder::new(cols);
        for row in rows {
            builder.push_row(row)?;
        }
        Ok(builder.finish())
    }

    /// The `n × n` identity.
    pub fn identity(n: usize) -> Self {
        Self {
            rows: n,
            cols: n,
            row_ptr: (0..=n).collect(),
            col_idx: (0..n as u32).collect(),
            values: vec![1.0; n],
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row `r` as `(columns, values)`.
    pub fn row(&self, r: usize) -> (&[u32], &[Real]) {
        let span = self.row_ptr[r]..self.row_ptr[r + 1];
        (&self.col_idx[span.clone()], &self.values[span])
    }

    /// The entry at `(r, c)` (0 when not stored).
    pub fn get(&self, r: usize, c: u32) -> Real {
        let (cols, vals) = self.row(r);
        cols.binary_search(&c).map_or(0.0, |i| vals[i])
    }

    /// Sum of each row.
    pub fn row_sums(&self) -> Vec<Real> {
        (0..self.rows).map(|r| self.row(r).1.iter().sum()).collect()
    }

    /// `self · other`. Errors when the inner dimensions differ.
    pub fn mul(&self, other: &CsrMatrix) -> Result<CsrMatrix, HierarchyError> {
        if self.cols != other.rows {
            return Err(HierarchyError::ShapeMismatch {
                left: (self.rows, self.cols),
                right: (other.rows, other.cols),
            });
        }
        let rows = (0..self.rows)
            .map(|r| {
                let (cols, vals) = self.row(r);
                let mut out = Vec::new();
                for (&k, &a) in cols.iter().zip(vals) {
                    let (ocols, ovals) = other.row(k as usize);
                    out.extend(ocols.iter().zip(ovals).map(|(&c, &b)| (c, a * b)));
                }
                out
            })
            .collect();
        CsrMatrix::from_rows(other.cols, rows)
    }

    /// `self · points` for a `rows × cols` matrix and `cols` points: each output point is
    /// the weighted sum of the input points its row names. Errors on a length mismatch.
    pub fn apply(&self, points: &[Vec3]) -> Result<Vec<Vec3>, HierarchyError> {
        if points.len() != self.cols {
            return Err(HierarchyError::ShapeMismatch {
                left: (self.rows, self.cols),
                right: (points.len(), 3),
            });
        }
        Ok((0..self.rows)
            .map(|r| {
                let (cols, vals) = self.row(r);
                cols.iter().zip(vals).fold(Vec3::zeros(), |acc, (&c, &w)| acc + points[c as usize] * w)
            })
            .collect())
    }

    /// The triplets in row-major order.
    pub fn to_coo(&self) -> Coo {
        let mut row = Vec::with_capacity(self.nnz());
        for r in 0..self.rows {
            row.extend(std::iter::repeat_n(r as u32, self.row_ptr[r + 1] - self.row_ptr[r]));
        }
        Coo { rows: self.rows, cols: self.cols, row, col: self.col_idx.clone(), data: self.values.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Duplicates are summed, zeros dropped, columns sorted: the canonical form.
    #[test]
    fn from_rows_is_canonical() {
        let m = CsrMatrix::from_rows(4, vec![vec![(3, 1.0), (1, 2.0), (3, 0.5)], vec![(2, 1.0), (2, -1.0)]])
            .unwrap();
        assert_eq!(m.row_ptr, vec![0, 2, 2]);
        assert_eq!(m.col_idx, vec![1, 3]);
        assert_eq!(m.values, vec![2.0, 1.5]);
    }

    #[test]
    fn column_past_the_end_is_refused() {
        let err = CsrMatrix::from_rows(2, vec![vec![], vec![(2, 1.0)]]).unwrap_err();
        assert!(matches!(err, HierarchyError::ColumnOutOfRange { row: 1, col: 2, cols: 2 }));
    }

    /// [[1, 2], [0, 3]] · [[4, 0], [5, 6]] = [[14, 12], [15, 18]], by hand.
    #[test]
    fn product_matches_hand_computation() {
        let a = CsrMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 2.0)], vec![(1, 3.0)]]).unwrap();
        let b = CsrMatrix::from_rows(2, vec![vec![(0, 4.0)], vec![(0, 5.0), (1, 6.0)]]).unwrap();
        let c = a.mul(&b).unwrap();
        assert_eq!(c.to_coo().data, vec![14.0, 12.0, 15.0, 18.0]);
        assert_eq!(c.to_coo().row, vec![0, 0, 1, 1]);
        assert!(a.mul(&CsrMatrix::identity(3)).is_err());
    }

    #[test]
    fn apply_weights_points() {
        let m = CsrMatrix::from_rows(2, vec![vec![(0, 0.25), (1, 0.75)]]).unwrap();
        let out = m.apply(&[Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 8.0, -4.0)]).unwrap();
        assert_eq!(out, vec![Vec3::new(3.0, 6.0, -3.0)]);
    }
}
