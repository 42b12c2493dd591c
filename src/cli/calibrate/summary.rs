//! What `dualcal calibrate` prints of its result: the methods and what was identified, the
//! parameters' uncertainty, the accuracy before and after, the suspect configurations.

use crate::dataset::{Dataset, Split};
use crate::metrics;
use crate::params::StatisticsRecord;
use crate::quality;
use crate::side::{ConfigId, PerSide, Side};
use crate::solver::uncertainty::ArmUncertainty;
use crate::solver::{CalibrationResult, Stage};
use anyhow::Result;

/// Step 1's and step 2's methods, what each arm identified, the tracker frames, how each stage
/// ended; the solver's warnings; the total time.
pub(super) fn print_identifiability(result: &CalibrationResult) {
    let settings = &result.settings;
    outln!(
        "\nmethod: step 1 `{}`, step 2 `{}`",
        settings.method.name(),
        settings.base_method.name()
    );
    for (side, rep) in result.identifiability.iter() {
        let Some(rep) = rep else { continue };
        let extra = if settings.method.is_absolute() {
            format!(" and the 6 of tracker_from_{}_base", side.name())
        } else {
            String::new()
        };
        outln!(
            "\n{side} arm: {} of {} parameters identified{extra}; condition number {:.3e} → {:.3e}",
            rep.free.len(),
            result.nominal.arm(side).param_count(),
            rep.condition_before,
            rep.condition_after
        );
        if let Some(r) = result.reflector_used[side] {
            let arm = result.nominal.arm(side);
            let name = arm
                .reflector_names
                .get(r.index())
                .map_or("?", String::as_str);
            outln!(
                "  reflector {name} used ({}); the other reflectors' coordinates are nominal: the \
                 flange's orientation is not identified",
                settings.method.name()
            );
        }
        for f in &rep.fixed {
            outln!("  fixed {:<8} {}", f.name, f.reason);
        }
        for w in &result.weak[side] {
            outln!("  weak  {}", w.describe());
        }
    }
    for (side, t) in result.tracker_from_base.iter() {
        let Some(t) = t else { continue };
        let v = t.translation.vector;
        let w = t.rotation.scaled_axis();
        outln!(
            "tracker_from_{}_base: translation ({:.3}, {:.3}, {:.3}) mm, rotation vector ({:.6}, \
             {:.6}, {:.6}) rad",
            side.name(),
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    for s in &result.stages {
        outln!(
            "{}: {} after {} iterations, ψ {:.6} → {:.6} mm²",
            s.stage,
            s.termination,
            s.iterations,
            s.psi_start_mm2,
            s.psi_mm2
        );
        if result.settings.hessian == crate::solver::Hessian::Auto
            && s.curvature == Some(crate::solver::Hessian::GaussNewton)
            && let Stage::Arm(side) = s.stage
        {
            let condition = result.identifiability[side]
                .as_ref()
                .map_or(f64::NAN, |r| r.condition_after);
            outln!(
                "{}: Gauss–Newton curvature: the identified parameters' scaled Jacobian has \
                 condition number {condition:.0} at the start (above {:.0}: ill-conditioned data, \
                 where the paper's BFGS crawls; `--hessian bfgs` for it)",
                s.stage,
                crate::solver::AUTO_GAUSS_NEWTON_CONDITION
            );
        }
    }
    let reflectors = result.nominal.arm(Side::Left).reflector_count();
    if reflectors == 1 {
        outln!(
            "one reflector per arm: ψ is that reflector's summed squared distance errors (the minimax \
             of step 1 is a least-squares fit); the flange's orientation is not measurable"
        );
    } else if reflectors == 2 {
        outln!(
            "two reflectors per arm: ψ is the larger of their summed squared distance errors; the \
             flange's orientation is not measurable"
        );
    }
    if let Some(why) = &result.base_not_measurable {
        outln!(
            "{}: not measurable from this data ({why}); the base is nominal",
            crate::solver::Stage::Base
        );
    }
    for warning in result.warnings() {
        eprintln!("warning: {warning}");
    }
    outln!("total time {:.3} s", result.elapsed_secs);
}

/// Each arm's parameter uncertainty in a few lines (the parameter file has every σ).
pub(super) fn print_uncertainty(u: &PerSide<Option<ArmUncertainty>>) {
    for (side, u) in u.iter() {
        let Some(u) = u else { continue };
        let largest = |unit: &str| {
            u.largest(unit).map_or(String::new(), |p| {
                format!("{:.4} {unit} ({})", p.sigma, p.name)
            })
        };
        outln!(
            "{side} arm: 1σ of the identified parameters (from the residuals: point noise {:.4} mm per axis; {} configurations): largest {}, {}; condition number {:.1}",
            u.point_sigma_mm,
            u.configurations,
            largest("mm"),
            largest("mrad"),
            u.condition
        );
        // The errors beyond geometry, each unit once (`--model`).
        let mut units: Vec<&str> = Vec::new();
        for p in &u.parameters {
            if p.unit != "mm" && p.unit != "mrad" && !units.contains(&p.unit.as_str()) {
                units.push(&p.unit);
            }
        }
        if !units.is_empty() {
            let parts: Vec<String> = units.iter().map(|unit| largest(unit)).collect();
            outln!("  beyond geometry: largest {}", parts.join(", "));
        }
        if !u.correlations.is_empty() {
            let pairs: Vec<String> = u
                .correlations
                .iter()
                .take(5)
                .map(|c| format!("{}–{} {:+.2}", c.a, c.b, c.correlation))
                .collect();
            outln!(
                "  {} pair(s) correlated beyond ±{}: {}{}",
                u.correlations.len(),
                crate::solver::uncertainty::REPORTED_CORRELATION,
                pairs.join(", "),
                if u.correlations.len() > 5 {
                    ", …"
                } else {
                    ""
                }
            );
        }
    }
}

/// Nominal vs calibrated, on the calibration and verification splits of `ds`; the calibrated
/// model's figures taken from `recorded` (the parameter file's record of them on `ds`) where it has
/// them.
pub fn comparison_table(
    ds: &Dataset,
    result: &CalibrationResult,
    recorded: Option<&StatisticsRecord>,
) -> Result<String> {
    use crate::par::prelude::*;
    let splits = [(Split::Cal, "calibration"), (Split::Ver, "verification")];
    // The splits' figures side by side (each computed as alone: the same numbers), printed in order.
    let figures: Vec<Option<(metrics::AccuracyReport, metrics::AccuracyReport)>> = splits
        .into_par_iter()
        .map(|(split, _)| -> Result<_> {
            if !metrics::has_split(ds, split) {
                return Ok(None);
            }
            let before = metrics::evaluate(ds, &result.nominal, split)?;
            let record = recorded.and_then(|r| if split == Split::Cal { r.cal } else { r.ver });
            let after = match record {
                Some(report) => report,
                None => metrics::evaluate(ds, &result.calibrated, split)?,
            };
            Ok(Some((before, after)))
        })
        .collect::<Result<_>>()?;
    let mut out = String::new();
    for ((_, name), figures) in splits.into_iter().zip(figures) {
        let Some((before, after)) = figures else {
            continue;
        };
        out.push_str(&format!(
            "Accuracy on the {name} configurations (nominal → calibrated)\n"
        ));
        out.push_str(&metrics::format_comparison_named(
            &before,
            &after,
            ["nominal", "calibrated"],
            &ds.reflector_names,
        ));
        out.push('\n');
    }
    Ok(out)
}

/// The suspect configurations, one line each (most severe flag first).
pub(super) fn print_flags(title: &str, screening: &quality::Screening, excluded: &[ConfigId]) {
    let worst = screening.worst_per_config();
    if worst.is_empty() {
        return;
    }
    outln!("\n{title} ({}):", worst.len());
    for f in &worst {
        let mark = if excluded.contains(&f.config) {
            "excluded"
        } else {
            "kept"
        };
        outln!(
            "  {:<5} {:<10} line {:<5} {:<3} {:<14} {:>9.3} mm  {:<8}  {}",
            f.config.side.name(),
            crate::textfile::excerpt(&f.id),
            f.line,
            f.split.name(),
            f.kind.label(),
            f.size_mm,
            mark,
            f.reason
        );
    }
}

/// Warn about suspect configurations the calibration kept, and about whole-file findings.
pub(super) fn warn_suspects_kept(after: &quality::Screening, excluded: &[ConfigId]) {
    let suspects_kept: Vec<String> = after
        .worst_per_config()
        .iter()
        .filter(|f| !excluded.contains(&f.config))
        .map(|f| f.id.clone())
        .collect();
    if !suspects_kept.is_empty() {
        let shown = suspects_kept.len().min(10);
        eprintln!(
            "warning: {} suspect configuration(s) were used for the calibration; the minimax fit is \
             steered by its worst point: look at them, then --exclude {}{} or --auto-exclude",
            suspects_kept.len(),
            suspects_kept[..shown].join(","),
            if shown < suspects_kept.len() {
                ",…"
            } else {
                ""
            }
        );
    }
    for f in &after.findings {
        eprintln!("warning: {f}");
    }
}
