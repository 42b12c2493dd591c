//! `dualcal reproduce paper`: the paper's comparison of calibration methods (Tables 4–8, Figs. 4, 6–8)
//! on simulated data of its protocol, or on a dataset of the user's.
//!
//! Per seed: simulate (220 configurations per arm, 120 for calibration, 100 for verification; with
//! unmodelled joint errors on request), run every method of [`comparison::METHODS`] through the engine's
//! [`comparison::compare`], evaluate the nominal and the true model, and repeat the step-1 methods on
//! the first n calibration configurations for Fig. 4. Then the tables (mean ± standard deviation over the
//! seeds) go to CSV files and a Markdown report beside the paper's numbers, the figures to SVG files.
//!
//! `--quick` is the version the tests run: one seed unless `--seeds` says otherwise (the paper's
//! protocol, 220 configurations per arm), Fig. 4 at 20, 60 and 120 calibration configurations instead
//! of twelve sizes.

mod paper_values;
mod plan;
mod plots;
mod report;
mod tables;

use super::args::ReproduceArgs;
use crate::cli::common::load_workspace;
use crate::comparison;
use crate::dataset::{Dataset, Split};
use crate::output::{Overwrite, refuse_existing, write_atomic};
use crate::robot::RobotDescription;
use crate::side::Side;
use crate::simulate::{self, SimOptions};
use crate::solver::CalibrationSettings;
use anyhow::{Context, Result, bail};
pub(crate) use plan::FIG4_SIZES;
use plan::{Fig4Point, Plan, SeedRun};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Every file the study writes into `--out`.
pub(crate) const OUTPUT_FILES: [&str; 15] = [
    "report.md",
    "runs.csv",
    tables::TABLE4_CSV,
    tables::TABLE5_CSV,
    tables::TABLE6_CSV,
    tables::TABLE7_CSV,
    tables::TABLE8_CSV,
    tables::FIG4_CSV,
    plots::FIG4_SVG,
    plots::FIG6_RIGHT_SVG,
    plots::FIG6_LEFT_SVG,
    plots::FIG7_SVG,
    plots::FIG8_SVG,
    plots::HISTOGRAMS_CSV,
    plots::BOXPLOTS_CSV,
];

pub(crate) fn run(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    let Some(out_dir) = a.out.clone() else {
        bail!(
            "`reproduce paper` needs --out DIR (the tables, figures and report are written there)"
        );
    };
    let plan = Plan::new(a)?;
    let overwrite = if a.force {
        Overwrite::Allow
    } else {
        Overwrite::Refuse
    };
    let paths: Vec<PathBuf> = OUTPUT_FILES.iter().map(|f| out_dir.join(f)).collect();
    refuse_existing(
        &paths.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
        overwrite,
    )
    .context("pass --force to replace the outputs of an earlier run")?;
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;

    let started = Instant::now();
    let runs = match &plan.dataset {
        Some(path) => {
            let ws = load_workspace(path)?;
            let input = comparison::CompareInput {
                dataset: &ws.dataset,
                nominal: &ws.nominal,
                truth: None,
                body_from_left_base: ws.robot.body_from_arm_base(Side::Left),
            };
            vec![run_one(&plan, None, input)?]
        }
        None => plan
            .seeds
            .iter()
            .map(|&seed| {
                let opts = SimOptions {
                    joint_error: plan.joint_errors,
                    ..simulate::paper_options(seed, plan.configs.0, plan.configs.1)
                };
                let sim = simulate::simulate_with_robot(&opts, robot)
                    .with_context(|| format!("simulating seed {seed}"))?;
                let input = comparison::CompareInput {
                    dataset: &sim.dataset,
                    nominal: &sim.nominal,
                    truth: Some(&sim.truth),
                    body_from_left_base: robot.body_from_arm_base(Side::Left),
                };
                run_one(&plan, Some(seed), input)
            })
            .collect::<Result<Vec<_>>>()?,
    };
    let elapsed = started.elapsed().as_secs_f64();

    let tables = tables::build(&plan, &runs);
    let write = |name: &str, bytes: &[u8]| -> Result<()> {
        let path = out_dir.join(name);
        write_atomic(&path, bytes).with_context(|| format!("writing {}", path.display()))
    };
    for t in &tables.tables {
        write(t.file, t.to_csv()?.as_bytes())?;
    }
    write(tables::FIG4_CSV, tables.fig4_csv.as_bytes())?;
    write("runs.csv", tables::runs_csv(&runs)?.as_bytes())?;
    let figures = plots::draw(&plan, &runs)?;
    for (name, bytes) in &figures.files {
        write(name, bytes)?;
    }
    let report = report::report(&plan, &runs, &tables, elapsed);
    write("report.md", report.as_bytes())?;
    outln!("{report}");
    outln!(
        "wrote {} files into {} in {:.1} s",
        OUTPUT_FILES.len(),
        out_dir.display(),
        elapsed
    );
    debug_assert!(
        OUTPUT_FILES
            .iter()
            .all(|f| Path::new(&out_dir).join(f).is_file())
    );
    Ok(())
}

