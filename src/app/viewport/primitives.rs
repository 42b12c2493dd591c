//! The unit primitives the mesh pipeline instances: cube [-1, 1]³, cylinder and sphere of radius 1.

/// A vertex of a unit primitive (`mesh.wgsl` locations 0 and 1).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

/// Cube [-1, 1]³ with flat normals.
pub fn unit_box() -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::with_capacity(24);
    let mut i = Vec::with_capacity(36);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = v.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[u_axis] = su;
                p[v_axis] = sv;
                v.push(MeshVertex {
                    position: p,
                    normal: n,
                });
            }
            i.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    (v, i)
}

/// Cylinder of radius 1 from z = -1 to z = 1, with caps.
pub fn unit_cylinder(segments: u32) -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    for k in 0..=segments {
        let a = k as f32 / segments as f32 * std::f32::consts::TAU;
        let (s, c) = a.sin_cos();
        v.push(MeshVertex {
            position: [c, s, -1.0],
            normal: [c, s, 0.0],
        });
        v.push(MeshVertex {
            position: [c, s, 1.0],
            normal: [c, s, 0.0],
        });
    }
    for k in 0..segments {
        let b = 2 * k;
        i.extend([b, b + 2, b + 1, b + 1, b + 2, b + 3]);
    }
    for z in [-1.0f32, 1.0] {
        let centre = v.len() as u32;
        v.push(MeshVertex {
            position: [0.0, 0.0, z],
            normal: [0.0, 0.0, z],
        });
        for k in 0..=segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            v.push(MeshVertex {
                position: [c, s, z],
                normal: [0.0, 0.0, z],
            });
        }
        for k in 0..segments {
            i.extend([centre, centre + 1 + k, centre + 2 + k]);
        }
    }
    (v, i)
}

/// Sphere of radius 1 (latitude/longitude grid).
pub fn unit_sphere(segments: u32, rings: u32) -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    for r in 0..=rings {
        let phi = r as f32 / rings as f32 * std::f32::consts::PI;
        let (sp, cp) = phi.sin_cos();
        for k in 0..=segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            let p = [sp * c, sp * s, cp];
            v.push(MeshVertex {
                position: p,
                normal: p,
            });
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for k in 0..segments {
            let a = r * row + k;
            let b = a + row;
            i.extend([a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    (v, i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_meshes_index_their_own_vertices_and_have_unit_normals() {
        for (v, i) in [unit_box(), unit_cylinder(16), unit_sphere(12, 8)] {
            assert_eq!(i.len() % 3, 0);
            assert!(i.iter().all(|&k| (k as usize) < v.len()));
            for vert in &v {
                let n = vert.normal;
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-5, "{n:?}");
                assert!(vert.position.iter().all(|c| c.abs() <= 1.0 + 1e-6));
            }
        }
    }
}
