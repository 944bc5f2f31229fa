//! The current faces of the mesh being simplified and, for every vertex slot, the list
//! of its live faces: the connectivity every collapse reads and rewrites.
//!
//! Layout: a vertex's faces are a run of `refs` (`start`, `len`). When a vertex absorbs
//! a neighbour its new run is appended at the end of `refs` (the old runs are
//! abandoned), and `refs` is compacted when it has grown past `refs_limit`: appending
//! is cheaper than merging in place, and compaction is rare.

use desal_mesh::VertexFaces;

/// Faces (corners as vertex slots, `orig_idx` of the slot holder), their liveness, and
/// each slot's run of live face ids (input face order at first, then in the order
/// collapses rewrote it).
#[derive(Debug)]
pub(crate) struct FaceLists {
    faces: Vec<[u32; 3]>,
    alive: Vec<bool>,
    start: Vec<u32>,
    len: Vec<u32>,
    refs: Vec<u32>,
    /// `refs` is compacted when it grows past this length.
    refs_limit: usize,
    live_faces: usize,
}

/// What a collapse did to the faces: how many died (the faces on the edge, one or two)
/// and their apexes (the corners other than the edge's endpoints).
#[derive(Debug, Clone, Copy)]
pub(crate) struct DeadFaces {
    pub(crate) count: usize,
    pub(crate) apexes: [u32; 2],
}

impl FaceLists {
    /// The lists of `faces` (every face non-degenerate) over `vertex_count` slots.
    pub(crate) fn new(vertex_count: usize, faces: Vec<[u32; 3]>) -> Self {
        let vertex_faces = VertexFaces::new(vertex_count, &faces);
        let len = (0..vertex_count).map(|v| vertex_faces.offsets[v + 1] - vertex_faces.offsets[v]).collect();
        let refs_limit = 2 * vertex_faces.faces.len() + 1024;
        let mut refs = vertex_faces.faces;
        refs.reserve(refs_limit + 64 - refs.len());
        Self {
            alive: vec![true; faces.len()],
            live_faces: faces.len(),
            faces,
            start: vertex_faces.offsets[..vertex_count].to_vec(),
            len,
            refs,
            refs_limit,
        }
    }

    /// The live faces around slot `v`.
    #[inline]
    pub(crate) fn of(&self, v: u32) -> &[u32] {
        // `len` sliced to `start`'s length: one bounds check covers both.
        let (start, len) = (&self.start[..], &self.len[..self.start.len()]);
        let s = start[v as usize] as usize;
        &self.refs[s..s + len[v as usize] as usize]
    }

    /// The number of live faces around slot `v` (its fan size).
    #[inline]
    pub(crate) fn count(&self, v: u32) -> u32 {
        self.len[v as usize]
    }

    /// The number of vertex slots.
    pub(crate) fn slot_count(&self) -> usize {
        self.start.len()
    }

    /// The corners of face `f`, in its orientation.
    #[inline]
    pub(crate) fn face(&self, f: u32) -> [u32; 3] {
        self.faces[f as usize]
    }

    /// All faces (dead ones included), by face id.
    pub(crate) fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The live faces, in input order.
    pub(crate) fn live(&self) -> impl Iterator<Item = &[u32; 3]> {
        self.faces.iter().zip(&self.alive).filter(|(_, alive)| **alive).map(|(f, _)| f)
    }

    pub(crate) fn live_face_count(&self) -> usize {
        self.live_faces
    }

    /// Merges slot `remove` into slot `keep`: the faces on the edge die, `remove`'s
    /// other faces are re-pointed to `keep`, `keep`'s list becomes both lists' live
    /// faces, and the apexes of the dead faces drop them from their lists.
    pub(crate) fn collapse(&mut self, remove: u32, keep: u32) -> DeadFaces {
        let (r, k) = (remove, keep);
        let mut dead = DeadFaces { count: 0, apexes: [u32::MAX; 2] };
        let (r_start, r_len) = (self.start[r as usize] as usize, self.len[r as usize] as usize);
        // The fields borrowed apart: through `self` every `Vec`'s pointer and length is
        // read again after each write to a face.
        let (refs, faces, alive) = (&self.refs[r_start..r_start + r_len], &mut self.faces, &mut self.alive);
        for &f in refs {
            let f = f as usize;
            let face = &mut faces[f];
            if face.contains(&k) {
                dead.apexes[dead.count] =
                    face.iter().copied().find(|&x| x != r && x != k).expect("three distinct");
                dead.count += 1;
                alive[f] = false;
            } else {
                for v in face.iter_mut() {
                    if *v == r {
                        *v = k;
                    }
                }
            }
        }
        self.rewrite(k, r);
        for &o in &dead.apexes[..dead.count] {
            self.drop_dead(o);
        }
        self.live_faces -= dead.count;
        dead
    }

