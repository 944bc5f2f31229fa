//! Attribute seams: edges of the (welded) input along which the caller's attributes are
//! split, such as a UV chart border or a hard normal edge (meshoptimizer's `Kind_Seam`,
//! with its `loop` array). The mesh is one surface across a seam, so stage 3 sees no
//! boundary there; what must survive is the seam as a polyline of edges, so that each
//! output face lies on one side of it and its corners can take that side's attributes.
//!
//! The graph here holds the *current* seam edges: a seam vertex that collapses along its
//! seam hands its other seam edge to the vertex that absorbs it
//! ([`SeamGraph::collapse`]). Which collapses the seams allow is the rule table in
//! `safeguards.rs`; the seam flags are set in `classify.rs`.

/// The seam edges of the current mesh, as every slot's seam neighbours (ascending).
#[derive(Debug, Clone)]
pub(crate) struct SeamGraph {
    neighbours: Vec<Vec<u32>>,
}

impl SeamGraph {
    /// The graph of `edges` over `vertex_count` slots; repeated edges (in either
    /// direction) count once. Every edge must have two distinct endpoints in range (the
    /// entry points check it).
    pub(crate) fn new(vertex_count: usize, edges: &[[u32; 2]]) -> Self {
        let mut neighbours = vec![Vec::new(); vertex_count];
        for &[a, b] in edges {
            debug_assert!(a != b && (a as usize) < vertex_count && (b as usize) < vertex_count);
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
        for n in &mut neighbours {
            n.sort_unstable();
            n.dedup();
        }
        Self { neighbours }
    }

    /// The seam neighbours of slot `v`, ascending.
    #[inline]
    pub(crate) fn of(&self, v: u32) -> &[u32] {
        &self.neighbours[v as usize]
    }

    /// Whether `(a, b)` is a seam edge.
    #[inline]
    pub(crate) fn joins(&self, a: u32, b: u32) -> bool {
        self.neighbours[a as usize].binary_search(&b).is_ok()
    }

    /// Slot `remove` merges into slot `keep`: the seam edge between them (if any) goes,
    /// and every other seam edge of `remove` becomes one of `keep`.
    pub(crate) fn collapse(&mut self, remove: u32, keep: u32) {
        let moved = std::mem::take(&mut self.neighbours[remove as usize]);
        for x in moved {
            let of_x = &mut self.neighbours[x as usize];
            if let Ok(i) = of_x.binary_search(&remove) {
                of_x.remove(i);
            }
            if x == keep {
                continue;
            }
            insert_sorted(of_x, keep);
            insert_sorted(&mut self.neighbours[keep as usize], x);
        }
    }
}

fn insert_sorted(list: &mut Vec<u32>, x: u32) {
    if let Err(at) = list.binary_search(&x) {
        list.insert(at, x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seam polyline 0–1–2–3: merging 1 into 2 along it leaves 0–2–3, and the edge
    /// 1–2 is gone; duplicates and reversed edges count once.
    #[test]
    fn a_collapse_along_the_seam_hands_on_the_other_edge() {
        let mut g = SeamGraph::new(5, &[[0, 1], [1, 2], [2, 1], [3, 2]]);
        assert_eq!(g.of(1), &[0, 2]);
        g.collapse(1, 2);
        assert_eq!((g.of(0), g.of(1), g.of(2), g.of(3)), (&[2][..], &[][..], &[0, 3][..], &[2][..]));
        assert!(g.joins(0, 2) && g.joins(2, 0) && !g.joins(1, 2) && !g.joins(4, 0));
    }
}
