//! Simplified copies of meshes (a level of detail) for drawing where triangles are dear: software
//! renderers such as Mesa's lavapipe. Only the viewport draws them; collision checks and exports keep
//! the full meshes.
//!
//! The simplifier is meshoptimizer's (the `meshopt` crate): edge collapses ordered by quadric error,
//! each collapse moving a vertex onto another one, so a copy uses a subset of its mesh's vertices —
//! nothing moves out of the mesh's bounding box — and vertices split for sharp creases stay split
//! (attribute seams are kept). It is C++, built with the system's C++ compiler; for the browser
//! (wasm32-unknown-unknown) it would need clang's wasm target and a C++ runtime, so there
//! [`simplify`] returns `None` and the full meshes are drawn.

/// Triangles a whole robot's distinct meshes are simplified to, together.
pub const ROBOT_TRIANGLES: usize = 20_000;

/// A mesh is not simplified below this many triangles (small parts stay recognisable).
pub const MIN_MESH_TRIANGLES: usize = 300;

/// The largest deviation a simplification may introduce, relative to the mesh's extent (its
/// bounding box's largest side): 2% of a 20 cm link is 4 mm.
pub const MAX_RELATIVE_ERROR: f32 = 0.02;

/// Whether this build has a simplifier (not in the browser).
pub const fn available() -> bool {
    cfg!(not(target_arch = "wasm32"))
}

/// Each mesh's triangle budget: its share of `total` in proportion to its size, at least
/// [`MIN_MESH_TRIANGLES`], never more than it has.
pub fn budgets(triangles: &[usize], total: usize) -> Vec<usize> {
    let sum: usize = triangles.iter().sum();
    if sum <= total {
        return triangles.to_vec();
    }
    let ratio = total as f64 / sum as f64;
    triangles
        .iter()
        .map(|&n| {
            ((n as f64 * ratio).ceil() as usize)
                .max(MIN_MESH_TRIANGLES)
                .min(n)
        })
        .collect()
}

/// Simplify an indexed triangle list over `positions` towards `target_triangles`, stopping where a
/// collapse would deviate more than `max_relative_error` of the mesh's extent. Returns triangle
/// indices into the same `positions` (a mesh already within its budget comes back unchanged), or
/// `None` in a build without a simplifier.
#[cfg(not(target_arch = "wasm32"))]
pub fn simplify(
    positions: &[[f32; 3]],
    indices: &[u32],
    target_triangles: usize,
    max_relative_error: f32,
) -> Option<Vec<u32>> {
    if indices.len() / 3 <= target_triangles {
        return Some(indices.to_vec());
    }
    let simplified = meshopt::simplify_decoder(
        indices,
        positions,
        target_triangles * 3,
        max_relative_error,
        meshopt::SimplifyOptions::None,
        None,
    );
    Some(simplified)
}

/// Without a simplifier (the browser): `None`, the full mesh is drawn.
#[cfg(target_arch = "wasm32")]
pub fn simplify(
    _positions: &[[f32; 3]],
    _indices: &[u32],
    _target_triangles: usize,
    _max_relative_error: f32,
) -> Option<Vec<u32>> {
    None
}

/// Keep only the vertices `indices` use (in order of first use) and renumber `indices` to them.
pub fn compact<T: Clone>(vertices: &[T], indices: &mut [u32]) -> Vec<T> {
    let mut remap = vec![u32::MAX; vertices.len()];
    let mut kept = Vec::new();
    for i in indices.iter_mut() {
        let slot = &mut remap[*i as usize];
        if *slot == u32::MAX {
            *slot = kept.len() as u32;
            kept.push(vertices[*i as usize].clone());
        }
        *i = *slot;
    }
    kept
}

/// The axis-aligned bounding box of the vertices `indices` use: `(min, max)`.
pub fn bounds(positions: &[[f32; 3]], indices: &[u32]) -> Option<([f32; 3], [f32; 3])> {
    let mut it = indices.iter().map(|&i| positions[i as usize]);
    let first = it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| {
        (
            [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
            [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
        )
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A UV sphere of radius `r` centred at `c` with shared vertices: `2 · rings · segments`
    /// triangles (poles as fans).
    fn sphere(c: [f32; 3], r: f32, rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let mut positions = vec![[c[0], c[1], c[2] + r]];
        for i in 1..rings {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segments {
                let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                positions.push([
                    c[0] + r * theta.sin() * phi.cos(),
                    c[1] + r * theta.sin() * phi.sin(),
                    c[2] + r * theta.cos(),
                ]);
            }
        }
        positions.push([c[0], c[1], c[2] - r]);
        let south = positions.len() as u32 - 1;
        let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let mut indices = Vec::new();
        for j in 0..segments {
            indices.extend([0, at(1, j), at(1, j + 1)]);
            indices.extend([south, at(rings - 1, j + 1), at(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..segments {
                let (a, b, c2, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
                indices.extend([a, c2, b, b, c2, d]);
            }
        }
        (positions, indices)
    }

    #[test]
    fn budgets_share_the_total_in_proportion_and_keep_small_meshes() {
        assert_eq!(budgets(&[100, 200], 1000), vec![100, 200], "within budget");
        let b = budgets(&[100_000, 50_000, 200], 15_000);
        assert!((9_980..=10_000).contains(&b[0]), "{b:?}");
        assert!((4_990..=5_000).contains(&b[1]), "{b:?}");
        assert_eq!(b[2], 200, "never below the minimum, never above the mesh");
        assert_eq!(budgets(&[100_000, 1_000], 10_000)[1], MIN_MESH_TRIANGLES);
    }

    #[cfg(not(target_arch = "wasm32"))]
    #[test]
    fn a_fine_sphere_is_reduced_and_keeps_its_bounding_box() {
        let (positions, indices) = sphere([0.1, -0.2, 0.3], 0.05, 100, 200);
        let full = indices.len() / 3;
        assert!(full > 39_000);
        let simplified = simplify(&positions, &indices, 2_000, MAX_RELATIVE_ERROR).unwrap();
        let n = simplified.len() / 3;
        assert!((500..=2_000).contains(&n), "{n} triangles of {full}");
        assert!(simplified.iter().all(|&i| (i as usize) < positions.len()));
        // The bounding box within 2% of the extent (0.1 m) of the full one.
        let (lo, hi) = bounds(&positions, &indices).unwrap();
        let (slo, shi) = bounds(&positions, &simplified).unwrap();
        for k in 0..3 {
            assert!(slo[k] >= lo[k] - 1e-6 && shi[k] <= hi[k] + 1e-6, "inside");
            assert!((slo[k] - lo[k]).abs() <= 0.002, "{k}: {slo:?} vs {lo:?}");
            assert!((shi[k] - hi[k]).abs() <= 0.002, "{k}: {shi:?} vs {hi:?}");
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    #[test]
    fn a_mesh_within_its_budget_is_untouched() {
        let (positions, indices) = sphere([0.0; 3], 1.0, 10, 20);
        let same = simplify(&positions, &indices, indices.len() / 3, 0.5).unwrap();
        assert_eq!(same, indices);
    }

    #[test]
    fn compacting_keeps_only_used_vertices_in_order_of_use() {
        let vertices = ['a', 'b', 'c', 'd', 'e'];
        let mut indices = vec![4, 2, 0, 2, 4, 0];
        let kept = compact(&vertices, &mut indices);
        assert_eq!(kept, vec!['e', 'c', 'a']);
        assert_eq!(indices, vec![0, 1, 2, 1, 0, 2]);
    }
}