    /// Appends `keep`'s new list (its live faces, then `remove`'s) to `refs`.
    fn rewrite(&mut self, keep: u32, remove: u32) {
        if self.refs.len() > self.refs_limit {
            self.compact();
        }
        let start = self.refs.len();
        // Both runs copied whole, then the dead faces dropped from the copy in place:
        // pushing face by face read the `Vec` again at every one.
        for v in [keep, remove] {
            let s = self.start[v as usize] as usize;
            self.refs.extend_from_within(s..s + self.len[v as usize] as usize);
        }
        let live = keep_alive(&mut self.refs[start..], &self.alive);
        self.refs.truncate(start + live);
        self.start[keep as usize] = start as u32;
        self.len[keep as usize] = live as u32;
        self.len[remove as usize] = 0;
    }

    /// Removes dead faces from `v`'s list, in place.
    fn drop_dead(&mut self, v: u32) {
        let s = self.start[v as usize] as usize;
        let len = self.len[v as usize] as usize;
        self.len[v as usize] = keep_alive(&mut self.refs[s..s + len], &self.alive) as u32;
    }

    /// Copies every slot's run to the front, dropping abandoned runs.
    fn compact(&mut self) {
        let mut refs = Vec::with_capacity(self.refs_limit + 64);
        for v in 0..self.start.len() {
            let s = self.start[v] as usize;
            self.start[v] = refs.len() as u32;
            refs.extend_from_slice(&self.refs[s..s + self.len[v] as usize]);
        }
        self.refs_limit = (2 * refs.len()).max(self.refs_limit / 2) + 1024;
        refs.reserve(self.refs_limit + 64 - refs.len());
        self.refs = refs;
    }
}

/// Moves the live faces of `run` to its front, in order; returns how many there are.
/// On a slice, with `alive` borrowed apart from it: through `FaceLists` every `Vec` was
/// read again after each write.
#[inline]
fn keep_alive(run: &mut [u32], alive: &[bool]) -> usize {
    let mut live = 0;
    // Branch-free: every face is written at the cursor, which moves past the live
    // ones only (a dead face is a coin toss to the branch predictor).
    for i in 0..run.len() {
        let f = run[i];
        run[live] = f;
        live += usize::from(alive[f as usize]);
    }
    live
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing edge (1, 2): merging 2 into 1 kills both (both contain the
    /// edge), leaves 1's list empty of live faces and reports apexes 0 and 3.
    #[test]
    fn collapsing_the_shared_edge_kills_both_faces() {
        let mut lists = FaceLists::new(4, vec![[0, 1, 2], [2, 1, 3]]);
        let dead = lists.collapse(2, 1);
        assert_eq!((dead.count, dead.apexes), (2, [0, 3]));
        assert_eq!(lists.live_face_count(), 0);
        assert!(lists.of(1).is_empty() && lists.of(0).is_empty() && lists.of(3).is_empty());
    }

    /// A fan of three faces around 0; merging ring vertex 1 into ring vertex 2 kills face
    /// (0, 1, 2), re-points (0, 3, 1) to (0, 3, 2), and 2 inherits it.
    #[test]
    fn collapse_repoints_the_removed_vertex_faces() {
        let mut lists = FaceLists::new(4, vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]]);
        let dead = lists.collapse(1, 2);
        assert_eq!((dead.count, dead.apexes[0]), (1, 0));
        assert_eq!(lists.face(2), [0, 3, 2]);
        assert_eq!(lists.of(2), &[1, 2]);
        assert_eq!(lists.of(0), &[1, 2]);
        assert_eq!(lists.live().copied().collect::<Vec<_>>(), vec![[0, 2, 3], [0, 3, 2]]);
    }
}
