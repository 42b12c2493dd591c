//! Every WGSL shader in `shaders/` parses and validates with naga, so a broken shader fails without a GPU.

use std::path::Path;

fn validate(path: &Path) -> Result<(), String> {
    let source = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let module = naga::front::wgsl::parse_str(&source)
        .map_err(|e| format!("{}: {}", path.display(), e.emit_to_string(&source)))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{}: {}", path.display(), e.emit_to_string(&source)))?;
    let entry_points: Vec<_> = module
        .entry_points
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    for needed in ["vs_main", "fs_main"] {
        if !entry_points.contains(&needed) {
            return Err(format!("{}: no entry point `{needed}`", path.display()));
        }
    }
    Ok(())
}

#[test]
fn every_shader_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .expect("shaders/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
        .collect();
    paths.sort();
    assert!(
        paths.len() >= 3,
        "expected the mesh, line and background shaders, found {paths:?}"
    );
    let failures: Vec<String> = paths.iter().filter_map(|p| validate(p).err()).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_broken_shader_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.wgsl");
    // Type error: assigning a vec3 to a vec4 output.
    std::fs::write(
        &path,
        "@vertex fn vs_main() -> @builtin(position) vec4<f32> { return vec3<f32>(0.0); }\n\
         @fragment fn fs_main() -> @location(0) vec4<f32> { return vec4<f32>(1.0); }\n",
    )
    .unwrap();
    assert!(validate(&path).is_err());
}
