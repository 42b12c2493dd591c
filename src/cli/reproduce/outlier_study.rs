//! `dualcal reproduce outliers`: gross errors injected by the simulator, how many the screening catches,
//! how many good configurations it flags, and what the exclusion does to the verification accuracy
//! (docs/reliability.md).

use super::args::ReproduceArgs;
use crate::dataset::Split;
use crate::metrics::{self, AccuracyReport};
use crate::quality::{self, ScreenSettings};
use crate::robot::RobotDescription;
use crate::side::{ConfigId, Side};
use crate::simulate::{self, GrossError, GrossErrorModel, SimOptions};
use crate::solver::{CalibrationSettings, Calibrator};
use anyhow::Result;
use std::collections::BTreeSet;

/// Detection counts of one kind of gross error.
#[derive(Default, Clone, Copy)]
struct Caught {
    injected: usize,
    pre_fit: usize,
    caught: usize,
}

fn kind_of(e: &GrossError) -> usize {
    match e {
        GrossError::Misread { .. } => 0,
        GrossError::SwappedLabels { .. } => 1,
        GrossError::OtherArm { .. } => 2,
    }
}

const KIND_NAMES: [&str; 3] = [
    "reflector misread by 0.5–5 mm",
    "two reflector labels swapped",
    "row of the other arm",
];

fn three(r: &AccuracyReport, pick: fn(&metrics::AccuracyStats) -> f64) -> [f64; 3] {
    [
        r.relative_or_nan(Side::Left),
        r.relative_or_nan(Side::Right),
        r.collaborative_or_nan(),
    ]
    .map(|s| pick(&s))
}

fn fmt3(v: [f64; 3], digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).join(" / ")
}

/// What the study adds up over seeds.
#[derive(Default)]
struct Totals {
    kinds: [Caught; 3],
    false_alarms: usize,
    findings: usize,
    clean_configs: usize,
    /// Per seed: collaborative verification position RMS of a fit over the outlier-free fit's, for no
    /// exclusion, `--auto-exclude`, and the injected errors excluded.
    ratios: Vec<[f64; 3]>,
}

/// The gross-error model of the study, with the fractions the user gave.
fn gross_model(a: &ReproduceArgs) -> GrossErrorModel {
    let study = GrossErrorModel::study();
    GrossErrorModel {
        misread_fraction: a.misread_fraction.unwrap_or(study.misread_fraction),
        swapped_labels_fraction: a
            .swapped_labels_fraction
            .unwrap_or(study.swapped_labels_fraction),
        other_arm_fraction: a.other_arm_fraction.unwrap_or(study.other_arm_fraction),
        ..study
    }
}

fn print_header(a: &ReproduceArgs, gross: &GrossErrorModel) {
    outln!(
        "Outlier study: per arm {:.0}% of the configurations with a reflector misread by {}–{} mm, {:.0}% \
         with two reflector labels swapped, {:.0}% replaced by a row of the other arm{}; \
         `--auto-exclude` rule; verification accuracy on the outlier-free measurements of the same \
         verification configurations",
        100.0 * gross.misread_fraction,
        gross.misread_mm.0,
        gross.misread_mm.1,
        100.0 * gross.swapped_labels_fraction,
        100.0 * gross.other_arm_fraction,
        match a.joint_errors() {
            Some(j) => format!(
                "; unmodelled joint errors ({} mrad gear, {} mrad/m compliance)",
                j.periodic_amplitude_mrad, j.compliance_mrad_per_m
            ),
            None => String::new(),
        }
    );
    outln!(
        "| seed | injected | caught before fitting | caught | false alarms | excluded (L+R) | fit | ver pos RMS L/R/collab (mm) | ver pos max L/R/collab (mm) | ver ori RMS L/R/collab (rad) |"
    );
    outln!("|---:|---:|---:|---:|---:|---:|---|---|---|---|");
}

