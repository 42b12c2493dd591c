//! `dualcal reproduce`'s arguments: the study and its simulation.

use crate::simulate;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum Study {
    /// Paper Fig. 4: accuracy against the number of calibration configurations.
    Fig4,
    /// The paper's subgradient QP against the exact QP (docs/solver.md).
    Qp,
    /// Minimax against least squares with unmodelled joint errors and outliers (docs/solver.md).
    Robustness,
    /// Gross errors (misread reflectors, swapped labels, rows of the other arm): detection, false
    /// alarms, accuracy with and without exclusion (docs/reliability.md).
    Outliers,
    /// The paper's comparison of methods: Tables 4–8 and Figs. 4, 6–8 as CSV, SVG and a Markdown
    /// report in --out (docs/reproduction.md).
    Paper,
}

#[derive(Args, Debug)]
pub struct ReproduceArgs {
    #[arg(value_enum)]
    pub study: Study,
    /// Simulation seed(s), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub seeds: Vec<u64>,
    /// Calibration set sizes for fig4 and paper [default: 10,20,…,120; paper --quick: 20,60,120].
    #[arg(long, value_delimiter = ',')]
    pub sizes: Option<Vec<usize>>,
    /// Use this dataset instead of simulating (fig4 and paper).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Paper study: the output directory (created) for the CSVs, the SVG figures and report.md.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Paper study: replace outputs that already exist in --out.
    #[arg(long)]
    pub force: bool,
    /// Paper study: the quick version the tests run (one seed unless --seeds; Fig. 4 at 20, 60 and 120
    /// calibration configurations instead of twelve sizes).
    #[arg(long)]
    pub quick: bool,
    /// Paper study: only these methods (keys of `comparison::METHODS`, comma separated) [default: all].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Simulate with unmodelled joint errors (1 mrad gear error, 0.5 mrad/m compliance) — a paper-like
    /// residual of ~0.4 mm after calibration (fig4 and qp).
    #[arg(long)]
    pub unmodelled: bool,
    /// With --unmodelled (implied; all studies): amplitude of the periodic (gear) joint error, mrad,
    /// instead of 1.
    #[arg(long)]
    pub joint_error_mrad: Option<f64>,
    /// With --unmodelled (implied; all studies): joint compliance, mrad/m, instead of 0.5.
    #[arg(long)]
    pub compliance_mrad_per_m: Option<f64>,
    /// Outliers study: fraction of each arm's configurations with a misread reflector (default 0.03).
    #[arg(long)]
    pub misread_fraction: Option<f64>,
    /// Outliers study: fraction with two reflector labels swapped (default 0.01).
    #[arg(long)]
    pub swapped_labels_fraction: Option<f64>,
    /// Outliers study: fraction replaced by a row of the other arm (default 0.01).
    #[arg(long)]
    pub other_arm_fraction: Option<f64>,
}

impl ReproduceArgs {
    /// The unmodelled joint errors of the study, if any.
    pub(crate) fn joint_errors(&self) -> Option<simulate::JointErrorModel> {
        let custom = self.joint_error_mrad.is_some() || self.compliance_mrad_per_m.is_some();
        (self.unmodelled || custom).then(|| {
            let default = simulate::unmodelled_joint_errors();
            simulate::JointErrorModel {
                periodic_amplitude_mrad: self
                    .joint_error_mrad
                    .unwrap_or(default.periodic_amplitude_mrad),
                compliance_mrad_per_m: self
                    .compliance_mrad_per_m
                    .unwrap_or(default.compliance_mrad_per_m),
                ..default
            }
        })
    }
}
