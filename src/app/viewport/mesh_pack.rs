//! The robot's meshes packed for the GPU: every distinct mesh once, all of them in one vertex and one
//! index buffer, each mesh an index range. Each mesh's vertex offset is baked into its indices, so a
//! draw never needs a base vertex (WebGL2 has none) and one index buffer serves every mesh.
//!
//! Packing (on the mesh task's thread, never the UI's) also **welds** each mesh: the loaders hand over
//! three vertices per triangle (STL has no shared vertices), and the vertex shader would run three
//! times per triangle. Corners at the same position whose faces meet at less than
//! [`CREASE_ANGLE_DEG`] share one vertex with the area-weighted mean normal (curved CAD surfaces are
//! shaded smooth), sharper edges keep one vertex per side (they stay sharp).

use super::primitives::MeshVertex;
use crate::meshes::{GeometryKind, MeshSet, TriangleMesh, lod};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

/// Faces meeting at less than this are shaded as one smooth surface.
pub const CREASE_ANGLE_DEG: f32 = 35.0;

/// Which mesh of which set: `(kind, filename as written, scale bits)` — [`MeshSet`]'s key with the
/// geometry kind.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct MeshKey {
    pub kind: GeometryKind,
    pub filename: String,
    pub scale_bits: [u64; 3],
}

impl MeshKey {
    pub fn new(kind: GeometryKind, filename: &str, scale: [f64; 3]) -> Self {
        Self {
            kind,
            filename: filename.to_string(),
            scale_bits: scale.map(f64::to_bits),
        }
    }
}

/// Every mesh of a robot in one vertex and one index buffer (positions in metres).
#[derive(Debug, Default)]
pub struct PackedMeshes {
    /// Tells one pack from another (the GPU uploads a pack once).
    pub id: u64,
    pub vertices: Vec<MeshVertex>,
    /// Indices into `vertices` (offsets baked in).
    pub indices: Vec<u32>,
    /// Each mesh's range of `indices`.
    pub ranges: Vec<Range<u32>>,
    keys: HashMap<MeshKey, u32>,
    /// Triangles of the meshes as loaded (before welding; the same after).
    pub triangles: usize,
}

static NEXT_PACK_ID: AtomicU64 = AtomicU64::new(1);

impl PackedMeshes {
    /// Pack `meshes` (each once), welding each one.
    pub fn pack<'a>(meshes: impl IntoIterator<Item = (MeshKey, &'a TriangleMesh)>) -> Self {
        Self::from_welded(weld_distinct(meshes))
    }

    /// Pack `meshes` (each once) as [`pack`](Self::pack) does, and a second pack of the same meshes
    /// simplified together to about `robot_triangles` triangles ([`crate::meshes::lod`]; the same
    /// keys and mesh indices). The second is `None` where this build has no simplifier (the
    /// browser).
    pub fn pack_with_lod<'a>(
        meshes: impl IntoIterator<Item = (MeshKey, &'a TriangleMesh)>,
        robot_triangles: usize,
    ) -> (Self, Option<Self>) {
        let welded = weld_distinct(meshes);
        let simplified = lod::available()
            .then(|| {
                let counts: Vec<usize> = welded.iter().map(|w| w.indices.len() / 3).collect();
                let budgets = lod::budgets(&counts, robot_triangles);
                welded
                    .iter()
                    .zip(budgets)
                    .map(|(w, budget)| {
                        let positions: Vec<[f32; 3]> =
                            w.vertices.iter().map(|v| v.position).collect();
                        let mut indices =
                            lod::simplify(&positions, &w.indices, budget, lod::MAX_RELATIVE_ERROR)?;
                        let vertices = lod::compact(&w.vertices, &mut indices);
                        Some(Welded {
                            key: w.key.clone(),
                            vertices,
                            triangles: indices.len() / 3,
                            indices,
                        })
                    })
                    .collect::<Option<Vec<_>>>()
            })
            .flatten()
            .map(Self::from_welded);
        (Self::from_welded(welded), simplified)
    }

    fn from_welded(welded: Vec<Welded>) -> Self {
        let mut pack = Self {
            id: NEXT_PACK_ID.fetch_add(1, Ordering::Relaxed),
            ..Default::default()
        };
        for w in welded {
            let offset = pack.vertices.len() as u32;
            let start = pack.indices.len() as u32;
            pack.vertices.extend(w.vertices);
            pack.indices.extend(w.indices.iter().map(|i| i + offset));
            pack.ranges.push(start..pack.indices.len() as u32);
            pack.triangles += w.triangles;
            pack.keys.insert(w.key, pack.ranges.len() as u32 - 1);
        }
        pack
    }

    /// Pack every mesh of the given sets.
    pub fn pack_sets(sets: &[(GeometryKind, &MeshSet)]) -> Self {
        Self::pack(sets.iter().flat_map(|(kind, set)| {
            set.meshes
                .iter()
                .map(move |((filename, scale_bits), mesh)| {
                    (
                        MeshKey {
                            kind: *kind,
                            filename: filename.clone(),
                            scale_bits: *scale_bits,
                        },
                        &**mesh,
                    )
                })
        }))
    }

    /// The index of a mesh in [`ranges`](Self::ranges), if it is in the pack.
    pub fn index_of(&self, kind: GeometryKind, filename: &str, scale: [f64; 3]) -> Option<u32> {
        self.keys.get(&MeshKey::new(kind, filename, scale)).copied()
    }

    pub fn mesh_count(&self) -> usize {
        self.ranges.len()
    }
}

