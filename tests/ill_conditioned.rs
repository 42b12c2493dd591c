//! A real-like, ill-conditioned calibration on data from a simulator written apart from dualcal's
//! model (`tools/ill_conditioned_data.py`: its own URDF of a UR-like 6-joint industrial arm, the joint
//! origins perturbed in the URDF itself, its own forward kinematics `tools/urdf_fk.py`): one reflector,
//! 150 calibration configurations whose flange turns less than 10° (the three parallel pitch joints
//! moved together, base and wrist nearly still), 0.04 mm of tracker noise per axis and joint errors no
//! geometric model explains (`--harmonic-mrad 0.5`) — what a Leica-measured industrial arm looks
//! like, where the paper's BFGS SQP crawls (issue 47; docs/solver.md, "Curvature").

mod common;

use std::path::Path;
use std::process::Command;

/// `(termination, iterations)` of step 1 of `dualcal calibrate DATA ARGS…`.
fn step1(data: &Path, args: &[&str]) -> (String, usize) {
    let out = Command::new(env!("CARGO_BIN_EXE_dualcal"))
        .arg("calibrate")
        .arg(data)
        .args(["--quiet", "--out"])
        .arg(data.join("params.json"))
        .args(args)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("step 1 (left arm): ") && l.contains(" iterations"))
        .unwrap_or_else(|| panic!("no step-1 line in:\n{text}"));
    let rest = &line["step 1 (left arm): ".len()..];
    let (termination, tail) = rest.split_once(" after ").unwrap();
    let iterations = tail.split_whitespace().next().unwrap().parse().unwrap();
    (termination.to_string(), iterations)
}

#[test]
fn the_gauss_newton_curvature_converges_about_as_least_squares_does() {
    let python = common::python("numpy");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let (mut total_gn, mut total_lsq) = (0, 0);
    // Seed 1 is left out: there the data do not determine the reflector's offset along the flange's
    // axis, and every method runs off (a weak parameter to hold, not a curvature to tune).
    for seed in 2..=6 {
        let data = dir.path().join(format!("seed{seed}"));
        let made = Command::new(&python)
            .arg(root.join("tools/ill_conditioned_data.py"))
            .arg(&data)
            .args(["--seed", &seed.to_string(), "--harmonic-mrad", "0.5"])
            .output()
            .unwrap();
        assert!(
            made.status.success(),
            "{}",
            String::from_utf8_lossy(&made.stderr)
        );
        let spread: f64 = String::from_utf8_lossy(&made.stdout)
            .split_whitespace()
            .nth(3)
            .and_then(|v| v.parse().ok())
            .unwrap();
        assert!(spread <= 10.0, "the flange turned {spread}°");
        // The curvatures compared on one solve each: `--keep-weak`, or a weak parameter found
        // (this data's flange hardly turns) would solve step 1 again with it held, and the count
        // would be of two solves (docs/reliability.md, *Weak parameters*).
        let gn = step1(&data, &["--hessian", "gauss-newton", "--keep-weak"]);
        let bfgs = step1(&data, &["--hessian", "bfgs", "--keep-weak"]);
        let lsq = step1(&data, &["--method", "lsq", "--keep-weak"]);
        // The default curvature (`auto`) sees the ill-conditioning (condition numbers 600–710 here)
        // and takes Gauss–Newton: the same run.
        let auto = step1(&data, &["--keep-weak"]);
        assert_eq!(auto, gn, "seed {seed}: the default against Gauss–Newton");
        // The same data solve the same way every time: least squares' normal equations were once
        // summed in whatever order rayon's threads stole the work, and its stopping test fired 9 to
        // 12 iterations in on one data set from run to run (CI saw 9 where this machine saw 12).
        for again in 0..2 {
            let repeated = step1(&data, &["--method", "lsq", "--keep-weak"]);
            assert_eq!(
                repeated,
                lsq,
                "seed {seed}: least squares' run {}",
                again + 2
            );
        }
        eprintln!("seed {seed}: Gauss–Newton {gn:?}, BFGS {bfgs:?}, least squares {lsq:?}");
        for (name, (termination, _)) in [("Gauss–Newton", &gn), ("least squares", &lsq)] {
            assert!(
                termination.starts_with("converged"),
                "seed {seed}, {name}: {termination}"
            );
        }
        assert!(gn.1 < bfgs.1, "seed {seed}: {gn:?} against BFGS {bfgs:?}");
        assert!(
            gn.1 * 2 <= lsq.1 * 5,
            "seed {seed}: {} iterations against least squares' {}",
            gn.1,
            lsq.1
        );
        total_gn += gn.1;
        total_lsq += lsq.1;
    }
    // Over the seeds, within a quarter of least squares' iterations (measured: 100 against 87; the
    // paper's BFGS 173).
    assert!(
        total_gn * 4 <= total_lsq * 5,
        "{total_gn} iterations against least squares' {total_lsq}"
    );
}
