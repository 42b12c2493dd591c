//! What `reproduce paper` runs (the seeds or the user's dataset, Fig. 4's sizes, the methods) and
//! what each run gives.

use super::super::args::ReproduceArgs;
use crate::comparison::{self, Comparison, MethodEntry};
use crate::metrics::AccuracyReport;
use crate::simulate::JointErrorModel;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

/// Configurations per arm of the paper's protocol (§4.1), and of them for calibration.
const PAPER_CONFIGS: (usize, usize) = (220, 120);
/// The calibration set sizes of Fig. 4 (the paper's twelve subsets).
pub(crate) const FIG4_SIZES: [usize; 12] = [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120];
/// Fig. 4's calibration set sizes for `--quick`.
const QUICK_SIZES: [usize; 3] = [20, 60, 120];

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
    pub(super) fn new(a: &ReproduceArgs) -> Result<Self> {
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