/// The comparison and Fig. 4 on one dataset.
fn run_one(plan: &Plan, seed: Option<u64>, input: comparison::CompareInput<'_>) -> Result<SeedRun> {
    let ds = input.dataset;
    let what = seed.map_or_else(|| "dataset".to_owned(), |s| format!("seed {s}"));
    // The paper's BFGS, as published (the report says so).
    let common = CalibrationSettings {
        hessian: crate::solver::Hessian::Bfgs,
        ..CalibrationSettings::default()
    };
    let cancel = Arc::new(AtomicBool::new(false));
    let mut progress = |e: comparison::ComparisonEvent| {
        if let comparison::ComparisonEvent::MethodFinished {
            key,
            error: Some(e),
            ..
        } = e
        {
            eprintln!("warning: {what}: {key}: {e}");
        }
    };
    let t = Instant::now();
    let comparison = comparison::compare(&input, &plan.methods, &common, &cancel, &mut progress)
        .with_context(|| format!("{what}: the comparison"))?;
    for m in &comparison.methods {
        if let Some(run) = m.run() {
            for w in run.result.warnings() {
                eprintln!("warning: {what}: {}: {w}", m.entry.key);
            }
        }
    }
    eprintln!(
        "{what}: {} methods in {:.1} s",
        comparison.methods.len(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let arm_methods = plan.arm_methods();
    let n_cal = min_cal_configs(ds);
    let mut fig4 = Vec::new();
    for &n in &plan.sizes {
        if n > n_cal {
            eprintln!(
                "warning: {what}: Fig. 4 at {n} configurations skipped: only {n_cal} calibration configurations"
            );
            continue;
        }
        let sub = ds.with_cal_subset(n);
        let input = comparison::CompareInput {
            dataset: &sub,
            truth: None,
            ..input
        };
        let c = comparison::compare(&input, &arm_methods, &common, &cancel, &mut |_| {})
            .with_context(|| format!("{what}: Fig. 4 with {n} configurations"))?;
        for m in &c.methods {
            fig4.push(Fig4Point {
                n,
                key: m.entry.key,
                cal: m.figures().and_then(|f| f.report(Split::Cal)).copied(),
                ver: m.figures().and_then(|f| f.report(Split::Ver)).copied(),
            });
        }
    }
    eprintln!(
        "{what}: Fig. 4 ({} sizes) in {:.1} s",
        plan.sizes.len(),
        t.elapsed().as_secs_f64()
    );
    Ok(SeedRun {
        seed,
        comparison,
        fig4,
    })
}

/// The smaller arm's number of calibration configurations.
fn min_cal_configs(ds: &Dataset) -> usize {
    crate::side::Side::BOTH
        .iter()
        .map(|&s| {
            ds.arm(s)
                .measurements
                .iter()
                .filter(|m| m.split == Split::Cal)
                .count()
        })
        .min()
        .unwrap_or(0)
}
