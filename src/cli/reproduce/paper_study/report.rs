//! The Markdown report of `reproduce paper`.

use super::plan::{Plan, SeedRun};
use super::tables::{
    Model, Pick, THREE, Tables, fmt_num, own_reflector_rms, ratio_summary, summary, ver_stat,
};
use crate::comparison::{MethodEntry, Observes};
use crate::side::Side;
use std::fmt::Write as _;

/// The four figures the ratio tables compare.
const PICKS: [(&str, Pick); 4] = [
    ("pos RMS*", |s| s.pos_rms_mm),
    ("pos max", |s| s.pos_max_mm),
    ("ori RMS", |s| s.ori_rms_rad.unwrap_or(f64::NAN)),
    ("ori max", |s| s.ori_max_rad.unwrap_or(f64::NAN)),
];

/// How each method ended: converged runs, iterations per stage, calibration time.
fn terminations(out: &mut String, plan: &Plan, runs: &[SeedRun]) {
    let _ = writeln!(
        out,
        "| method | runs converged (all stages) | iterations L / R / base (mean) | calibration time (s, mean) |\n|---|---:|---|---:|"
    );
    for m in &plan.methods {
        let outcomes: Vec<_> = runs
            .iter()
            .filter_map(|r| r.comparison.method(m.key))
            .collect();
        let ok: Vec<_> = outcomes.iter().filter_map(|o| o.run()).collect();
        let converged = ok.iter().filter(|r| r.result.is_converged()).count();
        let iters: Vec<String> = (0..3)
            .map(|k| {
                let v: Vec<f64> = ok
                    .iter()
                    .filter_map(|r| r.result.stages.get(k).map(|s| s.iterations as f64))
                    .collect();
                fmt_num(summary(&v).0, 1)
            })
            .collect();
        let secs: Vec<f64> = ok.iter().map(|r| r.result.elapsed_secs).collect();
        let failed = outcomes.len() - ok.len();
        let _ = writeln!(
            out,
            "| {} | {converged} of {}{} | {} | {} |",
            m.title(),
            outcomes.len(),
            if failed > 0 {
                format!(" ({failed} could not run)")
            } else {
                String::new()
            },
            iters.join(" / "),
            fmt_num(summary(&secs).0, 3)
        );
    }
}

/// Each method's verification figures over the true parameters' (1.00 = the noise floor).
fn against_truth(out: &mut String, plan: &Plan, runs: &[SeedRun], picks: &[(&str, Pick)]) {
    let _ = writeln!(
        out,
        "#### Against the true parameters (the noise floor)\n\n\
         Mean over the runs of the method's verification figure divided by the true parameters' \
         (1.00 = the noise floor).\n"
    );
    let _ = write!(out, "| method | observes |");
    for (label, _) in picks {
        let _ = write!(out, " {label} L / R / collab |");
    }
    out.push_str(" its reflector's pos RMS L / R |\n|---|---|");
    out.push_str(&"---|".repeat(picks.len() + 1));
    out.push('\n');
    for m in &plan.methods {
        let _ = write!(
            out,
            "| {} | {} |",
            m.title(),
            match m.observes {
                Observes::ThreeReflectors => "three reflectors",
                Observes::OneReflector => "one reflector",
            }
        );
        for (_, pick) in picks {
            let cells: Vec<String> = THREE
                .iter()
                .map(|&(pairs, _)| {
                    ratio_summary(
                        runs,
                        |r| ver_stat(r, Model::Method(m.key), pairs, *pick),
                        |r| ver_stat(r, Model::Truth, pairs, *pick),
                    )
                    .map_or("–".into(), |(mean, _, _)| format!("{mean:.2}"))
                })
                .collect();
            let _ = write!(out, " {} |", cells.join(" / "));
        }
        // A one-reflector method is at the noise floor, if anywhere, on its own reflector.
        let own: Vec<String> = Side::BOTH
            .iter()
            .map(|&side| {
                ratio_summary(
                    runs,
                    |r| own_reflector_rms(r, m.key, side, Model::Method(m.key)),
                    |r| own_reflector_rms(r, m.key, side, Model::Truth),
                )
                .map_or("–".into(), |(mean, _, _)| format!("{mean:.2}"))
            })
            .collect();
        let _ = writeln!(
            out,
            " {} |",
            if m.observes == Observes::OneReflector {
                own.join(" / ")
            } else {
                "–".into()
            }
        );
    }
    out.push('\n');
}

