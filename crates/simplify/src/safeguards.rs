//! The safeguards a collapse must pass before it is performed, functions that only read
//! the [`Surface`]'s arrays: the seam rule (a seam vertex goes only along its seam, and no seam loop
//! shrinks below three edges), the link condition (no non-manifold edge, no pinched
//! boundary, no tetrahedral fan), and for every face that survives with a moved corner:
//! no degeneracy, no normal turned past the limit from before the collapse or from the
//! input, and the fold guard (no normal far from the input normals under its corners).

use desal_mesh::Vec3;

use crate::classify::{BOUNDARY, PINNED, SEAM};
use crate::config::Params;
use crate::face_lists::FaceLists;
use crate::marks::{Epoch, ScratchMarks};
use crate::report::Refusal;
use crate::seams::SeamGraph;
use crate::surface::Surface;

/// A new face with `2·area < DEGENERATE_RATIO · (longest edge)²` counts as degenerate
/// (a needle or cap flatter than one part in a million).
const DEGENERATE_RATIO: f64 = 1e-6;

/// All safeguards for collapsing `remove` into `keep` at `position`: the seam rule, the
/// link condition, then the geometry of every face that survives the collapse. `marks`
/// is scratch. Inlined by force into `try_collapse`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
pub(crate) fn check_collapse(
    s: &Surface,
    params: &Params,
    remove: u32,
    keep: u32,
    position: &Vec3,
    marks: &mut ScratchMarks,
) -> Result<(), Refusal> {
    check_seam_rule(s.seams.as_ref(), &s.flags, remove, keep)?;
    if !link_condition_holds(&s.lists, &s.flags, remove, keep, marks) {
        return Err(Refusal::Topology);
    }
    check_moved_faces(s, params, remove, keep, position)?;
    if *position != s.positions[keep as usize] {
        check_moved_faces(s, params, keep, remove, position)?;
    }
    Ok(())
}

/// The seam rule, meshoptimizer's `kCanCollapse` for the kinds a seam gives:
///
/// | remove \ keep | free | `SEAM` | `PINNED` |
/// |---|---|---|---|
/// | free | yes | yes | yes |
/// | `SEAM` | no | along a seam edge | along a seam edge |
/// | `PINNED` | no | no | no |
///
/// so a seam stays a polyline of edges and both its sides keep their faces. A `SEAM`
/// vertex leaving along its seam must also not fold a seam loop of three edges into
/// a doubled edge: its other seam neighbour may not already be a seam neighbour of
/// `keep`. Without seams, nothing is refused here.
pub(crate) fn check_seam_rule(
    seams: Option<&SeamGraph>,
    flags: &[u8],
    remove: u32,
    keep: u32,
) -> Result<(), Refusal> {
    let Some(seams) = seams else { return Ok(()) };
    if !seam_rule_lets_remove(Some(seams), flags, remove, keep) {
        return Err(Refusal::Seam);
    }
    if flags[remove as usize] & SEAM != 0
        && seams.of(remove).iter().any(|&other| other != keep && seams.joins(keep, other))
    {
        return Err(Refusal::Seam);
    }
    Ok(())
}

/// Whether the seam rule's table lets `remove` collapse onto its neighbour `keep`.
#[inline]
pub(crate) fn seam_rule_lets_remove(seams: Option<&SeamGraph>, flags: &[u8], remove: u32, keep: u32) -> bool {
    let flags = flags[remove as usize];
    if flags & PINNED != 0 {
        return false;
    }
    flags & SEAM == 0 || seams.is_some_and(|s| s.joins(remove, keep))
}

/// Whether edge `(a, b)` may collapse in at least one direction under the seam rule's
/// table (the ranking then keeps the endpoint that must stay).
#[inline]
pub(crate) fn seam_rule_allows_either(seams: Option<&SeamGraph>, flags: &[u8], a: u32, b: u32) -> bool {
    seam_rule_lets_remove(seams, flags, a, b) || seam_rule_lets_remove(seams, flags, b, a)
}

/// The link condition (Dey et al. 1999) in the form that matters for a 2-manifold
/// with boundary: the endpoints' common neighbours are exactly the apexes of the
/// faces on the edge; an interior edge does not join two boundary vertices (that
/// would pinch); and no apex is left with a degenerate fan (a closed fan of three
/// faces — the tetrahedron case — or a single boundary face). Inlined by force into
/// `try_collapse`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
pub(crate) fn link_condition_holds(
    lists: &FaceLists,
    flags: &[u8],
    a: u32,
    b: u32,
    marks: &mut ScratchMarks,
) -> bool {
    // `a`'s neighbours are marked, and the faces on the edge found, in one walk of
    // `a`'s faces.
    let of_a = marks.fresh();
    let mut apexes = [0u32; 2];
    let mut shared = 0;
    for &f in lists.of(a) {
        let face = lists.face(f);
        for x in face {
            marks.insert(x, of_a);
        }
        if face.contains(&b) {
            if shared == 2 {
                return false;
            }
            apexes[shared] = face.iter().copied().find(|&x| x != a && x != b).expect("three distinct");
            shared += 1;
        }
    }
    if shared == 0 || count_common_neighbours(lists, a, b, of_a, marks) != shared {
        return false;
    }
    let boundary = |v: u32| flags[v as usize] & BOUNDARY != 0;
    if shared == 2 && boundary(a) && boundary(b) {
        return false;
    }
    apexes[..shared].iter().all(|&o| {
        let fan = lists.count(o);
        if boundary(o) { fan >= 2 } else { fan >= 4 }
    })
}

