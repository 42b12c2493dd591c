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
mod plots;
mod tables;

use super::args::ReproduceArgs;
use crate::cli::common::load_workspace;
use crate::comparison::{self, Comparison, MethodEntry};
use crate::dataset::{Dataset, Split};
use crate::metrics::AccuracyReport;
use crate::output::{Overwrite, refuse_existing, write_atomic};
use crate::robot::RobotDescription;
use crate::side::Side;
use crate::simulate::{self, JointErrorModel, SimOptions};
use crate::solver::CalibrationSettings;
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Configurations per arm of the paper's protocol (§4.1), and of them for calibration.
const PAPER_CONFIGS: (usize, usize) = (220, 120);
/// The calibration set sizes of Fig. 4 (the paper's twelve subsets).
pub(crate) const FIG4_SIZES: [usize; 12] = [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120];
/// Fig. 4's calibration set sizes for `--quick`.
const QUICK_SIZES: [usize; 3] = [20, 60, 120];

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

/// What the study runs.
pub(crate) struct Plan {
    /// The simulation seeds (one run per seed); empty with a dataset of the user's.
    pub seeds: Vec<u64>,
    pub dataset: Option<PathBuf>,
    /// Configurations per arm and of them for calibration (simulation).
    pub configs: (usize, usize),
    /// Fig. 4's calibration set sizes.
    pub sizes: Vec<usize>,
    pub joint_errors: Option<JointErrorModel>,
    pub methods: Vec<MethodEntry>,
    pub quick: bool,
    /// The command line that reproduces the run, for the report.
    pub command: String,
}

impl Plan {
    fn new(a: &ReproduceArgs) -> Result<Self> {
        let configs = PAPER_CONFIGS;
        let sizes = match &a.sizes {
            Some(s) => s.clone(),
            None if a.quick => QUICK_SIZES.to_vec(),
            None => FIG4_SIZES.to_vec(),
        };
        if a.dataset.is_some() && a.seeds != [1] {
            bail!("--seeds simulates; with --dataset the study runs once on that dataset");
        }
        if a.dataset.is_some() && a.joint_errors().is_some() {
            bail!(
                "--unmodelled, --joint-error-mrad and --compliance-mrad-per-m simulate; not with --dataset"
            );
        }
        if a.dataset.is_none()
            && let Some(&n) = sizes.iter().find(|&&n| n > configs.1 || n < 2)
        {
            bail!(
                "--sizes: {n} calibration configurations; the simulation has {} per arm",
                configs.1
            );
        }
        let methods = match &a.methods {
            None => comparison::METHODS.to_vec(),
            Some(keys) => keys
                .iter()
                .map(|k| {
                    comparison::method(k.trim()).copied().with_context(|| {
                        let known: Vec<&str> = comparison::METHODS.iter().map(|m| m.key).collect();
                        format!("--methods: no method `{k}` (known: {})", known.join(", "))
                    })
                })
                .collect::<Result<_>>()?,
        };
        let mut seeds = a.seeds.clone();
        seeds.sort_unstable();
        seeds.dedup();
        Ok(Self {
            seeds: if a.dataset.is_some() {
                Vec::new()
            } else {
                seeds
            },
            dataset: a.dataset.clone(),
            configs,
            sizes,
            joint_errors: a.joint_errors(),
            methods,
            quick: a.quick,
            command: command_line(a),
        })
    }

    /// The methods of the step-1 comparison.
    pub fn arm_methods(&self) -> Vec<MethodEntry> {
        self.methods
            .iter()
            .filter(|m| m.role.compares_arms())
            .copied()
            .collect()
    }

    /// The methods of the step-2 comparison.
    pub fn base_methods(&self) -> Vec<MethodEntry> {
        self.methods
            .iter()
            .filter(|m| m.role.compares_base())
            .copied()
            .collect()
    }

    /// What the data are, for the report.
    pub fn describe_data(&self) -> String {
        match &self.dataset {
            Some(p) => format!("the dataset {}", p.display()),
            None => {
                let errors = match self.joint_errors {
                    None => {
                        "geometric errors only (DH parameters, reflectors, base), tracker noise \
                             from its MPE"
                            .to_owned()
                    }
                    Some(j) => format!(
                        "geometric errors, tracker noise, and unmodelled joint errors: a {} mrad gear \
                         error {} times per revolution on every joint and {} mrad/m compliance",
                        j.periodic_amplitude_mrad, j.periods_per_rev, j.compliance_mrad_per_m
                    ),
                };
                format!(
                    "simulated{} ({}; {} configurations per arm, {} calibration + {} verification; seed{} {})",
                    if self.quick {
                        ", the quick version"
                    } else {
                        ""
                    },
                    errors,
                    self.configs.0,
                    self.configs.1,
                    self.configs.0 - self.configs.1,
                    if self.seeds.len() == 1 { "" } else { "s" },
                    self.seeds
                        .iter()
                        .map(u64::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        }
    }
}

fn command_line(a: &ReproduceArgs) -> String {
    let mut c = String::from("dualcal reproduce paper");
    if a.quick {
        c.push_str(" --quick");
    }
    if let Some(d) = &a.dataset {
        c.push_str(&format!(" --dataset {}", d.display()));
    } else {
        let seeds: Vec<String> = a.seeds.iter().map(u64::to_string).collect();
        c.push_str(&format!(" --seeds {}", seeds.join(",")));
    }
    if let Some(j) = a.joint_errors() {
        c.push_str(&format!(
            " --joint-error-mrad {} --compliance-mrad-per-m {}",
            j.periodic_amplitude_mrad, j.compliance_mrad_per_m
        ));
    }
    if let Some(s) = &a.sizes {
        let s: Vec<String> = s.iter().map(usize::to_string).collect();
        c.push_str(&format!(" --sizes {}", s.join(",")));
    }
    if let Some(m) = &a.methods {
        c.push_str(&format!(" --methods {}", m.join(",")));
    }
    c.push_str(" --out DIR");
    c
}

/// One point of Fig. 4: the step-1 method `key` calibrated on the first `n` calibration configurations.
pub(crate) struct Fig4Point {
    pub n: usize,
    pub key: &'static str,
    /// The figures on those n configurations and on the verification configurations; `None` when the
    /// method could not run.
    pub cal: Option<AccuracyReport>,
    pub ver: Option<AccuracyReport>,
}

/// Everything one seed (or the user's dataset) gave.
pub(crate) struct SeedRun {
    /// The seed, `None` for the user's dataset.
    pub seed: Option<u64>,
    pub comparison: Comparison,
    pub fig4: Vec<Fig4Point>,
}

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
    let report = tables::report(&plan, &runs, &tables, elapsed);
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
    let common = CalibrationSettings::default();
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
