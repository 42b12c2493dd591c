//! Robot meshes: resolve the filename of a URDF `<mesh>` to a file and load it into an indexed
//! triangle mesh (for the viewport, and for collision checks as convex hulls). No GPU here.
//!
//! **Resolution** ([`MeshResolver`]), never by shelling out to ROS:
//! - `package://pkg/rest`: an explicit package map, then the URDF's folder and its ancestors (a
//!   folder that is package `pkg` — its `package.xml` names it, or it is called `pkg` — or that holds
//!   such a folder), then each `ROS_PACKAGE_PATH` entry (the entry itself, a folder in it, or a
//!   package folder one grouping level further down);
//! - `file:///abs/path`, absolute paths, and relative paths (against the URDF's folder).
//!
//! **Loading** ([`load_mesh`]): STL (binary and ASCII), Collada `.dae` (its `<unit meter>` applied)
//! and Wavefront OBJ through the `mesh-loader` crate, dispatched on the extension in any case. The
//! result is in metres with the `<mesh scale>` applied: positions, unit normals (the file's where it
//! has usable ones, else per-face ones from the winding) and triangle indices. A negative scale
//! determinant flips the winding so that faces stay front-facing.
//!
//! Every problem is a [`MeshWarning`] naming the file: the caller draws a placeholder and goes on.

pub mod lod;

use crate::par::prelude::*;
use crate::source::{FileKind, FileSource, Files, MeshFormat};
use nalgebra::Vector3;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Package name → package folder.
pub type PackageMap = HashMap<String, PathBuf>;

/// A problem with one mesh: the robot still loads, the mesh is drawn as a placeholder.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshWarning {
    #[error(
        "mesh `{filename}`: package `{package}` not found (looked in the package map, the URDF's folder and its ancestors, and ROS_PACKAGE_PATH)"
    )]
    UnknownPackage { filename: String, package: String },
    #[error("mesh `{filename}`: no file at {}", .path.display())]
    NotFound { filename: String, path: PathBuf },
    #[error("mesh `{filename}`: unsupported URL scheme (only package://, file:// and paths)")]
    UnsupportedScheme { filename: String },
    #[error("mesh `{filename}`: unsupported format `{extension}` (STL, DAE and OBJ are read)")]
    UnsupportedFormat { filename: String, extension: String },
    #[error("mesh `{filename}` ({}): cannot be read: {message}", .path.display())]
    Unreadable {
        filename: String,
        path: PathBuf,
        message: String,
    },
    #[error("mesh `{filename}` ({}): holds no triangles", .path.display())]
    Empty { filename: String, path: PathBuf },
}

/// Where mesh filenames are resolved from.
#[derive(Clone, Debug, Default)]
pub struct MeshResolver {
    /// Where the files are looked for and read (default: the file system).
    pub files: Files,
    /// The folder of the URDF file, if it was read from one.
    pub urdf_dir: Option<PathBuf>,
    pub packages: PackageMap,
    pub ros_package_path: Vec<PathBuf>,
}

/// Does folder `dir` hold ROS package `pkg`? Its `package.xml` names it (`<name>pkg</name>`), or the
/// folder is called `pkg` and has a `package.xml` (or a manifest.xml, ROS 1's old form).
fn is_package(files: &dyn FileSource, dir: &Path, pkg: &str) -> bool {
    let package_xml = files
        .read_limited(&dir.join("package.xml"), 1 << 20)
        .map(|bytes| String::from_utf8_lossy(&bytes).into_owned());
    match package_xml {
        Ok(xml) => {
            let named = xml
                .split_once("<name>")
                .and_then(|(_, rest)| rest.split_once("</name>"))
                .is_some_and(|(name, _)| name.trim() == pkg);
            named || dir.file_name().is_some_and(|n| n == pkg)
        }
        Err(_) => {
            dir.file_name().is_some_and(|n| n == pkg) && files.is_file(&dir.join("manifest.xml"))
        }
    }
}

