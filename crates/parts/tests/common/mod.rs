//! Checks shared by the test binaries on real data: the structural guarantees of
//! `discover_parts`, verified independently of the crate's own graph code.

use desal_mesh::{EdgeTopology, PartLabels, PoseSet};

/// Every part is one connected patch on the mesh's edges and the part graph (parts
/// adjacent when an edge joins them) is connected; panics naming the first failure.
pub fn assert_connected_parts(poses: &PoseSet, labels: &PartLabels) {
    let n = poses.vertex_count();
    let edges = EdgeTopology::new(&poses.faces).edges;
    // Union-find over same-part edges: one root per part means every part is connected.
    let mut root: Vec<usize> = (0..n).collect();
    fn find(root: &mut [usize], mut x: usize) -> usize {
        while root[x] != x {
            root[x] = root[root[x]];
            x = root[x];
        }
        x
    }
    let mut part_root: Vec<usize> = (0..labels.part_count()).collect();
    for &[a, b] in &edges {
        let (a, b) = (a as usize, b as usize);
        let (pa, pb) = (labels.labels[a] as usize, labels.labels[b] as usize);
        if pa == pb {
            let (ra, rb) = (find(&mut root, a), find(&mut root, b));
            root[rb] = ra;
        } else {
            let (ra, rb) = (find(&mut part_root, pa), find(&mut part_root, pb));
            part_root[rb] = ra;
        }
    }
    for (part, members) in labels.members().iter().enumerate() {
        let first = find(&mut root, members[0] as usize);
        for &v in members {
            assert_eq!(find(&mut root, v as usize), first, "part {part} is not connected (vertex {v})");
        }
    }
    let first = find(&mut part_root, 0);
    for part in 0..labels.part_count() {
        assert_eq!(find(&mut part_root, part), first, "the part graph is not connected (part {part})");
    }
}
