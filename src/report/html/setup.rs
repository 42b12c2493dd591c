//! The sections on what was calibrated and how.

use super::{escape, facts, num, split_name, table, td};
use crate::report::{ArmSummary, Report, UncertaintySource};
use crate::side::Side;
use std::fmt::Write as _;

pub(super) fn dataset(r: &Report) -> String {
    let d = &r.dataset;
    let mut rows = vec![("directory", d.dir.display().to_string())];
    let arm_rows: Vec<Vec<String>> = r
        .measured_sides()
        .map(|side| (side, &d.arms[side]))
        .map(|(side, a)| {
            vec![
                td(side.name()),
                td(&a.file.display().to_string()),
                num(&a.joints.to_string()),
                num(&a.cal.to_string()),
                num(&a.ver.to_string()),
                num(&a.excluded.to_string()),
                td(a.station.as_deref().unwrap_or("—")),
            ]
        })
        .collect();
    let at: Vec<String> = r
        .measured_sides()
        .map(|side| format!("{:.4} mm ({side})", d.mpe_mm[side]))
        .collect();
    rows.push((
        "tracker (MPE)",
        format!(
            "{} µm + {} µm/m; at the arms' mean measuring distance {}",
            d.tracker.mpe_um,
            d.tracker.mpe_um_per_m,
            at.join(", ")
        ),
    ));
    let alone: Vec<Side> = r.measured_sides().collect();
    rows.push((
        "stations",
        if let [side] = alone.as_slice() {
            format!(
                "one arm measured alone ({side}): no step 2 and no collaborative figures; the \
                 {} arm keeps its nominal parameters",
                side.other()
            )
        } else if d.one_station {
            "one: both arms measured in one tracker frame".into()
        } else {
            "two: each arm in its own tracker frame (no collaborative figures)".into()
        },
    ));
    let reflectors: Vec<Vec<String>> = d
        .reflectors
        .iter()
        .map(|(name, p)| {
            let mut row = vec![td(name)];
            row.extend([p.x, p.y, p.z].map(|v| num(&format!("{v:.3}"))));
            row
        })
        .collect();
    format!(
        "{}{}{}",
        facts(&rows),
        table(
            "Configurations per arm and split",
            &[
                "arm",
                "file",
                "joints",
                "calibration",
                "verification",
                "excluded",
                "station"
            ],
            &arm_rows
        ),
        table(
            "Reflectors (nominal, in the tip frame)",
            &["name", "x (mm)", "y (mm)", "z (mm)"],
            &reflectors
        )
    )
}

pub(super) fn robot(r: &Report) -> String {
    let rb = &r.robot;
    let rows: Vec<Vec<String>> = rb
        .arms
        .iter()
        .map(|(side, (chain, joints))| {
            vec![
                td(side.name()),
                td(chain),
                num(&joints.len().to_string()),
                td(&joints.join(", ")),
            ]
        })
        .collect();
    format!(
        "{}{}",
        facts(&[
            ("description", rb.name.clone()),
            ("nominal model", rb.nominal_model.clone()),
        ]),
        table(
            "Arm chains",
            &["arm", "chain", "joints", "joint names"],
            &rows
        )
    )
}

pub(super) fn method(r: &Report) -> String {
    let m = &r.method;
    let mut out = match &m.record {
        Ok(rec) => {
            let (a, b) = (rec.method(), rec.base_method());
            let excluded: Vec<String> = rec
                .excluded
                .iter()
                .map(|c| format!("{} {}", c.arm, c.id))
                .collect();
            facts(&[
                ("method", rec.name.clone()),
                (
                    "step 1 (each arm)",
                    format!("{} — {}", a.name(), a.spec().fits),
                ),
                (
                    "step 2 (right base in left base)",
                    format!("{} — {}", b.name(), b.spec().fits),
                ),
                ("QP solver", format!("{:?}", rec.qp)),
                ("configurations fitted", split_name(rec.split).into()),
                ("iteration limit per stage", rec.max_iterations.to_string()),
                ("step tolerance", format!("{:e}", rec.step_tolerance)),
                (
                    "progress tolerance",
                    format!("{:e}", rec.progress_tolerance),
                ),
                (
                    "configurations left out",
                    if excluded.is_empty() {
                        "none".into()
                    } else {
                        excluded.join(", ")
                    },
                ),
            ])
        }
        Err(why) => format!("<p>{}</p>", escape(why)),
    };
    match &m.stages {
        Some(stages) => {
            let rows: Vec<Vec<String>> = stages
                .iter()
                .map(|s| {
                    let ok = s.termination.is_converged();
                    vec![
                        td(&s.stage.to_string()),
                        num(&s.n_configs.to_string()),
                        num(&s.iterations.to_string()),
                        format!(
                            "<td class=\"{}\">{}</td>",
                            if ok { "good" } else { "bad" },
                            escape(&s.termination.to_string())
                        ),
                        num(&format!("{:.6} → {:.6}", s.psi_start_mm2, s.psi_mm2)),
                    ]
                })
                .collect();
            out.push_str(&table(
                "Termination per stage",
                &[
                    "stage",
                    "configurations",
                    "iterations",
                    "termination",
                    "ψ start → end (mm²)",
                ],
                &rows,
            ));
        }
        None => out.push_str("<p>No termination record.</p>"),
    }
    let _ = write!(
        out,
        "<p>Converged: <span class=\"{}\">{}</span>{}.</p>",
        converged(r).0,
        converged(r).1,
        m.statistics.as_ref().map_or(String::new(), |s| format!(
            "; calibration time {:.3} s",
            s.elapsed_secs
        ))
    );
    out
}