/// One distinct mesh, welded.
struct Welded {
    key: MeshKey,
    vertices: Vec<MeshVertex>,
    indices: Vec<u32>,
    /// Triangles of the mesh as loaded (the welded mesh has as many).
    triangles: usize,
}

/// Weld each distinct mesh once, in order of first appearance.
fn weld_distinct<'a>(meshes: impl IntoIterator<Item = (MeshKey, &'a TriangleMesh)>) -> Vec<Welded> {
    let cos_crease = CREASE_ANGLE_DEG.to_radians().cos();
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for (key, mesh) in meshes {
        if !seen.insert(key.clone()) {
            continue;
        }
        let (vertices, indices) = weld(mesh, cos_crease);
        out.push(Welded {
            key,
            vertices,
            indices,
            triangles: mesh.triangle_count(),
        });
    }
    out
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalized(v: [f32; 3]) -> Option<[f32; 3]> {
    let len = dot(v, v).sqrt();
    (len > 0.0 && len.is_finite()).then(|| v.map(|c| c / len))
}

/// Weld a mesh: one vertex per (position, smoothing group), normals the area-weighted mean of the
/// faces within the crease angle of the corner's face. Degenerate triangles (no area) keep the mesh's
/// own normals and are not welded.
fn weld(mesh: &TriangleMesh, cos_crease: f32) -> (Vec<MeshVertex>, Vec<u32>) {
    let p = &mesh.positions_m;
    let triangles: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    // Area-weighted face normals (the cross product's length is twice the area).
    let face: Vec<([f32; 3], Option<[f32; 3]>)> = triangles
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
            let n = cross(sub(b, a), sub(c, a));
            (n, normalized(n))
        })
        .collect();
    // The triangles with a corner at each position.
    let mut at: HashMap<[u32; 3], Vec<u32>> = HashMap::with_capacity(p.len());
    for (t, tri) in triangles.iter().enumerate() {
        for &i in tri {
            at.entry(p[i as usize].map(f32::to_bits))
                .or_default()
                .push(t as u32);
        }
    }
    let mut vertices: Vec<MeshVertex> = Vec::with_capacity(p.len() / 2);
    let mut indices = vec![0u32; triangles.len() * 3];
    let mut unique: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::with_capacity(p.len() / 2);
    // In triangle order, so the pack is the same on every run.
    for (t, tri) in triangles.iter().enumerate() {
        for (k, &i) in tri.iter().enumerate() {
            let i = i as usize;
            let bits = p[i].map(f32::to_bits);
            let normal = match face[t].1 {
                Some(own) => {
                    // Faces at this position within the crease angle of this one.
                    let mut sum = [0.0f32; 3];
                    for &u in &at[&bits] {
                        if let (weighted, Some(n)) = face[u as usize]
                            && dot(n, own) >= cos_crease
                        {
                            sum = [
                                sum[0] + weighted[0],
                                sum[1] + weighted[1],
                                sum[2] + weighted[2],
                            ];
                        }
                    }
                    normalized(sum).unwrap_or(own)
                }
                None => mesh.normals[i],
            };
            // Corners whose normals come out equal share a vertex.
            let index = *unique
                .entry((bits, normal.map(f32::to_bits)))
                .or_insert_with(|| {
                    vertices.push(MeshVertex {
                        position: p[i],
                        normal,
                    });
                    vertices.len() as u32 - 1
                });
            indices[3 * t + k] = index;
        }
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube as twelve unshared triangles (as an STL loads) and a flat fan of four triangles.
    fn cube() -> TriangleMesh {
        let c = |i: usize| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32];
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut mesh = TriangleMesh::default();
        for q in quads {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let [a, b, c3] = tri.map(c);
                let n = normalized(cross(sub(b, a), sub(c3, a))).unwrap();
                let base = mesh.positions_m.len() as u32;
                mesh.positions_m.extend([a, b, c3]);
                mesh.normals.extend([n; 3]);
                mesh.indices.extend([base, base + 1, base + 2]);
            }
        }
        mesh
    }

    #[test]
    fn a_cube_keeps_sharp_edges_and_shares_vertices_within_a_face() {
        let mesh = cube();
        assert_eq!(mesh.positions_m.len(), 36);
        let (vertices, indices) = weld(&mesh, CREASE_ANGLE_DEG.to_radians().cos());
        // 90° edges are creases: 4 vertices per face.
        assert_eq!(vertices.len(), 24);
        assert_eq!(indices.len(), 36);
        // Every triangle keeps its corners' positions, and its normal is its face's.
        for (t, tri) in indices.chunks_exact(3).enumerate() {
            for k in 0..3 {
                let v = vertices[tri[k] as usize];
                assert_eq!(v.position, mesh.positions_m[3 * t + k]);
                assert_eq!(v.normal, mesh.normals[3 * t + k]);
            }
        }
    }

    #[test]
    fn a_shallow_fold_is_shaded_smooth() {
        // Two triangles meeting at 10° along the edge (0,0,0)–(0,1,0).
        let s = 10f32.to_radians();
        let mesh = TriangleMesh {
            positions_m: vec![
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0],
                [s.cos(), 0.0, s.sin()],
                [0.0, 1.0, 0.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 6],
            indices: vec![0, 1, 2, 3, 4, 5],
        };
        let (vertices, indices) = weld(&mesh, CREASE_ANGLE_DEG.to_radians().cos());
        assert_eq!(
            vertices.len(),
            4,
            "the shared edge's two vertices are welded"
        );
        assert_eq!(indices[0], indices[3]);
        let shared = vertices[indices[0] as usize].normal;
        assert!(shared[0] < 0.0 && shared[2] > 0.99, "{shared:?}");
    }

    #[test]
    fn offsets_are_baked_into_the_indices_and_each_mesh_is_packed_once() {
        let a = cube();
        let mut b = cube();
        for p in &mut b.positions_m {
            p[0] += 5.0;
        }
        let key = |name: &str| MeshKey::new(GeometryKind::Visual, name, [1.0; 3]);
        let pack = PackedMeshes::pack([(key("a"), &a), (key("b"), &b), (key("a"), &a)]);
        assert_eq!(pack.mesh_count(), 2);
        assert_eq!(pack.triangles, 24);
        let ib = pack.index_of(GeometryKind::Visual, "b", [1.0; 3]).unwrap();
        assert_eq!(
            pack.index_of(GeometryKind::Collision, "b", [1.0; 3]),
            None,
            "the geometry kind is part of the key"
        );
        // Mesh b's indices point at b's vertices (x ≥ 5) without a base vertex.
        let range = pack.ranges[ib as usize].clone();
        assert_eq!(range.len(), 36);
        for &i in &pack.indices[range.start as usize..range.end as usize] {
            assert!(pack.vertices[i as usize].position[0] >= 5.0);
        }
        assert!(
            pack.indices
                .iter()
                .all(|&i| (i as usize) < pack.vertices.len())
        );
        let other = PackedMeshes::pack([(key("a"), &a)]);
        assert_ne!(pack.id, other.id);
    }

    /// A UV sphere as an STL loads it (three unshared corners per triangle).
    fn sphere(rings: u32, segments: u32) -> TriangleMesh {
        let point = |i: u32, j: u32| {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]
        };
        let mut mesh = TriangleMesh::default();
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (
                    point(i, j),
                    point(i, j + 1),
                    point(i + 1, j),
                    point(i + 1, j + 1),
                );
                for tri in [[a, c, b], [b, c, d]] {
                    let Some(n) = normalized(cross(sub(tri[1], tri[0]), sub(tri[2], tri[0])))
                    else {
                        continue;
                    };
                    let base = mesh.positions_m.len() as u32;
                    mesh.positions_m.extend(tri);
                    mesh.normals.extend([n; 3]);
                    mesh.indices.extend([base, base + 1, base + 2]);
                }
            }
        }
        mesh
    }

    #[test]
    fn the_simplified_copy_has_the_same_meshes_with_fewer_triangles_and_the_full_pack_is_untouched()
    {
        let fine = sphere(80, 160);
        let small = cube();
        let key = |name: &str| MeshKey::new(GeometryKind::Visual, name, [1.0; 3]);
        let meshes = || [(key("fine"), &fine), (key("small"), &small)];
        let (full, simplified) = PackedMeshes::pack_with_lod(meshes(), 2_000);
        let plain = PackedMeshes::pack(meshes());
        // Full mode: exactly what packing alone gives.
        assert_eq!(full.indices, plain.indices);
        assert_eq!(full.ranges, plain.ranges);
        assert_eq!(full.triangles, plain.triangles);
        assert_eq!(full.vertices.len(), plain.vertices.len());
        let simplified = simplified.expect("a simplifier in native builds");
        assert_ne!(simplified.id, full.id);
        for name in ["fine", "small"] {
            assert_eq!(
                simplified.index_of(GeometryKind::Visual, name, [1.0; 3]),
                full.index_of(GeometryKind::Visual, name, [1.0; 3])
            );
        }
        let fine_range = |p: &PackedMeshes| p.ranges[0].len() / 3;
        assert!(fine_range(&full) > 20_000);
        assert!(
            fine_range(&simplified) <= 2_000 && fine_range(&simplified) > 200,
            "{} triangles",
            fine_range(&simplified)
        );
        // The cube (12 triangles) is under its minimum budget: kept whole.
        assert_eq!(simplified.ranges[1].len(), 36);
        assert_eq!(simplified.triangles, simplified.indices.len() / 3);
        assert!(simplified.vertices.len() < full.vertices.len() / 5);
        assert!(
            simplified
                .indices
                .iter()
                .all(|&i| (i as usize) < simplified.vertices.len())
        );
        // Every vertex drawn is one of the full mesh's (none moved): still on the unit sphere.
        for &i in &simplified.indices
            [simplified.ranges[0].start as usize..simplified.ranges[0].end as usize]
        {
            let p = simplified.vertices[i as usize].position;
            assert!((dot(p, p).sqrt() - 1.0).abs() < 1e-5);
        }
    }
}
