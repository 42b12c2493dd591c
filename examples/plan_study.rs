//! The planning studies of docs/planning.md (issue 23): simulations that print figures and assert
//! nothing, so they are commands rather than tests. Each plans the measurement on simulations of the
//! built-in IRB 14000 (or a robot description of the user's own), calibrates on the planned and on
//! random configurations alike, and prints the verification RMS over the true parameters'.
//!
//! - `cargo run --release --example plan_study -- curve`: the curve against the number of
//!   configurations N ([`accuracy_against_the_number_of_configurations`]; `DUALCAL_PLAN_SVG=FILE`
//!   draws it, as docs/planning-curve.svg).
//! - `cargo run --release --example plan_study -- rounded`: the relaxation rounded against the
//!   exchanged design at one N ([`the_relaxation_rounded_against_the_exchanged_design`]).
//!
//! Both read the `DUALCAL_PLAN_*` variables their documentation lists (seeds, N, candidates, method,
//! noise draws). The simulations are those of tests/plan.rs (`tests/plan_sim/mod.rs`).

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/plan_sim/mod.rs"]
mod plan_sim;

use dualcal::collision::CollisionWorld;
use dualcal::plan::plan;
use dualcal::robot::RobotDescription;
use dualcal::side::{PerSide, Side};
use dualcal::simulate::default_reflectors_for;
use plan_sim::{
    Outcome, drawn_as_candidates, noise_seed, noise_seeds, planned_and_random, ratio_to_truth,
    simulation_and_options,
};

fn main() {
    match std::env::args().nth(1).as_deref() {
        Some("curve") => accuracy_against_the_number_of_configurations(),
        Some("rounded") => the_relaxation_rounded_against_the_exchanged_design(),
        _ => {
            eprintln!("usage: cargo run --release --example plan_study -- curve|rounded");
            std::process::exit(2);
        }
    }
}