/// The CSS class and the word for whether the calibration converged: `yes`, `no`, or `unknown`
/// without a termination record (and no `converged: false`).
pub(super) fn converged(r: &Report) -> (&'static str, &'static str) {
    let m = &r.method;
    if !m.converged {
        ("bad", "no")
    } else if m.stages.is_none() {
        ("muted", "unknown")
    } else {
        ("good", "yes")
    }
}

pub(super) fn identifiability(r: &Report) -> String {
    let mut out = String::from(
        "<p class=\"muted\">The condition number is that of the column-scaled identification \
         Jacobian: how much a relative error of the data can grow in the parameters. Above ~1e3 \
         single parameters are poorly determined even when the fit is accurate.</p>",
    );
    for (side, arm) in r.arms.iter().filter(|(s, _)| r.dataset.measured[*s]) {
        let identified = arm.parameters.iter().filter(|p| p.fixed.is_none()).count();
        let _ = write!(
            out,
            "<h3>{side} arm</h3><p>{identified} of {} parameters identified, {} fixed.",
            arm.parameters.len(),
            arm.fixed.len()
        );
        if let Some(c) = &arm.conditioning {
            let f = |v: Option<f64>| v.map_or("infinite".into(), |v| format!("{v:.3e}"));
            let _ = write!(
                out,
                " Condition number with every parameter {}, with the fixed ones removed {}.",
                f(c.condition_before),
                f(c.condition_after)
            );
        }
        if let Some(u) = &arm.uncertainty {
            let _ = write!(
                out,
                " Condition number of the identified parameters at the solution {:.3e}.",
                u.condition
            );
        }
        out.push_str("</p>");
        let rows: Vec<Vec<String>> = arm
            .fixed
            .iter()
            .map(|f| vec![td(&f.name), td(&f.reason)])
            .collect();
        if !rows.is_empty() {
            out.push_str(&table("Fixed parameters", &["parameter", "why"], &rows));
        }
        out.push_str(&weak_table(&arm.weak));
    }
    out
}

/// The weak parameters: identified, but barely constrained across the workspace (none: nothing).
fn weak_table(weak: &[crate::solver::weak::WeakParameter]) -> String {
    if weak.is_empty() {
        return String::new();
    }
    let rows: Vec<Vec<String>> = weak
        .iter()
        .map(|w| {
            vec![
                td(&w.name),
                td(&w.reason),
                num(&format!("{:.3} {}", w.sigma, w.unit)),
                num(&format!("{:.3}", w.workspace_mm)),
                num(&format!("{:.0}×", w.workspace_mm / w.noise_mm)),
                td(if w.held {
                    "held at its nominal value"
                } else {
                    "kept free (--keep-weak)"
                }),
            ]
        })
        .collect();
    format!(
        "<p>Weak parameters: these configurations barely constrain them — their 1σ would move \
         distances across the robot's workspace by more than {}× the tracker's noise \
         (docs/reliability.md, <em>Weak parameters</em>).</p>{}",
        crate::solver::weak::WEAK_NOISE_RATIO,
        table(
            "Weak parameters",
            &[
                "parameter",
                "why",
                "1σ",
                "workspace effect (mm RMS)",
                "× noise",
                "done"
            ],
            &rows
        )
    )
}