/// Minimax's verification figures over each other method's, and how often minimax was smaller.
fn against_minimax(out: &mut String, plan: &Plan, runs: &[SeedRun], picks: &[(&str, Pick)]) {
    let _ = writeln!(
        out,
        "#### The paper's method against the others\n\n\
         Mean over the runs of minimax's verification figure divided by the other method's (below \
         1: minimax smaller), and in how many of the runs × (L, R, collab) minimax was smaller or \
         equal.\n"
    );
    let _ = write!(out, "| minimax against |");
    for (label, _) in picks {
        let _ = write!(out, " {label} L / R / collab |");
    }
    out.push_str("\n|---|");
    out.push_str(&"---|".repeat(picks.len()));
    out.push('\n');
    for m in plan.methods.iter().filter(|m| m.key != "minimax") {
        let _ = write!(out, "| {} |", m.title());
        for (_, pick) in picks {
            let mut wins = 0;
            let mut total = 0;
            let cells: Vec<String> = THREE
                .iter()
                .map(|&(pairs, _)| {
                    match ratio_summary(
                        runs,
                        |r| ver_stat(r, Model::Method("minimax"), pairs, *pick),
                        |r| ver_stat(r, Model::Method(m.key), pairs, *pick),
                    ) {
                        Some((mean, w, n)) => {
                            wins += w;
                            total += n;
                            format!("{mean:.3}")
                        }
                        None => "–".into(),
                    }
                })
                .collect();
            let _ = write!(out, " {} ({wins} of {total}) |", cells.join(" / "));
        }
        out.push('\n');
    }
    out.push('\n');
}

/// The Markdown report: what ran, the tables beside the paper's, Fig. 4, the ratios that the
/// orderings rest on, and the figures' files.
pub(crate) fn report(plan: &Plan, runs: &[SeedRun], tables: &Tables, elapsed_secs: f64) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "### `{}`\n", plan.command);
    let _ = writeln!(
        out,
        "Data: {}. Step-1 methods: {}. Step-2 methods: {}. Every figure is on the verification \
         configurations (not used for identification); mean ± standard deviation over the seeds where \
         there are several. Run time {:.1} s.\n",
        plan.describe_data(),
        plan.arm_methods()
            .iter()
            .map(MethodEntry::title)
            .collect::<Vec<_>>()
            .join(", "),
        plan.base_methods()
            .iter()
            .map(MethodEntry::title)
            .collect::<Vec<_>>()
            .join(", "),
        elapsed_secs
    );
    let _ = writeln!(
        out,
        "Curvature of every SQP stage: the paper's BFGS (Algorithm I as published; `dualcal \
         calibrate`'s default `--hessian auto` takes Gauss–Newton only on ill-conditioned data, \
         docs/solver.md).\n"
    );
    terminations(&mut out, plan, runs);
    out.push('\n');
    for t in &tables.tables {
        out.push_str(&t.to_markdown());
        out.push('\n');
    }
    let _ = writeln!(
        out,
        "#### Fig. 4 analogue: accuracy against the number of calibration configurations\n\n\
         Each step-1 method on the first n calibration configurations of each arm; cal = those n, ver = \
         the verification configurations.\n"
    );
    out.push_str(&tables.fig4_markdown);
    out.push('\n');

    let with_truth = runs.iter().all(|r| r.comparison.truth.is_some());
    if with_truth {
        against_truth(&mut out, plan, runs, &PICKS);
    }
    if plan.methods.iter().any(|m| m.key == "minimax") {
        against_minimax(&mut out, plan, runs, &PICKS);
    }
    let _ = writeln!(
        out,
        "Figures: [Fig. 4](fig4_configurations.svg), [Fig. 6 right arm](fig6_relative_right.svg), \
         [Fig. 6 left arm](fig6_relative_left.svg), [Fig. 7](fig7_base_methods.svg), \
         [Fig. 8](fig8_collaborative.svg); the numbers behind them in histograms.csv and boxplots.csv, \
         every run's figures in runs.csv."
    );
    out
}