/// The curve of docs/planning.md: verification RMS over the truth's against N, planned and random,
/// four simulations each by default (`cargo run --release --example plan_study -- curve`;
/// `DUALCAL_PLAN_N=20` for one N, `DUALCAL_PLAN_CANDIDATES=3000` for another pool,
/// `DUALCAL_PLAN_METHOD=lsq` to calibrate by least squares (or any step-1 method's name),
/// `DUALCAL_PLAN_ROBOT=yumi.urdf` for a robot description, `DUALCAL_PLAN_SEEDS=1,2,3,4,5,6,7,8`
/// for other simulations, `DUALCAL_PLAN_NOISE=1` for another draw of the measurement's noise,
/// `DUALCAL_PLAN_NOISE=0,1,2,3` for several over the same plans: every seed and draw is one
/// simulation of the figures; `DUALCAL_PLAN_DRAWS=candidates` draws the random sets and the
/// verification configurations by the planner's own checks, [`plan_sim::drawn_as_candidates`]).
fn accuracy_against_the_number_of_configurations() {
    // `DUALCAL_PLAN_ROBOT=yumi.urdf` plans and simulates a robot description of the user's own (the
    // arms found as `dualcal plan --robot` finds them; the built-in IRB 14000 by default).
    let robot = std::env::var("DUALCAL_PLAN_ROBOT").map_or_else(
        |_| RobotDescription::builtin_irb14000(),
        |path| RobotDescription::load(std::path::Path::new(&path), &Default::default()).unwrap(),
    );
    let ns: Vec<usize> = std::env::var("DUALCAL_PLAN_N").map_or_else(
        |_| vec![10, 15, 20, 30, 40],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    let seeds: Vec<u64> = std::env::var("DUALCAL_PLAN_SEEDS").map_or_else(
        |_| vec![1, 2, 3, 4],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    eprintln!("N   planned (mean, min–max)   random (mean, min–max)");
    let mut curve = Vec::new();
    for n in ns {
        let outcomes: Vec<Outcome> = seeds
            .iter()
            .map(|&seed| planned_and_random(&robot, seed, n))
            .collect();
        for (seed, o) in seeds.iter().zip(&outcomes) {
            let each: Vec<String> = o
                .draws
                .iter()
                .map(|(p, q)| format!("planned {p:.3}, random {q:.3}"))
                .collect();
            eprintln!("seed {seed}, N {n}: {}", each.join("; "));
        }
        // Every simulation: each seed with each noise draw.
        let r: Vec<(f64, f64)> = outcomes.iter().flat_map(|o| o.draws.clone()).collect();
        let arms = |f: fn(&Outcome) -> &PerSide<f64>| {
            outcomes
                .iter()
                .map(|o| 0.5 * (f(o).left + f(o).right))
                .sum::<f64>()
                / outcomes.len() as f64
        };
        let stats = |f: fn(&(f64, f64)) -> f64| {
            let v: Vec<f64> = r.iter().map(f).collect();
            (
                v.iter().sum::<f64>() / v.len() as f64,
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (p, q) = (stats(|x| x.0), stats(|x| x.1));
        eprintln!(
            "{n:<3} {:.3} ({:.3}–{:.3})       {:.3} ({:.3}–{:.3})   planned better on {} of {} \
             simulations; predicted {:.3}, efficient {:.3}, bound {:.3}",
            p.0,
            p.1,
            p.2,
            q.0,
            q.1,
            q.2,
            r.iter().filter(|x| x.0 < x.1).count(),
            r.len(),
            arms(|o| &o.predicted),
            arms(|o| &o.efficient),
            arms(|o| &o.bound)
        );
        curve.push(CurvePoint {
            n,
            planned: p,
            random: q,
            efficient: arms(|o| &o.efficient),
        });
    }
    // `DUALCAL_PLAN_SVG=FILE` draws the curve (docs/planning-curve.svg is such a drawing).
    if let Ok(path) = std::env::var("DUALCAL_PLAN_SVG") {
        let method = std::env::var("DUALCAL_PLAN_METHOD").unwrap_or_else(|_| "minimax".into());
        let draws = if drawn_as_candidates() {
            "random and verification sets drawn by the planner's checks"
        } else {
            "the simulator's random and verification sets"
        };
        let title = format!(
            "calibrated by {method}; {} simulations per N ({draws})",
            seeds.len() * noise_seeds(0).len()
        );
        std::fs::write(&path, curve_svg(&curve, &title)).unwrap();
        eprintln!("curve drawn in {path}");
    }
}

/// One N of the curve: the planned and the random sets' ratios (mean, min, max over the simulations)
/// and the efficient fit's prediction for the planned sets.
struct CurvePoint {
    n: usize,
    planned: (f64, f64, f64),
    random: (f64, f64, f64),
    efficient: f64,
}

/// The curve as an SVG drawing, the analogue of the paper's Fig. 4 for the planner: the verification
/// RMS over the true parameters' against N, planned and random (means, bars from the smallest to the
/// largest simulation), the efficient fit's prediction for the planned sets, and the 1.10.
fn curve_svg(curve: &[CurvePoint], subtitle: &str) -> String {
    use plotters::prelude::*;
    const FONT: &str = "sans-serif";
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 560)).into_drawing_area();
        root.fill(&WHITE).unwrap();
        let x_hi = curve.iter().map(|c| c.n).max().unwrap_or(1) as f64 + 5.0;
        let y_hi = curve
            .iter()
            .map(|c| c.planned.2.max(c.random.2))
            .fold(1.2_f64, f64::max)
            .min(3.0)
            + 0.02;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("Verification accuracy against the number of configurations per arm — {subtitle}"),
                (FONT, 14),
            )
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..x_hi, 0.98..y_hi)
            .unwrap();
        chart
            .configure_mesh()
            .x_desc("calibration configurations per arm (N)")
            .y_desc("verification RMS / true parameters' RMS")
            .label_style((FONT, 11))
            .axis_desc_style((FONT, 12))
            .bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(242, 242, 242))
            .draw()
            .unwrap();
        let target = RGBColor(200, 40, 40);
        chart
            .draw_series(LineSeries::new(
                [(0.0, 1.10), (x_hi, 1.10)],
                target.stroke_width(1),
            ))
            .unwrap()
            .label("the issue's target, 1.10")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], target));
        let series = [
            ("random", RGBColor(150, 150, 150), 3.0, 1),
            ("planned", RGBColor(30, 90, 200), -3.0, 0),
        ];
        for (name, colour, shift, which) in series {
            let pick = |c: &CurvePoint| if which == 0 { c.planned } else { c.random };
            chart
                .draw_series(curve.iter().map(|c| {
                    let (mean, lo, hi) = pick(c);
                    ErrorBar::new_vertical(c.n as f64 + shift / 10.0, lo, mean, hi, colour, 6)
                }))
                .unwrap();
            chart
                .draw_series(LineSeries::new(
                    curve.iter().map(|c| (c.n as f64, pick(c).0)),
                    colour.stroke_width(2),
                ))
                .unwrap()
                .label(format!("{name} (mean; bars: smallest to largest)"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
        }
        let predicted = RGBColor(30, 90, 200);
        chart
            .draw_series(DashedLineSeries::new(
                curve.iter().map(|c| (c.n as f64, c.efficient)),
                5,
                4,
                predicted.stroke_width(1),
            ))
            .unwrap()
            .label("planned: the efficient fit's prediction")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], predicted));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(200, 200, 200))
            .label_font((FONT, 11))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .unwrap();
        root.present().unwrap();
    }
    svg
}

