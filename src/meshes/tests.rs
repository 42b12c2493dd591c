//! Tests of mesh resolution and loading on files the tests write.

use super::*;
use crate::test_robots::{TETRA, ascii_stl, binary_stl, dae, obj, write_file};

fn face_normal_of(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Vector3<f32> {
    let (a, b, c) = (Vector3::from(a), Vector3::from(b), Vector3::from(c));
    (b - a).cross(&(c - a))
}

/// Positions of each triangle (unshared), for comparing meshes however they are indexed.
fn triangles(m: &TriangleMesh) -> Vec<[[f32; 3]; 3]> {
    let mut t: Vec<[[f32; 3]; 3]> = m
        .indices
        .chunks_exact(3)
        .map(|f| {
            let mut tri = [0, 1, 2].map(|i| m.positions_m[f[i] as usize]);
            // Rotate so that the smallest vertex comes first (winding kept).
            let first = (0..3)
                .min_by(|&a, &b| tri[a].partial_cmp(&tri[b]).unwrap())
                .unwrap();
            tri.rotate_left(first);
            tri
        })
        .collect();
    t.sort_by(|a, b| a.partial_cmp(b).unwrap());
    t
}

fn assert_outward_tetra(m: &TriangleMesh, size: f32) {
    assert_eq!(m.triangle_count(), 4);
    let (lo, hi) = m.bounds_m().unwrap();
    assert!(
        lo.iter().all(|&v| v.abs() < 1e-6)
            && hi.iter().all(|&v| (v - size).abs() < 1e-6 * size.max(1.0)),
        "{lo:?} {hi:?}"
    );
    // Every face normal points away from the centroid (outward, counter-clockwise faces).
    let centroid = Vector3::repeat(size / 4.0);
    for f in m.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|i| m.positions_m[f[i] as usize]);
        let n = face_normal_of(a, b, c);
        let mid = (Vector3::from(a) + Vector3::from(b) + Vector3::from(c)) / 3.0;
        assert!(n.dot(&(mid - centroid)) > 0.0, "inward face");
        for &i in f {
            let vn = Vector3::from(m.normals[i as usize]);
            assert!((vn.norm() - 1.0).abs() < 1e-5);
        }
    }
}

#[test]
fn all_formats_load_to_the_same_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = [
        write_file(d, "bin.stl", &binary_stl(b"binary tetra", &TETRA)),
        // A binary STL whose header starts with "solid", as some exporters write.
        write_file(
            d,
            "solid-header.STL",
            &binary_stl(b"solid but binary", &TETRA),
        ),
        write_file(d, "ascii.stl", ascii_stl(&TETRA).as_bytes()),
        write_file(d, "tetra.obj", obj(&TETRA).as_bytes()),
        // Collada in millimetres: its <unit> makes metres.
        write_file(d, "tetra_mm.DAE", dae(&TETRA, 0.001).as_bytes()),
    ];
    let reference = triangles(&load_mesh("bin.stl", &files[0], [1.0; 3]).unwrap());
    for f in &files {
        let m = load_mesh("x", f, [1.0; 3]).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_outward_tetra(&m, 1.0);
        let got = triangles(&m);
        for (a, b) in got.iter().zip(&reference) {
            for (p, q) in a.iter().zip(b) {
                assert!(
                    p.iter().zip(q).all(|(x, y)| (x - y).abs() < 1e-5),
                    "{}: {a:?} vs {b:?}",
                    f.display()
                );
            }
        }
    }
}

#[test]
fn obj_with_a_missing_material_library_still_loads() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("mtllib missing.mtl\nusemtl steel\n{}", obj(&TETRA));
    let p = write_file(dir.path(), "with_mtl.obj", text.as_bytes());
    let m = load_mesh("with_mtl.obj", &p, [1.0; 3]).unwrap();
    assert_outward_tetra(&m, 1.0);
}

#[test]
fn scale_is_applied_and_mirroring_keeps_faces_outward() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_file(dir.path(), "t.stl", &binary_stl(b"t", &TETRA));
    let m = load_mesh("t.stl", &p, [0.001; 3]).unwrap();
    assert_outward_tetra(&m, 0.001);
    let mirrored = load_mesh("t.stl", &p, [-1.0, 1.0, 1.0]).unwrap();
    let centroid = Vector3::new(-0.25, 0.25, 0.25);
    for f in mirrored.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|i| mirrored.positions_m[f[i] as usize]);
        let mid = (Vector3::from(a) + Vector3::from(b) + Vector3::from(c)) / 3.0;
        assert!(face_normal_of(a, b, c).dot(&(mid - centroid)) > 0.0);
    }
}