/// One seed: simulate with and without gross errors, screen, fit four ways, print its rows.
fn one_seed(
    a: &ReproduceArgs,
    robot: &RobotDescription,
    gross: GrossErrorModel,
    screen_settings: &ScreenSettings,
    seed: u64,
    t: &mut Totals,
) -> Result<()> {
    let base = SimOptions {
        joint_error: a.joint_errors(),
        ..simulate::paper_options(seed, 220, 120)
    };
    let clean = simulate::simulate_with_robot(&base, robot)?;
    let dirty = simulate::simulate_with_robot(
        &SimOptions {
            gross_errors: Some(gross),
            ..base.clone()
        },
        robot,
    )?;
    let nominal = &dirty.nominal;
    let injected: BTreeSet<ConfigId> = dirty.gross_errors.iter().map(|r| r.config).collect();
    let pre = quality::screen(&dirty.dataset, nominal, screen_settings);
    let pre_flagged: BTreeSet<ConfigId> = pre.suspects().into_iter().collect();
    let auto = crate::exclusion::auto_exclude(
        &dirty.dataset,
        nominal,
        Some(&pre),
        &CalibrationSettings::default(),
        screen_settings,
    )?;
    let mut flagged: BTreeSet<ConfigId> = auto.excluded.iter().map(|f| f.config).collect();
    flagged.extend(auto.screening.suspects());
    for r in &dirty.gross_errors {
        let k = &mut t.kinds[kind_of(&r.error)];
        k.injected += 1;
        k.pre_fit += usize::from(pre_flagged.contains(&r.config));
        k.caught += usize::from(flagged.contains(&r.config));
    }
    let alarms = flagged.difference(&injected).count();
    for f in pre.findings.iter().chain(&auto.screening.findings) {
        t.findings += 1;
        outln!("| {seed} | | | | | | finding: {} | | | |", f.message);
    }
    t.false_alarms += alarms;
    let n_configs: usize = dirty
        .dataset
        .arms
        .values()
        .map(|arm| arm.measurements.len())
        .sum();
    t.clean_configs += n_configs - injected.len();

    let fit = |ds: &crate::dataset::Dataset, exclude: Vec<ConfigId>| -> Result<AccuracyReport> {
        let result = Calibrator::new(ds, nominal)
            .settings(CalibrationSettings {
                exclude,
                ..CalibrationSettings::default()
            })
            .run()?;
        Ok(metrics::evaluate(
            &clean.dataset,
            &result.calibrated,
            Split::Ver,
        )?)
    };
    let outlier_free = fit(&clean.dataset, Vec::new())?;
    let unscreened = fit(&dirty.dataset, Vec::new())?;
    let oracle = fit(&dirty.dataset, injected.iter().copied().collect())?;
    let screened = metrics::evaluate(&clean.dataset, &auto.result.calibrated, Split::Ver)?;
    let excluded = |side| {
        auto.excluded
            .iter()
            .filter(|f| f.config.side == side)
            .count()
    };
    let rows = [
        ("outlier-free data", &outlier_free),
        ("no exclusion", &unscreened),
        ("--auto-exclude", &screened),
        ("injected excluded", &oracle),
    ];
    for (r, (name, report)) in rows.iter().enumerate() {
        let lead = if r == 0 {
            format!(
                "| {seed} | {} | {} | {} | {alarms} | {} + {} |",
                injected.len(),
                pre_flagged.intersection(&injected).count(),
                flagged.intersection(&injected).count(),
                excluded(crate::side::Side::Left),
                excluded(crate::side::Side::Right)
            )
        } else {
            "| | | | | | |".to_string()
        };
        outln!(
            "{lead} {name} | {} | {} | {} |",
            fmt3(three(report, |s| s.pos_rms_mm), 4),
            fmt3(three(report, |s| s.pos_max_mm), 4),
            fmt3(three(report, |s| s.ori_rms_rad.unwrap_or(f64::NAN)), 5)
        );
    }
    let collab = |r: &AccuracyReport| r.collaborative_or_nan().pos_rms_mm;
    t.ratios.push([
        collab(&unscreened) / collab(&outlier_free),
        collab(&screened) / collab(&outlier_free),
        collab(&oracle) / collab(&outlier_free),
    ]);
    if let Some(why) = &auto.stopped {
        outln!("| {seed} | | | | | | stopped: {why} | | | |");
    }
    Ok(())
}

fn print_summary(t: &Totals, n_seeds: usize) {
    outln!("");
    outln!("Summary over {} seed(s)", n_seeds);
    outln!("| gross error | injected | caught before fitting | caught |");
    outln!("|---|---:|---:|---:|");
    let mut total = Caught::default();
    for (k, c) in t.kinds.iter().enumerate() {
        total.injected += c.injected;
        total.pre_fit += c.pre_fit;
        total.caught += c.caught;
        outln!(
            "| {} | {} | {} ({:.1}%) | {} ({:.1}%) |",
            KIND_NAMES[k],
            c.injected,
            c.pre_fit,
            100.0 * c.pre_fit as f64 / c.injected.max(1) as f64,
            c.caught,
            100.0 * c.caught as f64 / c.injected.max(1) as f64
        );
    }
    outln!(
        "| all | {} | {} ({:.1}%) | {} ({:.1}%) |",
        total.injected,
        total.pre_fit,
        100.0 * total.pre_fit as f64 / total.injected.max(1) as f64,
        total.caught,
        100.0 * total.caught as f64 / total.injected.max(1) as f64
    );
    outln!(
        "\nFalse alarms: {} of {} good configurations ({:.2}%); whole-file \
         findings (none expected): {}.",
        t.false_alarms,
        t.clean_configs,
        100.0 * t.false_alarms as f64 / t.clean_configs.max(1) as f64,
        t.findings
    );
    let n = t.ratios.len().max(1) as f64;
    let mean = |i: usize| t.ratios.iter().map(|r| r[i]).sum::<f64>() / n;
    let worst = |i: usize| t.ratios.iter().map(|r| r[i]).fold(0.0, f64::max);
    outln!(
        "Collaborative verification position RMS relative to the outlier-free fit (mean, worst): \
         no exclusion {:.3}, {:.3}; --auto-exclude {:.3}, {:.3}; injected excluded {:.3}, {:.3}.",
        mean(0),
        worst(0),
        mean(1),
        worst(1),
        mean(2),
        worst(2)
    );
}

pub(crate) fn run(a: &ReproduceArgs, robot: &RobotDescription) -> Result<()> {
    let gross = gross_model(a);
    let screen_settings = ScreenSettings::default();
    print_header(a, &gross);
    let mut totals = Totals::default();
    for &seed in &a.seeds {
        one_seed(a, robot, gross, &screen_settings, seed, &mut totals)?;
    }
    print_summary(&totals, a.seeds.len());
    Ok(())
}
