//! The engine's layers (docs/architecture.md): every module of the crate uses only modules of the
//! layers below its own, so no arrow runs back up — the screening never calls the solver, the data
//! never reach for the robot, the engine never for the workbench. Read from the source: every
//! `crate::module` a module's code (not its comments, not its tests) names.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Bottom first. A module may use the modules of the layers before its own.
const LAYERS: &[&[&str]] = &[
    // The parallel loops (rayon, or in order in a browser); the sorts (one compiled sort in a browser).
    &["par", "sort"],
    // Leaves: values, statistics, where files come from and what they are, atomic writes.
    &[
        "side",
        "stats",
        "source",
        "output",
        "finite_difference",
        "choice",
    ],
    // Text files, the arm models (DH and URDF chains), meshes.
    &["textfile", "kinematics", "meshes"],
    // Measurements.
    &["dataset"],
    // The robot description (URDF, arms, shapes).
    &["robot"],
    // What is computed from a model and the data, and what is exported of a robot.
    &[
        "metrics",
        "collision",
        "urdf_export",
        "import",
        "controller",
    ],
    // The screening, the solver, the simulator, the figures of a model.
    &["quality", "solver", "simulate", "analysis"],
    // What combines them: the load pipeline, exclusion and re-fit, the comparison, the parameter file,
    // the measurement's plan (designed for the parameters the solver's analysis frees).
    &["workspace", "exclusion", "comparison", "params", "plan"],
    // What reports on a calibration: the HTML report (parameter file, figures, screening); the front
    // door (the crate root's Dataset, Robot, Calibration, Calibrated: load, fit, figures, exports).
    &["report", "api"],
    // The command line, then the workbench.
    &["cli"],
    &["app"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// The `.rs` files of a module (its file, or every file under its folder), tests left out.
fn files_of(src: &Path, module: &str) -> Vec<PathBuf> {
    let file = src.join(format!("{module}.rs"));
    let dir = src.join(module);
    let mut out = Vec::new();
    if file.is_file() {
        out.push(file);
    }
    let mut stack = vec![dir];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                if name != "tests" {
                    stack.push(p);
                }
            } else if name.ends_with(".rs") && name != "tests.rs" {
                out.push(p);
            }
        }
    }
    out
}