#[test]
fn package_urls_resolve_from_map_ancestors_and_ros_package_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // ws/src/robot_description/{package.xml, meshes/a.stl, urdf/robot.urdf}
    let pkg = d.join("ws/src/robot_description");
    write_file(
        &pkg,
        "package.xml",
        b"<package format=\"2\"><name>robot_description</name></package>",
    );
    let mesh = write_file(&pkg, "meshes/a.stl", &binary_stl(b"a", &TETRA));
    let urdf = write_file(&pkg, "urdf/robot.urdf", b"<robot name=\"r\"/>");
    let url = "package://robot_description/meshes/a.stl";
    // From the URDF's ancestors.
    let r = MeshResolver {
        urdf_dir: Some(urdf.parent().unwrap().into()),
        ..Default::default()
    };
    assert_eq!(r.resolve(url).unwrap(), mesh);
    // A package folder named differently from the package: found by its package.xml.
    let other = d.join("elsewhere/renamed");
    write_file(
        &other,
        "package.xml",
        b"<package><name> other_pkg </name></package>",
    );
    let m2 = write_file(&other, "m.obj", obj(&TETRA).as_bytes());
    let r = MeshResolver {
        ros_package_path: vec![d.join("elsewhere")],
        ..Default::default()
    };
    assert_eq!(r.resolve("package://other_pkg/m.obj").unwrap(), m2);
    // From ROS_PACKAGE_PATH (a workspace's src, one grouping level deep).
    let r = MeshResolver {
        ros_package_path: vec![d.join("ws")],
        ..Default::default()
    };
    assert_eq!(r.resolve(url).unwrap(), mesh);
    // From an explicit package map, which wins.
    let alt = write_file(d, "alt/meshes/a.stl", &binary_stl(b"alt", &TETRA));
    let r = MeshResolver {
        urdf_dir: Some(urdf.parent().unwrap().into()),
        packages: [("robot_description".to_string(), d.join("alt"))].into(),
        ..Default::default()
    };
    assert_eq!(r.resolve(url).unwrap(), alt);
    // Relative and file:// paths.
    let r = MeshResolver {
        urdf_dir: Some(urdf.parent().unwrap().into()),
        ..Default::default()
    };
    assert_eq!(
        r.resolve("../meshes/a.stl").unwrap(),
        pkg.join("urdf/../meshes/a.stl")
    );
    assert_eq!(
        r.resolve(&format!("file://{}", mesh.display())).unwrap(),
        mesh
    );
    // Problems are typed and name the file.
    let w = r.resolve("package://nope/x.stl").unwrap_err();
    assert!(
        matches!(&w, MeshWarning::UnknownPackage { package, .. } if package == "nope"),
        "{w}"
    );
    let w = r
        .resolve("package://robot_description/meshes/missing.stl")
        .unwrap_err();
    assert!(
        matches!(w, MeshWarning::NotFound { .. }) && w.to_string().contains("missing.stl"),
        "{w}"
    );
    assert!(matches!(
        r.resolve("http://example.org/a.stl"),
        Err(MeshWarning::UnsupportedScheme { .. })
    ));
}

#[test]
fn broken_files_are_warnings_not_failures() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_file(d, "package.xml", b"<package><name>p</name></package>");
    write_file(d, "ok.stl", &binary_stl(b"ok", &TETRA));
    write_file(d, "garbage.dae", b"<COLLADA><library_geometries><geometry"); // truncated XML
    write_file(d, "short.stl", &binary_stl(b"x", &TETRA)[..100]); // truncated binary STL
    write_file(d, "model.ply", b"ply\n");
    write_file(d, "empty.obj", b"# nothing\n");
    let urdf = format!(
        "<robot name=\"r\">{}</robot>",
        [
            "ok.stl",
            "garbage.dae",
            "short.stl",
            "model.ply",
            "missing.obj",
            "empty.obj",
            "package://p/ok.stl"
        ]
        .iter()
        .enumerate()
        .map(|(i, f)| format!(
            "<link name=\"l{i}\"><visual><geometry><mesh filename=\"{f}\"/></geometry></visual></link>"
        ))
        .collect::<String>()
    );
    let robot = urdf_rs::read_from_string(&urdf).unwrap();
    let resolver = MeshResolver {
        urdf_dir: Some(d.into()),
        ..Default::default()
    };
    let set = load_robot_meshes(&robot, &resolver, GeometryKind::Visual);
    assert_eq!(set.meshes.len(), 2, "{:?}", set.warnings);
    assert!(
        set.get("ok.stl", [1.0; 3]).is_some() && set.get("package://p/ok.stl", [1.0; 3]).is_some()
    );
    let text: Vec<String> = set.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(text.len(), 5, "{text:#?}");
    for name in [
        "garbage.dae",
        "short.stl",
        "model.ply",
        "missing.obj",
        "empty.obj",
    ] {
        assert!(text.iter().any(|t| t.contains(name)), "{name}: {text:#?}");
    }
}

#[test]
fn the_yumi_like_package_loads_every_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let urdf_path = crate::test_robots::write_yumi_like(dir.path());
    let robot = urdf_rs::read_file(&urdf_path).unwrap();
    let resolver = MeshResolver::new(Some(&urdf_path), PackageMap::new());
    let visual = load_robot_meshes(&robot, &resolver, GeometryKind::Visual);
    assert!(visual.warnings.is_empty(), "{:?}", visual.warnings);
    // body, 7 links, gripper base (OBJ), finger (DAE, mm with a 0.001 scale).
    assert_eq!(visual.meshes.len(), 10);
    let finger = visual
        .get(
            "package://yumi_description/meshes/gripper/finger.dae",
            [0.001; 3],
        )
        .unwrap();
    let (lo, hi) = finger.bounds_m().unwrap();
    assert!((hi[2] - lo[2] - 0.03).abs() < 1e-6, "{lo:?} {hi:?}");
    let collision = load_robot_meshes(&robot, &resolver, GeometryKind::Collision);
    assert!(collision.warnings.is_empty(), "{:?}", collision.warnings);
    assert_eq!(collision.meshes.len(), 8);
    assert_eq!(collision.triangle_count(), 8 * 12);
}
