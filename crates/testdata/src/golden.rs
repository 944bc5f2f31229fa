//! Inputs and a hash for the stage crates' golden tests (`crates/<stage>/tests/golden.rs`)
//! (its tube also builds the end-to-end tests' pose set):
//! a small fixed body-like input and an FNV-1a hash of an output's exact bits. A golden
//! test fails when a stage's output changes, and its message says which `VERSION` to
//! bump (the driver's cache keys carry it).

use desal_mesh::{Face, PartLabels, PoseSet, TriMesh, Vec3};

/// The faces of an `nx × ny` grid of vertices (row by row, `x` fastest), two triangles
/// per square, all wound the same way: `2 (nx − 1)(ny − 1)` faces.
pub fn grid_faces(nx: u32, ny: u32) -> Vec<Face> {
    let mut faces = Vec::new();
    for j in 0..ny.saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            let v = j * nx + i;
            faces.push([v, v + 1, v + nx]);
            faces.push([v + 1, v + nx + 1, v + nx]);
        }
    }
    faces
}

/// A closed tube along +y, `rings` rings of `segments` vertices plus two cap centres,
/// with a slight deterministic wobble so no two edges cost exactly the same.
pub fn tube(rings: usize, segments: usize) -> TriMesh {
    tube_shaped(rings, segments, 0.01, 0.02)
}

/// A closed tube along +y (radius 0.1, rings 0.05 apart): `rings` rings of `segments`
/// vertices, each radius wobbled by up to `wobble` (deterministically), plus two cap
/// centres lifted `cap_lift` beyond the end rings. `tube_shaped(r, s, 0.0, 0.0)` is the
/// plain tube of the end-to-end tests.
pub fn tube_shaped(rings: usize, segments: usize, wobble: f64, cap_lift: f64) -> TriMesh {
    let mut positions = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = s as f64 / segments as f64 * std::f64::consts::TAU;
            let radius = 0.1 + wobble * ((r * 7 + s * 3) % 5) as f64 / 5.0;
            positions.push(Vec3::new(radius * a.cos(), r as f64 * 0.05, radius * a.sin()));
        }
    }
    let bottom = positions.len() as u32;
    positions.push(Vec3::new(0.0, 0.0 - cap_lift, 0.0));
    let top = positions.len() as u32;
    positions.push(Vec3::new(0.0, (rings - 1) as f64 * 0.05 + cap_lift, 0.0));
    let idx = |r: usize, s: usize| (r * segments + s % segments) as u32;
    let mut faces = Vec::new();
    for r in 0..rings - 1 {
        for s in 0..segments {
            faces.push([idx(r, s), idx(r + 1, s), idx(r + 1, s + 1)]);
            faces.push([idx(r, s), idx(r + 1, s + 1), idx(r, s + 1)]);
        }
    }
    for s in 0..segments {
        faces.push([bottom, idx(0, s), idx(0, s + 1)]);
        faces.push([top, idx(rings - 1, s + 1), idx(rings - 1, s)]);
    }
    TriMesh { positions, faces }
}

/// The tube (16 rings × 12) in four poses, its upper half bent about z by 0, 20, 45 and
/// 70 degrees with a bulge at the joint, and labelled as two parts (lower, upper).
pub fn bent_tube_pose_set() -> (PoseSet, PartLabels) {
    let mesh = tube(16, 12);
    let ymax = mesh.positions.iter().map(|p| p.y).fold(0.0, f64::max);
    let pivot = Vec3::new(0.0, ymax / 2.0, 0.0);
    let bend = |deg: f64| -> Vec<Vec3> {
        let (s, c) = deg.to_radians().sin_cos();
        mesh.positions
            .iter()
            .map(|p| {
                let near = (-((p.y - pivot.y) / 0.08).powi(2)).exp();
                let bulge = 1.0 + 0.15 * near * deg / 70.0;
                let q = Vec3::new(p.x * bulge, p.y, p.z * bulge);
                if q.y <= pivot.y {
                    return q;
                }
                let d = q - pivot;
                pivot + Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z)
            })
            .collect()
    };
    let angles = [0.0, 20.0, 45.0, 70.0];
    let names = angles.iter().map(|a| format!("bend{a}")).collect();
    let poses = angles.iter().map(|&a| bend(a)).collect();
    let set = PoseSet::try_new(names, poses, mesh.faces.clone(), 0).expect("a valid pose set");
    let labels = mesh.positions.iter().map(|p| u32::from(p.y > pivot.y)).collect();
    let labels = PartLabels::try_new(labels, vec!["lower".into(), "upper".into()]).expect("valid labels");
    (set, labels)
}

/// FNV-1a over a stream of 64-bit words (exact bits: `f64::to_bits`, indices as `u64`).
#[derive(Debug, Clone, Copy)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub fn word(&mut self, word: u64) -> &mut Self {
        for byte in word.to_le_bytes() {
            self.0 ^= u64::from(byte);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    pub fn f64s(&mut self, values: impl IntoIterator<Item = f64>) -> &mut Self {
        for v in values {
            self.word(v.to_bits());
        }
        self
    }

    pub fn points(&mut self, points: &[Vec3]) -> &mut Self {
        self.f64s(points.iter().flat_map(|p| [p.x, p.y, p.z]))
    }

    pub fn indices(&mut self, values: impl IntoIterator<Item = u32>) -> &mut Self {
        for v in values {
            self.word(u64::from(v));
        }
        self
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// Asserts a golden hash, naming the `VERSION` to bump when it changed.
pub fn assert_golden(stage: &str, version_const: &str, actual: u64, expected: u64) {
    assert_eq!(
        actual, expected,
        "{stage}'s output changed (hash {actual:#018x}, golden {expected:#018x}). If the change is intended, \
         bump `{version_const}` in the same commit (the cache keys carry it, so stale entries are not \
         served) and update this golden hash."
    );
}