/// The crate's modules a file's code names (`crate::x`), comments and its inline test module left out.
fn uses(text: &str) -> BTreeSet<String> {
    let code = match text.find("#[cfg(test)]\nmod tests {") {
        Some(k) => &text[..k],
        None => text,
    };
    let mut out = BTreeSet::new();
    for line in code.lines() {
        let line = match line.find("//") {
            Some(k) => &line[..k],
            None => line,
        };
        let mut rest = line;
        while let Some(k) = rest.find("crate::") {
            rest = &rest[k + "crate::".len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

#[test]
fn no_module_uses_one_of_a_higher_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let modules: Vec<String> = lib
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            l.strip_prefix("pub mod ")
                .or_else(|| l.strip_prefix("mod "))
        })
        .map(|m| m.trim_end_matches(';').to_string())
        .collect();
    assert!(modules.len() > 10, "{modules:?}");
    let mut problems = Vec::new();
    let mut arrows: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for m in &modules {
        let Some(own) = layer_of(m) else {
            problems.push(format!(
                "`{m}` is in no layer: add it to LAYERS and docs/architecture.md"
            ));
            continue;
        };
        for file in files_of(&src, m) {
            let text = std::fs::read_to_string(&file).unwrap();
            for used in uses(&text) {
                if &used == m || !modules.contains(&used) {
                    continue;
                }
                arrows.entry(m.clone()).or_default().insert(used.clone());
                match layer_of(&used) {
                    Some(l) if l < own => {}
                    _ => problems.push(format!(
                        "{}: `{m}` (layer {own}) uses `{used}` (layer {:?})",
                        file.strip_prefix(&src).unwrap().display(),
                        layer_of(&used)
                    )),
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The arrows the docs speak of are there (the test reads what it claims to read).
    assert!(arrows["workspace"].contains("quality") && arrows["workspace"].contains("robot"));
    assert!(arrows["exclusion"].contains("solver") && arrows["exclusion"].contains("quality"));
    assert!(!arrows["quality"].contains("solver"));
    assert!(!arrows["dataset"].contains("robot") && !arrows["dataset"].contains("quality"));
    assert!(arrows["report"].contains("params") && arrows["report"].contains("analysis"));
}

/// The modules of a folder (its files and subfolders, `mod.rs` left out).
fn modules_in(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter_map(|p| {
            let name = p.file_name()?.to_string_lossy().into_owned();
            match name.strip_suffix(".rs") {
                Some("mod") => None,
                Some(stem) => Some(stem.to_string()),
                None => p.is_dir().then_some(name),
            }
        })
        .collect()
}

/// The rooms of solver/ (issue 46): each `mod.rs` only declares and re-exports; a module reaches the
/// others by their own paths — `super::x` only for a sibling module `x`, `crate::solver::x` only for
/// a folder or file `x` of solver/ — never through its parent's items or re-exports, never by
/// `super::super`.
#[test]
fn solver_modules_only_reach_down_or_across() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/solver");
    let top = modules_in(&root);
    let mut problems = Vec::new();
    let mut seen = 0;
    for file in files_of(root.parent().unwrap(), "solver") {
        let text = std::fs::read_to_string(&file).unwrap();
        let code = match text.find("#[cfg(test)]\nmod tests {") {
            Some(k) => &text[..k],
            None => &text[..],
        };
        let code: String = code
            .lines()
            .map(|l| l.find("//").map_or(l, |k| &l[..k]))
            .collect::<Vec<_>>()
            .join("\n");
        let is_mod = file.file_name().unwrap() == "mod.rs";
        // A folder's mod.rs is its module; a file's siblings are the files beside it.
        let dir = file.parent().unwrap();
        let siblings = modules_in(if is_mod { dir.parent().unwrap() } else { dir });
        let name = file.strip_prefix(&root).unwrap().display().to_string();
        if code.contains("super::super") {
            problems.push(format!("{name}: `super::super`"));
        }
        for (prefix, allowed) in [("crate::solver::", &top), ("super::", &siblings)] {
            for (k, _) in code.match_indices(prefix) {
                let rest = &code[k + prefix.len()..];
                let names: Vec<&str> = match rest.strip_prefix('{') {
                    Some(group) => group[..group.find('}').unwrap_or(group.len())]
                        .split(',')
                        .map(|s| s.trim().split("::").next().unwrap_or(""))
                        .collect(),
                    None => vec![
                        rest.split(|c: char| !c.is_alphanumeric() && c != '_')
                            .next()
                            .unwrap(),
                    ],
                };
                for n in names.into_iter().filter(|n| !n.is_empty() && *n != "*") {
                    seen += 1;
                    if !allowed.contains(n) {
                        problems.push(format!("{name}: `{prefix}{n}` is not a module of its own"));
                    }
                }
            }
        }
        if is_mod {
            let mut body = code.clone();
            while let Some(k) = body.find("pub use ") {
                let end = body[k..].find(';').map_or(body.len(), |e| k + e + 1);
                body.replace_range(k..end, "");
            }
            for line in body.lines().map(str::trim).filter(|l| !l.is_empty()) {
                let declares =
                    line.ends_with(';') && ["mod ", "pub mod "].iter().any(|p| line.starts_with(p));
                if !declares && line != "#[cfg(test)]" {
                    problems.push(format!(
                        "{name}: `{line}` in a mod.rs (only declarations and re-exports)"
                    ));
                }
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The test reads what it claims to read.
    assert!(
        seen > 50 && top.contains("methods") && top.contains("types"),
        "{seen} {top:?}"
    );
}

/// The engine parses nothing from a command line: its enums parse from strings (`FromStr`, through
/// `dualcal::choice`), and only the command line (`cli`) and the workbench (`app`) know clap.
#[test]
fn only_the_command_line_knows_clap() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut problems = Vec::new();
    for layer in LAYERS {
        for m in layer.iter().filter(|m| !["cli", "app", "main"].contains(m)) {
            for file in files_of(&src, m) {
                let text = std::fs::read_to_string(&file).unwrap();
                if text.contains("clap::") || text.contains("use clap") {
                    problems.push(file.strip_prefix(&src).unwrap().display().to_string());
                }
            }
        }
    }
    assert!(problems.is_empty(), "engine files using clap: {problems:?}");
}
