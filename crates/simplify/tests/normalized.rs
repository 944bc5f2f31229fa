//! `SimplifyConfig::normalized_error`: ranking collapses by quadric error per unit area
//! (meshoptimizer's normalisation) spends the budget where the surface curves, not where
//! it is large. On two spheres of radius 1 and 3 with the same tessellation, the
//! Garland–Heckbert sum (area × squared distance, ∝ r⁴) keeps most vertices on the big
//! sphere; per unit area (∝ r²) the split moves towards the small one.

use desal_mesh::{TriMesh, Vec3};
use desal_simplify::{Placement, SimplifyConfig, SimplifyInput, Target, simplify};

/// A UV sphere of `radius` around `center`: `rings` latitude bands, `segments` around.
fn sphere(center: Vec3, radius: f64, rings: usize, segments: usize, mesh: &mut TriMesh) {
    let base = mesh.positions.len() as u32;
    mesh.positions.push(center + Vec3::new(0.0, 0.0, radius));
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
            mesh.positions.push(
                center + radius * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()),
            );
        }
    }
    mesh.positions.push(center + Vec3::new(0.0, 0.0, -radius));
    let south = mesh.positions.len() as u32 - 1;
    let ring = |r: usize, s: usize| base + 1 + ((r - 1) * segments + s % segments) as u32;
    for s in 0..segments {
        mesh.faces.push([base, ring(1, s), ring(1, s + 1)]);
        mesh.faces.push([south, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            mesh.faces.push([ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)]);
            mesh.faces.push([ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)]);
        }
    }
}

/// Kept vertices on the big sphere (x > 5), for each placement and error.
fn kept_on_big(normalized_error: bool, placement: Placement) -> (usize, usize) {
    let mut mesh = TriMesh { positions: Vec::new(), faces: Vec::new() };
    sphere(Vec3::zeros(), 1.0, 16, 24, &mut mesh);
    sphere(Vec3::new(10.0, 0.0, 0.0), 3.0, 16, 24, &mut mesh);
    let config = SimplifyConfig {
        target: Target::Vertices(120),
        placement,
        normalized_error,
        ..SimplifyConfig::qslim(Target::Vertices(120))
    };
    let out = simplify(&SimplifyInput::new(&mesh), &config).unwrap();
    assert_eq!(out.mesh.positions.len(), 120);
    (out.mesh.positions.iter().filter(|p| p.x > 5.0).count(), out.mesh.positions.len())
}

#[test]
fn normalised_error_moves_the_budget_from_the_large_sphere_to_the_small_one() {
    for placement in [Placement::Subset, Placement::Optimal] {
        let (plain, total) = kept_on_big(false, placement);
        let (normalised, _) = kept_on_big(true, placement);
        assert!(
            plain > total / 2,
            "{placement:?}: the area-weighted sum favours the big sphere: {plain} of {total}"
        );
        assert!(
            normalised + 5 < plain,
            "{placement:?}: per unit area, fewer on the big sphere: {normalised} vs {plain} of {total}"
        );
    }
}

/// Off by default: the paper's Garland–Heckbert error.
#[test]
fn normalised_error_is_off_by_default() {
    assert!(!SimplifyConfig::default().normalized_error);
}
