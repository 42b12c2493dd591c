//! Link geometry: primitives and meshes (resolved here, never by shelling out to ROS), with colours.

use super::tree::{Kinematics, LocalShape};
use super::{ShapeKind, finite_pose, isometry_from_urdf_pose};
use crate::meshes::MeshResolver;
use nalgebra::Vector3;

const DEFAULT_VISUAL_RGBA: [f32; 4] = [0.72, 0.73, 0.75, 1.0];
const COLLISION_RGBA: [f32; 4] = [0.95, 0.45, 0.15, 0.5];

/// Compile one `<geometry>`; `None` (with a warning) when its dimensions are unusable.
fn compile_geometry(
    geometry: &urdf_rs::Geometry,
    link: &str,
    resolver: &MeshResolver,
    warnings: &mut Vec<String>,
) -> Option<ShapeKind> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let kind = match geometry {
        urdf_rs::Geometry::Box { size } => {
            let s = Vector3::new(size[0], size[1], size[2]) * 500.0;
            if !s.iter().all(|&v| ok(v)) {
                warnings.push(format!(
                    "link `{link}`: box size {:?} is not positive; skipped",
                    size.0
                ));
                return None;
            }
            ShapeKind::Box { half_extents_mm: s }
        }
        urdf_rs::Geometry::Cylinder { radius, length }
        | urdf_rs::Geometry::Capsule { radius, length } => {
            if !ok(*radius) || !ok(*length) {
                warnings.push(format!(
                    "link `{link}`: cylinder/capsule radius {radius} length {length} not positive; skipped"
                ));
                return None;
            }
            let (radius_mm, half_length_mm) = (radius * 1000.0, length * 500.0);
            if matches!(geometry, urdf_rs::Geometry::Cylinder { .. }) {
                ShapeKind::Cylinder {
                    radius_mm,
                    half_length_mm,
                }
            } else {
                ShapeKind::Capsule {
                    radius_mm,
                    half_length_mm,
                }
            }
        }
        urdf_rs::Geometry::Sphere { radius } => {
            if !ok(*radius) {
                warnings.push(format!(
                    "link `{link}`: sphere radius {radius} not positive; skipped"
                ));
                return None;
            }
            ShapeKind::Sphere {
                radius_mm: radius * 1000.0,
            }
        }
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let scale = scale.map_or(Vector3::new(1.0, 1.0, 1.0), |s| {
                Vector3::new(s[0], s[1], s[2])
            });
            let resolved = match resolver.resolve(filename) {
                Ok(p) => Some(p),
                Err(why) => {
                    warnings.push(format!("link `{link}`: {why}; drawn as a placeholder"));
                    None
                }
            };
            ShapeKind::Mesh {
                filename: filename.clone(),
                resolved,
                scale,
            }
        }
    };
    Some(kind)
}

fn material_rgba(material: Option<&urdf_rs::Material>, robot: &urdf_rs::Robot) -> [f32; 4] {
    let Some(m) = material else {
        return DEFAULT_VISUAL_RGBA;
    };
    let color = m.color.as_ref().or_else(|| {
        robot
            .materials
            .iter()
            .find(|g| g.name == m.name && !m.name.is_empty())
            .and_then(|g| g.color.as_ref())
    });
    match color {
        Some(c) if c.rgba.0.iter().all(|v| v.is_finite()) => {
            c.rgba.0.map(|v| v.clamp(0.0, 1.0) as f32)
        }
        _ => DEFAULT_VISUAL_RGBA,
    }
}

/// The visual and collision shapes of every link, in their link's frame.
pub(super) fn compile_shapes(
    urdf: &urdf_rs::Robot,
    resolver: &MeshResolver,
    kin: &mut Kinematics,
    warnings: &mut Vec<String>,
) {
    for (li, link) in urdf.links.iter().enumerate() {
        for v in &link.visual {
            if !finite_pose(&v.origin) {
                warnings.push(format!(
                    "link `{}`: a visual origin is not finite; skipped",
                    link.name
                ));
                continue;
            }
            if let Some(kind) = compile_geometry(&v.geometry, &link.name, resolver, warnings) {
                kin.visual.push(LocalShape {
                    link: li,
                    kind,
                    link_from_shape: isometry_from_urdf_pose(&v.origin),
                    rgba: material_rgba(v.material.as_ref(), urdf),
                });
            }
        }
        for c in &link.collision {
            if !finite_pose(&c.origin) {
                warnings.push(format!(
                    "link `{}`: a collision origin is not finite; skipped",
                    link.name
                ));
                continue;
            }
            // Meshes are reported once (by the visual pass) when they are the same file.
            let mut scratch = Vec::new();
            if let Some(kind) = compile_geometry(&c.geometry, &link.name, resolver, &mut scratch) {
                kin.collision.push(LocalShape {
                    link: li,
                    kind,
                    link_from_shape: isometry_from_urdf_pose(&c.origin),
                    rgba: COLLISION_RGBA,
                });
            }
            for w in scratch {
                if !warnings.contains(&w) {
                    warnings.push(w);
                }
            }
        }
    }
}
