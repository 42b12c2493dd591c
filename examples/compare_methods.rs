//! Every calibration method of the paper's comparison on one simulated dataset of the paper's protocol
//! (220 configurations per arm, 120 for calibration, geometric errors only), verification accuracy
//! against the true parameters' (the noise floor). The figures of docs/solver.md, "Comparison methods".
//!
//! `cargo run --release --example compare_methods -- [SEED ...]`

use dualcal::dataset::Split;
use dualcal::metrics::{AccuracyStats, evaluate};
use dualcal::robot::RobotDescription;
use dualcal::side::Side;
use dualcal::simulate::{paper_options, simulate_with_robot};
use dualcal::solver::arm_problem::ArmProblem;
use dualcal::solver::least_squares::{DistanceLeastSquares, LsqAlgorithm, LsqState};
use dualcal::solver::problem::StageParams;
use dualcal::solver::{BaseMethod, CalibrationSettings, Calibrator, Method, StageSolver};
use nalgebra::DVector;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seeds: Vec<u64> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let seeds = if seeds.is_empty() { vec![1] } else { seeds };
    let robot = RobotDescription::builtin_irb14000();
    for seed in seeds {
        let sim = simulate_with_robot(&paper_options(seed, 220, 120), &robot)?;
        let ds = &sim.dataset;
        let truth = evaluate(ds, &sim.truth, Split::Ver)?;
        println!(
            "\nseed {seed}: verification split (100 configurations per arm); ratio to the truth's"
        );
        println!(
            "| step 1 | step 2 | left pos RMS* mm | left ori RMS rad | right pos RMS* mm | right ori RMS rad | collab pos RMS* mm | collab ori RMS rad | time |"
        );
        println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
        let cell = |s: &AccuracyStats, t: &AccuracyStats| {
            format!(
                "{:.4} ({:.2}) | {:.5} ({:.2})",
                s.pos_rms_mm,
                s.pos_rms_mm / t.pos_rms_mm,
                s.ori_rms_rad.unwrap(),
                s.ori_rms_rad.unwrap() / t.ori_rms_rad.unwrap()
            )
        };
        println!(
            "| truth | | {} | {} | {} | |",
            cell(&truth.relative_left.unwrap(), &truth.relative_left.unwrap()),
            cell(
                &truth.relative_right.unwrap(),
                &truth.relative_right.unwrap()
            ),
            cell(&truth.collaborative.unwrap(), &truth.collaborative.unwrap())
        );
        let combos = Method::ALL
            .iter()
            .copied()
            .map(|m| (m, BaseMethod::Minimax))
            .chain([
                (Method::Minimax, BaseMethod::Distance),
                (Method::Minimax, BaseMethod::Absolute),
                (Method::Position, BaseMethod::Absolute),
                (Method::DistanceSingle, BaseMethod::Distance),
            ]);
        for (method, base_method) in combos {
            let settings = CalibrationSettings {
                method,
                base_method,
                ..CalibrationSettings::default()
            };
            let t0 = std::time::Instant::now();
            let r = Calibrator::new(ds, &sim.nominal).settings(settings).run()?;
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let v = evaluate(ds, &r.calibrated, Split::Ver)?;
            println!(
                "| {} | {} | {} | {} | {} | {ms:.0} ms{} |",
                method.name(),
                base_method.name(),
                cell(&v.relative_left.unwrap(), &truth.relative_left.unwrap()),
                cell(&v.relative_right.unwrap(), &truth.relative_right.unwrap()),
                cell(&v.collaborative.unwrap(), &truth.collaborative.unwrap()),
                if r.is_converged() {
                    String::new()
                } else {
                    format!(" ({:?})", r.warnings())
                }
            );
            if method == Method::DistanceSingle && base_method == BaseMethod::Minimax {
                // Where its orientation error comes from: the same kinematics with the two reflectors
                // it cannot see fitted to their own distances afterwards (kinematics held) — a step
                // ref. [26] does not take.
                let mut model = r.calibrated.clone();
                for side in Side::BOTH {
                    let k = r.reflector_used[side].map_or(0, |r| r.index());
                    let arm = model.arm(side).clone();
                    let cal: Vec<_> = ds
                        .arm(side)
                        .measurements
                        .iter()
                        .filter(|m| m.split == Split::Cal)
                        .collect();
                    let off = arm.reflector_offset();
                    let free: Vec<usize> = (0..9).filter(|p| p / 3 != k).map(|p| off + p).collect();
                    let n_free = free.len();
                    let problem = ArmProblem::new(
                        cal.iter().map(|m| m.q_rad.clone()).collect(),
                        &cal.iter()
                            .map(|m| m.tracker_points_mm.clone())
                            .collect::<Vec<_>>(),
                        &arm,
                        free,
                        DVector::from_element(n_free, 1.0),
                        0.02,
                    )
                    .with_reflectors((0..3).map(|j| j != k).collect());
                    let mut state = LsqState::new(
                        DistanceLeastSquares {
                            problem,
                            reflectors: (0..3).map(|j| j != k).collect(),
                        },
                        LsqAlgorithm::GaussNewton,
                        1e-10,
                    );
                    for _ in 0..20 {
                        if StageSolver::next_iter(&mut state, &|| false)
                            .termination
                            .is_some()
                        {
                            break;
                        }
                    }
                    if let StageParams::Arm(fitted) = StageSolver::current(&state) {
                        *model.arm_mut(side) = *fitted;
                    }
                    println!(
                        "  distance-single {side} arm: reflector {} used",
                        r.reflector_used[side].map_or("?", |r| r.name())
                    );
                }
                let w = evaluate(ds, &model, Split::Ver)?;
                println!(
                    "| distance-single, then the unseen reflectors fitted to their distances | (step 2 not redone) | {} | {} | – | – | |",
                    cell(&w.relative_left.unwrap(), &truth.relative_left.unwrap()),
                    cell(&w.relative_right.unwrap(), &truth.relative_right.unwrap()),
                );
            }
        }
    }
    Ok(())
}