/// The relaxation rounded — the candidates of its N largest weights — against the exchanged design,
/// at N = 20 (`DUALCAL_PLAN_N`) on the curve's simulations: both designs' least-squares predictions
/// on the plan's sample and their measured ratios (`cargo run --release --example plan_study --
/// rounded`).
fn the_relaxation_rounded_against_the_exchanged_design() {
    let robot = RobotDescription::builtin_irb14000();
    let world = CollisionWorld::new(&robot);
    let reflectors = default_reflectors_for(&robot);
    let nominal = robot.nominal_model(reflectors.to_vec());
    let n: usize = std::env::var("DUALCAL_PLAN_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let seeds: Vec<u64> = std::env::var("DUALCAL_PLAN_SEEDS").map_or_else(
        |_| vec![1, 2, 3, 4],
        |v| v.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
    );
    for seed in seeds {
        let (sim, options) = simulation_and_options(&robot, seed, n);
        let planned = plan(&robot, &reflectors, &options).unwrap();
        let mut rounded = PerSide::new(Vec::new(), Vec::new());
        let mut predicted = PerSide::new((0.0, 0.0), (0.0, 0.0));
        for side in Side::BOTH {
            let arm = nominal.arm(side);
            let (pool, _) = dualcal::plan::candidates(&robot, arm, side, &world, &options).unwrap();
            let jac = dualcal::plan::scaled_jacobians(arm, &pool);
            let points: Vec<_> = pool.iter().map(|q| arm.reflector_fk(q).points_mm).collect();
            let index = |q: &Vec<f64>| pool.iter().position(|c| c == q).unwrap();
            let p = &planned[side];
            let design: Vec<usize> = p.configs.iter().map(index).collect();
            let ver: Vec<usize> = p.sample.iter().map(index).collect();
            let bound = dualcal::plan::bound::relaxed_bound(
                &points,
                &jac,
                pool.len(),
                &[],
                n,
                &design,
                &ver,
            )
            .unwrap();
            rounded[side] = bound.largest.iter().map(|&i| pool[i].clone()).collect();
            let free = dualcal::solver::identifiability::identifiable_at(arm, &p.configs);
            let ratio = |design: &[Vec<f64>]| {
                dualcal::solver::uncertainty::predicted_verification_ratio(
                    arm, design, &p.sample, &free, 0.01,
                )
                .unwrap()
            };
            predicted[side] = (ratio(&p.configs), ratio(&rounded[side]));
        }
        let planned_configs = planned.as_ref().map(|_, p| p.configs.clone());
        let noise = noise_seed(seed);
        let (mp, mr) = (
            ratio_to_truth(&sim, &planned_configs, None, noise),
            ratio_to_truth(&sim, &rounded, None, noise),
        );
        eprintln!(
            "seed {seed}, N {n}: predicted (least squares) exchanged {:.3}, rounded {:.3}; \
             measured exchanged {mp:.3}, rounded {mr:.3}",
            0.5 * (predicted.left.0 + predicted.right.0),
            0.5 * (predicted.left.1 + predicted.right.1)
        );
    }
}