/// The number of vertices adjacent to both `a` and `b`, `of_a` the set of `a`'s
/// neighbours (and `a`). Inlined by force into `try_collapse`'s clones
/// (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn count_common_neighbours(
    lists: &FaceLists,
    a: u32,
    b: u32,
    of_a: Epoch,
    marks: &mut ScratchMarks,
) -> usize {
    let counted = marks.fresh();
    let mut common = 0;
    for &f in lists.of(b) {
        for x in lists.face(f) {
            if x != a && x != b && marks.contains(x, of_a) {
                marks.insert(x, counted);
                common += 1;
            }
        }
    }
    common
}

/// Moving `moved` to `position` (merging it with `other`): refuse if any of its faces
/// not shared with `other` becomes degenerate, turns its normal past the threshold
/// from before the collapse or from the input (`Flip`), or ends up too far from the
/// input normals of the vertices at its corners (`Fold`, `max_corner_normal_deg`).
/// Inlined by force into `check_collapse` (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn check_moved_faces(
    s: &Surface,
    params: &Params,
    moved: u32,
    other: u32,
    position: &Vec3,
) -> Result<(), Refusal> {
    for &f in s.lists.of(moved) {
        let face = s.lists.face(f);
        if face.contains(&other) {
            continue;
        }
        // One slot count for positions and normals, so that one bounds check per
        // corner covers both.
        let p = &s.positions[..];
        let n = &s.vertex_normals[..p.len()];
        let [c0, c1, c2] = [p[face[0] as usize], p[face[1] as usize], p[face[2] as usize]];
        let old = (c1 - c0).cross(&(c2 - c0));
        // `moved` is exactly one corner: the face is in its list, and has three. The
        // substituted corners are chosen by a match, not written into an array at a
        // runtime index (which kept every corner on the stack).
        let at = face.iter().position(|&v| v == moved).expect("a face of `moved`");
        let (n0, n1, n2) = match at {
            0 => (*position, c1, c2),
            1 => (c0, *position, c2),
            _ => (c0, c1, *position),
        };
        let e0 = n1 - n0;
        let e1 = n2 - n0;
        let e2 = n2 - n1;
        let new = e0.cross(&e1);
        // The larger by a plain comparison, not `f64::max` (whose NaN handling costs
        // five instructions each). The two differ only when a squared length is NaN,
        // and then both refuse the face as degenerate: a NaN corner makes
        // `twice_area` NaN, and a NaN from `inf - inf` leaves another edge infinite
        // (so `f64::max` gives infinity) or every edge NaN.
        let larger = |x: f64, y: f64| if x > y { x } else { y };
        let longest_sq = larger(larger(e0.norm_squared(), e1.norm_squared()), e2.norm_squared());
        let twice_area = new.norm();
        // Written so that a NaN area is refused too.
        if twice_area.partial_cmp(&(DEGENERATE_RATIO * longest_sq)) != Some(std::cmp::Ordering::Greater) {
            return Err(Refusal::Degenerate);
        }
        let old_norm = old.norm();
        // A face that was already degenerate has no normal to compare with.
        if old_norm > 0.0 && new.dot(&old) <= params.cos_max_rotation * old_norm * twice_area {
            return Err(Refusal::Flip);
        }
        let input = &s.input_normals[f as usize];
        if new.dot(input) <= params.cos_max_rotation * input.norm() * twice_area {
            return Err(Refusal::Flip);
        }
        // The corners' input normals summed, `moved`'s counting for both merged
        // vertices (only the sign of a zero sum differs from starting at zero, and
        // the comparison below cannot see it).
        let [m0, m1, m2] = [n[face[0] as usize], n[face[1] as usize], n[face[2] as usize]];
        let reference = match at {
            0 => (m0 + n[other as usize]) + m1 + m2,
            1 => m0 + (m1 + n[other as usize]) + m2,
            _ => m0 + m1 + (m2 + n[other as usize]),
        };
        if new.dot(&reference) <= params.cos_max_corner_normal * reference.norm() * twice_area {
            return Err(Refusal::Fold);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use desal_mesh::TriMesh;

    use super::*;
    use crate::config::SimplifyConfig;

    /// A flat hexagonal fan: centre 0 at the origin, ring 1..=6 at unit distance.
    fn hexagon_fan() -> TriMesh {
        let mut positions = vec![Vec3::zeros()];
        positions.extend((0..6).map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 6.0;
            Vec3::new(t.cos(), t.sin(), 0.0)
        }));
        let faces = (0..6u32).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        TriMesh { positions, faces }
    }

    fn surface_for(mesh: &TriMesh, config: &SimplifyConfig) -> (Surface, Params, ScratchMarks) {
        let input = crate::SimplifyInput::new(mesh);
        let surface = Surface::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), config);
        let marks = ScratchMarks::new(mesh.positions.len());
        (surface, Params::new(config, 1), marks)
    }

    /// Collapsing ring vertex 1 into the centre while moving the centre past the
    /// opposite side of the ring turns the far faces over: refused as a flip. The same
    /// collapse onto the centre's own position is accepted.
    #[test]
    fn collapse_that_flips_a_face_is_refused() {
        let (s, params, mut marks) = surface_for(&hexagon_fan(), &SimplifyConfig::default());
        let flipping = Vec3::new(-1.5, 0.0, 0.0);
        assert_eq!(check_collapse(&s, &params, 1, 0, &flipping, &mut marks), Err(Refusal::Flip));
        assert_eq!(check_collapse(&s, &params, 1, 0, &Vec3::zeros(), &mut marks), Ok(()));
    }

    /// With the per-face limits off (180°), lifting the centre of a flat fan (ring
    /// radius 1, so each ring edge is 0.866 from the centre) by 1.5 tilts each surviving
    /// face by atan(1.5 / 0.866) = 60°, inside the fold guard's 70° of its corners' input
    /// normals (+z): accepted. Lifting it by 3 tilts them by 74°: refused as a fold, not
    /// as a flip.
    #[test]
    fn fold_guard_refuses_on_its_own() {
        let config = SimplifyConfig { max_normal_rotation_deg: 180.0, ..SimplifyConfig::default() };
        let (s, params, mut marks) = surface_for(&hexagon_fan(), &config);
        let mut lifted = |h: f64| check_collapse(&s, &params, 1, 0, &Vec3::new(0.0, 0.0, h), &mut marks);
        assert_eq!(lifted(1.5), Ok(()));
        assert_eq!(lifted(3.0), Err(Refusal::Fold));
    }

    /// Moving the centre exactly onto the line through two ring vertices flattens the
    /// face between them to zero area: refused as degenerate.
    #[test]
    fn collapse_that_degenerates_a_face_is_refused() {
        let (s, params, mut marks) = surface_for(&hexagon_fan(), &SimplifyConfig::default());
        // Face (0, 3, 4): ring 3 and 4 lie at 120° and 180°; their midpoint line.
        let (p3, p4) = (s.positions[3], s.positions[4]);
        let on_line = p3 + (p4 - p3) * 0.5;
        assert_eq!(check_collapse(&s, &params, 1, 0, &on_line, &mut marks), Err(Refusal::Degenerate));
    }

    /// The seam rule on the flat hexagonal fan with a seam 1–0–4 through the centre:
    /// the centre (two seam edges, not on the boundary) may go along the seam onto 1 but
    /// not onto 2; ring vertex 1 ends the seam, so it is locked and the collapse of edge
    /// (1, 2) must keep it; ring vertex 2 is off the seam and goes anywhere.
    #[test]
    fn a_seam_vertex_goes_only_along_its_seam() {
        let mesh = hexagon_fan();
        let seams = [[1, 0], [0, 4]];
        let input = crate::SimplifyInput::new(&mesh).with_seams(&seams);
        let config = SimplifyConfig::default();
        let s = Surface::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), &config);
        let rule = |remove, keep| check_seam_rule(s.seams.as_ref(), &s.flags, remove, keep);
        assert_eq!(rule(0, 1), Ok(()));
        assert_eq!(rule(0, 2), Err(Refusal::Seam));
        assert_eq!(rule(1, 2), Err(Refusal::Seam));
        assert_eq!(rule(2, 1), Ok(()));
        assert_eq!(rule(2, 0), Ok(()));
    }

    /// The link condition: in a closed octahedron every edge may collapse (apexes keep
    /// fans of four), but once a vertex has valence 3 its edges may not.
    #[test]
    fn link_condition_refuses_tetrahedral_fans() {
        let tetra = TriMesh {
            positions: vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()],
            faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        };
        let (s, _, mut marks) = surface_for(&tetra, &SimplifyConfig::default());
        assert!(!link_condition_holds(&s.lists, &s.flags, 0, 1, &mut marks));
        let octahedron = TriMesh {
            positions: vec![Vec3::x(), -Vec3::x(), Vec3::y(), -Vec3::y(), Vec3::z(), -Vec3::z()],
            faces: vec![
                [0, 2, 4],
                [2, 1, 4],
                [1, 3, 4],
                [3, 0, 4],
                [2, 0, 5],
                [1, 2, 5],
                [3, 1, 5],
                [0, 3, 5],
            ],
        };
        let (s, _, mut marks) = surface_for(&octahedron, &SimplifyConfig::default());
        assert!(link_condition_holds(&s.lists, &s.flags, 0, 4, &mut marks));
    }
}