impl MeshResolver {
    /// A resolver for a URDF read from `urdf_path` (if any), with an explicit package map and the
    /// process's `ROS_PACKAGE_PATH`.
    pub fn new(urdf_path: Option<&Path>, packages: PackageMap) -> Self {
        let ros_package_path = std::env::var_os("ROS_PACKAGE_PATH")
            .map(|v| {
                std::env::split_paths(&v)
                    .filter(|p| !p.as_os_str().is_empty())
                    .collect()
            })
            .unwrap_or_default();
        let urdf_dir = urdf_path.and_then(|p| p.parent()).map(|d| {
            if d.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                d.to_path_buf()
            }
        });
        Self {
            files: Files::default(),
            urdf_dir,
            packages,
            ros_package_path,
        }
    }

    /// Look for the meshes in `files` instead of the file system.
    pub fn with_files(mut self, files: Files) -> Self {
        self.files = files;
        self
    }

    /// The folder of package `pkg`, if it can be found.
    pub fn package_dir(&self, pkg: &str) -> Option<PathBuf> {
        if let Some(dir) = self.packages.get(pkg) {
            return Some(dir.clone());
        }
        if let Some(dir) = &self.urdf_dir {
            for anc in dir.ancestors() {
                if is_package(&*self.files, anc, pkg) {
                    return Some(anc.to_path_buf());
                }
                let sub = anc.join(pkg);
                if is_package(&*self.files, &sub, pkg) {
                    return Some(sub);
                }
            }
        }
        for entry in &self.ros_package_path {
            if is_package(&*self.files, entry, pkg) {
                return Some(entry.clone());
            }
            let sub = entry.join(pkg);
            if is_package(&*self.files, &sub, pkg) {
                return Some(sub);
            }
            // A package folder under another name, or one level of grouping folders (a catkin
            // workspace's src/<repo>/<pkg>).
            for child in self.files.read_dir(entry) {
                if is_package(&*self.files, &child, pkg) {
                    return Some(child);
                }
                let sub = child.join(pkg);
                if is_package(&*self.files, &sub, pkg) {
                    return Some(sub);
                }
            }
        }
        // Last resort, for a package copied without its package.xml: an ancestor called `pkg`, or a
        // folder called `pkg` beside the URDF or in one of its ancestors (how a browser upload of
        // loose mesh files is laid out).
        let dir = self.urdf_dir.as_ref()?;
        dir.ancestors()
            .find(|a| a.file_name().is_some_and(|n| n == pkg))
            .map(Path::to_path_buf)
            .or_else(|| {
                dir.ancestors()
                    .map(|a| a.join(pkg))
                    .find(|sub| self.files.is_dir(sub))
            })
    }

    /// The file a URDF mesh filename refers to.
    pub fn resolve(&self, filename: &str) -> Result<PathBuf, MeshWarning> {
        let path = if let Some(rest) = filename.strip_prefix("package://") {
            let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
            let dir = self
                .package_dir(pkg)
                .ok_or_else(|| MeshWarning::UnknownPackage {
                    filename: filename.into(),
                    package: pkg.into(),
                })?;
            dir.join(rel)
        } else if let Some(abs) = filename.strip_prefix("file://") {
            PathBuf::from(abs)
        } else if filename.contains("://") {
            return Err(MeshWarning::UnsupportedScheme {
                filename: filename.into(),
            });
        } else {
            let p = Path::new(filename);
            match &self.urdf_dir {
                Some(dir) if p.is_relative() => dir.join(p),
                _ => p.to_path_buf(),
            }
        };
        if self.files.is_file(&path) {
            Ok(path)
        } else {
            Err(MeshWarning::NotFound {
                filename: filename.into(),
                path,
            })
        }
    }
}

/// An indexed triangle mesh in metres (scale applied), ready for a vertex buffer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions_m: Vec<[f32; 3]>,
    /// Unit normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Counter-clockwise triangles (front faces), three indices each.
    pub indices: Vec<u32>,
}

impl TriangleMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Axis-aligned bounds `(min, max)` in metres; `None` when empty.
    pub fn bounds_m(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions_m.first()?;
        Some(self.positions_m.iter().fold((first, first), |(lo, hi), p| {
            (
                std::array::from_fn(|i| lo[i].min(p[i])),
                std::array::from_fn(|i| hi[i].max(p[i])),
            )
        }))
    }
}