pub(super) fn parameters(r: &Report) -> String {
    let mut out = String::from(
        "<p class=\"muted\">Lengths in mm; angles in rad, their change and σ in mrad. σ is one \
         standard deviation from the tracker's noise as the residuals at the solution estimate it \
         (the sandwich covariance of step 1's distance fit: pair errors share their points); for \
         the minimax fit it is a yardstick, the least-squares fit's covariance at the minimax \
         solution.</p>",
    );
    for (side, arm) in r.arms.iter().filter(|(s, _)| r.dataset.measured[*s]) {
        out.push_str(&arm_parameters(side, arm));
    }
    out.push_str(&base(r));
    out
}

fn arm_parameters(side: Side, arm: &ArmSummary) -> String {
    let mut out = format!("<h3>{side} arm</h3>");
    let source = match &arm.uncertainty_source {
        UncertaintySource::Recorded => "σ from the parameter file's `uncertainty` record".into(),
        UncertaintySource::Computed => {
            "σ computed by this report from the data (the parameter file records none)".into()
        }
        UncertaintySource::NotAvailable(why) => format!("σ not available: {why}"),
    };
    let _ = write!(out, "<p>{}", escape(&source));
    if let Some(u) = &arm.uncertainty {
        let _ = write!(
            out,
            "; point noise estimated from the residuals {:.4} mm per axis, {} configurations ({} in \
             the sums)",
            u.point_sigma_mm, u.configurations, u.configurations_used
        );
    }
    out.push_str(".</p>");
    let rows: Vec<Vec<String>> = arm
        .parameters
        .iter()
        .map(|p| {
            let digits = if p.angle { 6 } else { 4 };
            let unit = if p.angle { "rad / mrad" } else { p.unit };
            let sigma = p.sigma.map_or("—".into(), |s| format!("{s:.4}"));
            let ratio = p
                .sigma
                .filter(|&s| s > 0.0)
                .map_or("—".into(), |s| format!("{:.1}", p.change().abs() / s));
            vec![
                td(&p.name),
                td(unit),
                num(&format!("{:.digits$}", p.nominal)),
                num(&format!("{:.digits$}", p.calibrated)),
                num(&format!("{:+.4}", p.change())),
                format!(
                    "<td class=\"n\" data-param=\"{}.{}\"{}>{}</td>",
                    side.name(),
                    escape(&p.name),
                    p.sigma
                        .map_or(String::new(), |s| format!(" data-sigma=\"{s:?}\"")),
                    escape(&sigma)
                ),
                num(&ratio),
                td(if p.fixed.is_some() {
                    "fixed"
                } else {
                    "identified"
                }),
            ]
        })
        .collect();
    out.push_str(&table(
        "",
        &[
            "parameter",
            "unit",
            "nominal",
            "calibrated",
            "change",
            "σ",
            "|change| / σ",
            "status",
        ],
        &rows,
    ));
    if let Some(u) = &arm.uncertainty {
        let rows: Vec<Vec<String>> = u
            .correlations
            .iter()
            .map(|c| vec![td(&c.a), td(&c.b), num(&format!("{:+.3}", c.correlation))])
            .collect();
        if rows.is_empty() {
            out.push_str("<p>No pair of identified parameters correlates at ±0.9 or beyond.</p>");
        } else {
            out.push_str(&table(
                "Correlated pairs (|ρ| ≥ 0.9): the data hardly tell them apart",
                &["parameter", "parameter", "correlation"],
                &rows,
            ));
        }
    }
    out
}

/// The right base in the left base: translation (mm) and rotation vector (mrad), and the change.
pub(super) fn base(r: &Report) -> String {
    let (n, c) = (&r.base.nominal, &r.base.calibrated);
    let dt = c.translation.vector - n.translation.vector;
    let dr = (n.rotation.inverse() * c.rotation).scaled_axis() * 1e3;
    let v3 =
        |v: nalgebra::Vector3<f64>, d: usize| format!("({:.d$}, {:.d$}, {:.d$})", v.x, v.y, v.z);
    let rows = vec![
        vec![
            td("translation (mm)"),
            num(&v3(n.translation.vector, 3)),
            num(&v3(c.translation.vector, 3)),
            num(&format!("{} |{:.3}|", v3(dt, 3), dt.norm())),
        ],
        vec![
            td("rotation vector (mrad)"),
            num(&v3(n.rotation.scaled_axis() * 1e3, 2)),
            num(&v3(c.rotation.scaled_axis() * 1e3, 2)),
            num(&format!("{} |{:.3}|", v3(dr, 3), dr.norm())),
        ],
    ];
    format!(
        "<h3>Right arm base in the left arm base</h3>{}",
        table(
            "left_base_from_right_base (change of rotation: R_nominalᵀ R_calibrated)",
            &["", "nominal", "calibrated", "change"],
            &rows
        )
    )
}
