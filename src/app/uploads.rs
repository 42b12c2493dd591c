//! Files given to a browser page (picked together, dropped together, or as one `.zip`) mounted in
//! memory so the loaders find them as on disk; then which of them to open. Plain Rust (no browser
//! API), so it is tested natively; `web.rs` reads the browser's files and calls [`mount`].
//!
//! A batch is mounted under its own folder (`/uploads/<n>/`) with the paths it came with (a `.zip`'s
//! layout, or a folder's relative paths); loose files sit side by side. A URDF's meshes given as
//! loose files lose their folders, so each mesh the URDF names and cannot find is also mounted where
//! the URDF looks for it (`package://pkg/meshes/a.stl` → `<urdf folder>/pkg/meshes/a.stl`), matched
//! by file name when exactly one given file has that name.

use super::files::{FileReply, OpenKind};
use crate::meshes::{MeshResolver, PackageMap};
use crate::source::{FileKind, Files, MemoryFiles};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One file as the browser gave it: its path within the batch (a file name, or a folder's relative
/// path) and its bytes.
pub struct Upload {
    pub path: String,
    pub bytes: Vec<u8>,
}

/// Among robot descriptions, whatever their depth: a `.urdf` first, then a `.xacro` (which the loader
/// refuses with the command that expands it), then a `.xml` (a ROS package's `package.xml` is one).
fn robot_rank(path: &Path) -> u8 {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext.eq_ignore_ascii_case("urdf") {
        0
    } else if FileKind::of(path) == FileKind::Xacro {
        1
    } else {
        2
    }
}

/// Mount `uploads` under `dir` in `memory` and decide what to open: a dataset (its `dataset.toml`,
/// else another `.toml`; the shallowest) or a robot description (a `.urdf`). `wanted` is what the
/// user asked to open (`None`: dropped files, a manifest wins).
pub fn mount(
    memory: &MemoryFiles,
    dir: &Path,
    uploads: Vec<Upload>,
    wanted: Option<OpenKind>,
) -> FileReply {
    let names: Vec<String> = uploads.iter().map(|u| u.path.clone()).collect();
    let mut mounted = Vec::new();
    for upload in uploads {
        let relative = Path::new(&upload.path);
        if FileKind::of(relative) == FileKind::Zip {
            match crate::source::unpack_zip(memory, dir, &upload.path, &upload.bytes) {
                Ok(paths) => mounted.extend(paths),
                Err(e) => return FileReply::Failed(e.to_string()),
            }
        } else {
            // Only the normal parts of the path: nothing leaves `dir`.
            let inside: PathBuf = relative
                .components()
                .filter(|c| matches!(c, std::path::Component::Normal(_)))
                .collect();
            let path = dir.join(inside);
            memory.insert(&path, upload.bytes);
            mounted.push(path);
        }
    }
    // A file for the import view: the one picked.
    if let Some(kind @ (OpenKind::ImportFile(_) | OpenKind::ImportFolder)) = wanted {
        return match mounted.into_iter().next() {
            Some(path) => FileReply::Open(kind, path),
            None => FileReply::Cancelled,
        };
    }
    // The one rule for what a file is (`source::FileKind`); the shallowest of a kind wins.
    let shallowest = |is: fn(FileKind) -> bool, rank: fn(&Path) -> u8| {
        let mut found: Vec<&PathBuf> = mounted.iter().filter(|p| is(FileKind::of(p))).collect();
        crate::sort::sort_by_key(&mut found, |p| {
            (
                rank(p),
                p.components().count(),
                p.file_name() != Some(crate::dataset::MANIFEST_FILE.as_ref()),
            )
        });
        found.first().map(|p| p.to_path_buf())
    };
    let manifest = shallowest(|k| k == FileKind::DatasetManifest, |_| 0);
    let urdf = shallowest(FileKind::is_robot, robot_rank);
    if let Some(urdf) = &urdf {
        place_loose_meshes(memory, urdf, &mounted);
    }
    let prefer_urdf = match wanted {
        Some(kind) => kind == OpenKind::Urdf,
        None => manifest.is_none(),
    };
    match (manifest, urdf) {
        (_, Some(urdf)) if prefer_urdf => FileReply::Open(OpenKind::Urdf, urdf),
        (Some(manifest), _) => FileReply::Open(OpenKind::Dataset, manifest),
        (None, Some(urdf)) => FileReply::Open(OpenKind::Urdf, urdf),
        (None, None) => FileReply::Failed(format!(
            "{}: choose a dataset's dataset.toml together with its CSV files (or one .zip of \
             them), or a .urdf with its meshes",
            crate::textfile::excerpt_n(&names.join(", "), 200)
        )),
    }
}

/// Mount each mesh the URDF names and cannot find at the place it looks, when exactly one of the
/// given files has its file name.
fn place_loose_meshes(memory: &MemoryFiles, urdf: &Path, mounted: &[PathBuf]) {
    let Ok(text) = crate::textfile::read_from(memory, urdf) else {
        return;
    };
    let Ok(robot) = urdf_rs::read_from_string(&text) else {
        return; // Loading it reports the error.
    };
    let mut by_name: BTreeMap<&std::ffi::OsStr, Vec<&PathBuf>> = BTreeMap::new();
    for path in mounted {
        if let Some(name) = path.file_name() {
            by_name.entry(name).or_default().push(path);
        }
    }
    let resolver = MeshResolver::new(Some(urdf), PackageMap::new())
        .with_files(Files(Arc::new(memory.clone())));
    let urdf_dir = urdf.parent().unwrap_or(Path::new("/"));
    let filenames = robot.links.iter().flat_map(|link| {
        let visual = link.visual.iter().map(|v| &v.geometry);
        let collision = link.collision.iter().map(|c| &c.geometry);
        visual.chain(collision).filter_map(|g| match g {
            urdf_rs::Geometry::Mesh { filename, .. } => Some(filename.clone()),
            _ => None,
        })
    });
    for filename in filenames {
        if resolver.resolve(&filename).is_ok() {
            continue;
        }
        let target = if let Some(rest) = filename.strip_prefix("package://") {
            urdf_dir.join(rest)
        } else if filename.contains("://") || Path::new(&filename).is_absolute() {
            continue;
        } else {
            urdf_dir.join(&filename)
        };
        let Some(name) = target.file_name() else {
            continue;
        };
        if let Some([source]) = by_name.get(name).map(Vec::as_slice)
            && let Ok(bytes) = crate::source::FileSource::read_limited(
                memory,
                source,
                crate::meshes::MAX_MESH_BYTES,
            )
        {
            memory.insert(&target, bytes);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::FileSource;

    fn example(name: &str) -> Upload {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example");
        Upload {
            path: name.into(),
            bytes: std::fs::read(dir.join(name)).unwrap(),
        }
    }

    #[test]
    fn a_dataset_picked_as_files_loads_from_memory() {
        let memory = MemoryFiles::new();
        let reply = mount(
            &memory,
            Path::new("/uploads/1"),
            vec![
                example("left.csv"),
                example("dataset.toml"),
                example("right.csv"),
            ],
            None,
        );
        let FileReply::Open(OpenKind::Dataset, manifest) = reply else {
            panic!("{reply:?}");
        };
        assert_eq!(manifest, Path::new("/uploads/1/dataset.toml"));
        let files = Files(Arc::new(memory));
        let session = super::super::session::Session::load_from(&files, &manifest, None).unwrap();
        assert_eq!(session.dataset.arms.left.measurements.len(), 220);
        assert_eq!(session.dataset.dir, Path::new("/uploads/1"));
    }

    #[test]
    fn a_missing_csv_is_an_error_naming_its_path() {
        let memory = MemoryFiles::new();
        let reply = mount(
            &memory,
            Path::new("/uploads/2"),
            vec![example("dataset.toml"), example("left.csv")],
            Some(OpenKind::Dataset),
        );
        let FileReply::Open(_, manifest) = reply else {
            panic!("{reply:?}");
        };
        let files = Files(Arc::new(memory));
        let err = super::super::session::Session::load_from(&files, &manifest, None)
            .err()
            .unwrap();
        assert!(
            format!("{err:#}").contains("/uploads/2/right.csv"),
            "{err:#}"
        );
    }

    fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
        use std::io::Write as _;
        let mut writer = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, bytes) in entries {
            writer.start_file(*name, options).unwrap();
            writer.write_all(bytes).unwrap();
        }
        writer.finish().unwrap().into_inner()
    }

    #[test]
    fn a_zipped_dataset_opens_from_its_folder() {
        let files: Vec<Upload> = ["dataset.toml", "left.csv", "right.csv"]
            .into_iter()
            .map(example)
            .collect();
        let entries: Vec<(String, &[u8])> = files
            .iter()
            .map(|u| (format!("my-cell/{}", u.path), u.bytes.as_slice()))
            .collect();
        let entries: Vec<(&str, &[u8])> = entries.iter().map(|(n, b)| (n.as_str(), *b)).collect();
        let memory = MemoryFiles::new();
        let reply = mount(
            &memory,
            Path::new("/uploads/3"),
            vec![Upload {
                path: "cell.zip".into(),
                bytes: zip_of(&entries),
            }],
            None,
        );
        let FileReply::Open(OpenKind::Dataset, manifest) = reply else {
            panic!("{reply:?}");
        };
        assert_eq!(manifest, Path::new("/uploads/3/my-cell/dataset.toml"));
        let files = Files(Arc::new(memory));
        assert!(super::super::session::Session::load_from(&files, &manifest, None).is_ok());
        // Not a zip: refused with its name.
        let reply = mount(
            &MemoryFiles::new(),
            Path::new("/u"),
            vec![Upload {
                path: "broken.zip".into(),
                bytes: b"nope".to_vec(),
            }],
            None,
        );
        assert!(matches!(reply, FileReply::Failed(m) if m.starts_with("broken.zip")));
    }

    /// A ROS package uploaded whole: its `package.xml` (an `.xml`, which may be a URDF) lies above
    /// `urdf/robot.urdf`; the `.urdf` is the robot.
    #[test]
    fn a_urdf_wins_over_a_shallower_package_xml() {
        let reply = mount(
            &MemoryFiles::new(),
            Path::new("/uploads/5"),
            vec![
                Upload {
                    path: "r_description/package.xml".into(),
                    bytes: b"<package/>".to_vec(),
                },
                Upload {
                    path: "r_description/urdf/robot.urdf".into(),
                    bytes: b"<robot name=\"r\"/>".to_vec(),
                },
            ],
            None,
        );
        let FileReply::Open(OpenKind::Urdf, path) = reply else {
            panic!("{reply:?}");
        };
        assert_eq!(path, Path::new("/uploads/5/r_description/urdf/robot.urdf"));
    }

    #[test]
    fn loose_mesh_files_are_found_where_the_urdf_looks() {
        let urdf = br#"<robot name="r">
  <link name="base"><visual><geometry><mesh filename="package://r_description/meshes/visual/base.stl"/></geometry></visual></link>
  <link name="arm"><visual><geometry><mesh filename="meshes/arm.stl"/></geometry></visual></link>
  <joint name="j" type="fixed"><parent link="base"/><child link="arm"/></joint>
</robot>"#;
        let memory = MemoryFiles::new();
        let reply = mount(
            &memory,
            Path::new("/uploads/4"),
            vec![
                Upload {
                    path: "robot.urdf".into(),
                    bytes: urdf.to_vec(),
                },
                Upload {
                    path: "base.stl".into(),
                    bytes: b"solid base".to_vec(),
                },
                Upload {
                    path: "arm.stl".into(),
                    bytes: b"solid arm".to_vec(),
                },
            ],
            Some(OpenKind::Urdf),
        );
        let FileReply::Open(OpenKind::Urdf, path) = reply else {
            panic!("{reply:?}");
        };
        assert_eq!(path, Path::new("/uploads/4/robot.urdf"));
        let resolver = MeshResolver::new(Some(&path), PackageMap::new())
            .with_files(Files(Arc::new(memory.clone())));
        let base = resolver
            .resolve("package://r_description/meshes/visual/base.stl")
            .unwrap();
        assert_eq!(memory.read_limited(&base, 100).unwrap(), b"solid base");
        let arm = resolver.resolve("meshes/arm.stl").unwrap();
        assert_eq!(memory.read_limited(&arm, 100).unwrap(), b"solid arm");
    }
}