fn face_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f32; 3] {
    let (a, b, c) = (Vector3::from(a), Vector3::from(b), Vector3::from(c));
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    if len > 0.0 && len.is_finite() {
        (n / len).into()
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Convert a loaded mesh: apply `scale`, fix the winding for a mirroring scale, and take the file's
/// normals if every one is usable, else per-face normals (vertices unshared).
fn convert(mesh: &mesh_loader::Mesh, scale: [f64; 3]) -> TriangleMesh {
    let s = scale.map(|v| v as f32);
    let mirrored = s[0] * s[1] * s[2] < 0.0;
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| [v[0] * s[0], v[1] * s[1], v[2] * s[2]])
        .collect();
    let faces = mesh.faces.iter().filter(|f| {
        f.iter().all(|&i| (i as usize) < positions.len())
            && f[0] != f[1]
            && f[1] != f[2]
            && f[0] != f[2]
    });
    let file_normals_usable = mesh.normals.len() == mesh.vertices.len()
        && mesh
            .normals
            .iter()
            .all(|n| n.iter().all(|c| c.is_finite()) && n.iter().any(|&c| c != 0.0));
    if file_normals_usable {
        // Normals transform with the inverse scale, then renormalise.
        let normals = mesh
            .normals
            .iter()
            .map(|n| {
                let v = Vector3::new(n[0] / s[0], n[1] / s[1], n[2] / s[2]);
                let len = v.norm();
                if len > 0.0 && len.is_finite() {
                    (v / len).into()
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
            .collect();
        let indices = faces
            .flat_map(|f| if mirrored { [f[0], f[2], f[1]] } else { *f })
            .collect();
        TriangleMesh {
            positions_m: positions,
            normals,
            indices,
        }
    } else {
        let mut out = TriangleMesh::default();
        for f in faces {
            let [a, b, c] =
                if mirrored { [f[0], f[2], f[1]] } else { *f }.map(|i| positions[i as usize]);
            let n = face_normal(a, b, c);
            let base = out.positions_m.len() as u32;
            out.positions_m.extend([a, b, c]);
            out.normals.extend([n; 3]);
            out.indices.extend([base, base + 1, base + 2]);
        }
        out
    }
}

/// Most a mesh file may have: 512 MiB.
pub const MAX_MESH_BYTES: u64 = 512 * 1024 * 1024;

/// Load one mesh file (metres, `scale` applied).
pub fn load_mesh(
    filename: &str,
    path: &Path,
    scale: [f64; 3],
) -> Result<TriangleMesh, MeshWarning> {
    load_mesh_from(&crate::source::OsFiles, filename, path, scale)
}

/// [`load_mesh`] reading through `files`.
pub fn load_mesh_from(
    files: &dyn FileSource,
    filename: &str,
    path: &Path,
    scale: [f64; 3],
) -> Result<TriangleMesh, MeshWarning> {
    let unreadable = |message: String| MeshWarning::Unreadable {
        filename: filename.into(),
        path: path.to_path_buf(),
        message,
    };
    let FileKind::Mesh(format) = FileKind::of(path) else {
        return Err(MeshWarning::UnsupportedFormat {
            filename: filename.into(),
            extension: path
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase(),
        });
    };
    let bytes = files
        .read_limited(path, MAX_MESH_BYTES)
        .map_err(|e| unreadable(e.to_string()))?;
    let loader = mesh_loader::Loader::default().merge_meshes(true);
    let scene = match format {
        MeshFormat::Stl => loader.load_stl_from_slice(&bytes, path),
        MeshFormat::Collada => loader.load_collada_from_slice(&bytes, path),
        MeshFormat::Obj => loader.load_obj_from_slice(&bytes, path),
    }
    .map_err(|e| unreadable(e.to_string()))?;
    let mesh = match scene.meshes.first() {
        Some(m) => convert(m, scale),
        None => TriangleMesh::default(),
    };
    if mesh.indices.is_empty() {
        return Err(MeshWarning::Empty {
            filename: filename.into(),
            path: path.to_path_buf(),
        });
    }
    Ok(mesh)
}

/// Which geometry of the links.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GeometryKind {
    Visual,
    Collision,
}

/// The meshes of a robot description, each file loaded once (both arms of a YuMi share their link
/// meshes), and the warnings of those that could not be loaded.
#[derive(Clone, Debug, Default)]
pub struct MeshSet {
    /// `(filename as written, scale)` → mesh.
    pub meshes: BTreeMap<(String, [u64; 3]), Arc<TriangleMesh>>,
    pub warnings: Vec<MeshWarning>,
}

impl MeshSet {
    /// The mesh of a `<mesh filename scale>` element, if it loaded.
    pub fn get(&self, filename: &str, scale: [f64; 3]) -> Option<&Arc<TriangleMesh>> {
        self.meshes
            .get(&(filename.to_string(), scale.map(f64::to_bits)))
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.values().map(|m| m.triangle_count()).sum()
    }
}

/// Load every mesh of `kind` of `robot` (in parallel, each distinct file and scale once).
pub fn load_robot_meshes(
    robot: &urdf_rs::Robot,
    resolver: &MeshResolver,
    kind: GeometryKind,
) -> MeshSet {
    let mut wanted: BTreeMap<(String, [u64; 3]), [f64; 3]> = BTreeMap::new();
    for link in &robot.links {
        let geometries: Vec<&urdf_rs::Geometry> = match kind {
            GeometryKind::Visual => link.visual.iter().map(|v| &v.geometry).collect(),
            GeometryKind::Collision => link.collision.iter().map(|c| &c.geometry).collect(),
        };
        for g in geometries {
            if let urdf_rs::Geometry::Mesh { filename, scale } = g {
                let scale = scale.map_or([1.0; 3], |s| s.0);
                wanted.insert((filename.clone(), scale.map(f64::to_bits)), scale);
            }
        }
    }
    let results: Vec<_> = wanted
        .into_par_iter()
        .map(|(key, scale)| {
            let loaded = resolver
                .resolve(&key.0)
                .and_then(|path| load_mesh_from(&*resolver.files, &key.0, &path, scale));
            (key, loaded)
        })
        .collect();
    let mut set = MeshSet::default();
    for (key, loaded) in results {
        match loaded {
            Ok(mesh) => {
                set.meshes.insert(key, Arc::new(mesh));
            }
            Err(w) => set.warnings.push(w),
        }
    }
    set
}

#[cfg(test)]
mod tests;
