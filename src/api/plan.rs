//! [`Plan`]: which configurations to measure (`dualcal plan`), a thin layer over [`crate::plan`].

use super::dataset::Dataset;
use super::error::{Error, Result};
use super::robot::Robot;
use crate::collision::KeepOutBox;
use crate::dataset::TrackerSpec;
use crate::output::{OutputError, write_atomic};
use crate::plan::{ArmPlan, PlanOptions, PlanOutput};
use crate::side::{PerSide, Side};
use crate::solver::uncertainty::PredictedDesign;
use nalgebra::Vector3;
use std::path::Path;

/// A measurement to plan on a [`Robot`] for a tracker at a given place: per arm the configurations
/// to measure — collision-free, the reflectors facing the tracker, chosen so that every identifiable
/// parameter is well determined — in a short visiting order, with the predicted accuracy. The
/// options not set are `dualcal plan`'s defaults (docs/planning.md).
///
/// ```
/// # use dualcal::{Plan, Robot, Side};
/// let robot = Robot::builtin_irb14000();
/// let planned = Plan::new(&robot, [2000.0, 0.0, 800.0]) // the tracker in the body frame, mm
///     .configurations(8)
///     .candidates(80)
///     .run()?;
/// assert_eq!(planned.configurations(Side::Left).len(), 8);
/// if let Some(p) = planned.predicted(Side::Left) {
///     println!("largest predicted 1σ: {:?}", p.uncertainty.largest("mm").map(|s| s.sigma));
/// }
/// print!("{}", planned.summary());
/// # Ok::<(), dualcal::Error>(())
/// ```
pub struct Plan<'r> {
    robot: &'r Robot,
    options: PlanOptions,
    tracker: TrackerSpec,
    extending: bool,
}

impl<'r> Plan<'r> {
    /// A plan of `dualcal plan`'s defaults (20 configurations per arm from 600 candidates) for a
    /// tracker at `tracker_in_body_mm` (the robot's root frame, mm).
    pub fn new(robot: &'r Robot, tracker_in_body_mm: [f64; 3]) -> Self {
        Self {
            robot,
            options: PlanOptions {
                tracker_in_body_mm: Vector3::from(tracker_in_body_mm),
                ..PlanOptions::default()
            },
            tracker: TrackerSpec::default(),
            extending: false,
        }
    }

    /// Configurations to choose per arm (at least 2; default 20).
    pub fn configurations(mut self, per_arm: usize) -> Self {
        self.options.per_arm = per_arm;
        self
    }

    /// Candidate configurations drawn per arm to choose from (default 600).
    pub fn candidates(mut self, candidates: usize) -> Self {
        self.options.candidates = candidates;
        self
    }

    /// The random draws' seed (default 1): the same seed, the same plan.
    pub fn seed(mut self, seed: u64) -> Self {
        self.options.seed = seed;
        self
    }

    /// Largest angle between the reflectors' facing direction and the line to the tracker, deg
    /// (default 60).
    pub fn max_incidence_deg(mut self, degrees: f64) -> Self {
        self.options.max_incidence_deg = degrees;
        self
    }

    /// A keep-out box of the cell (body frame, mm): no arm link within the clearance of it.
    pub fn keep_out(mut self, min_mm: [f64; 3], max_mm: [f64; 3]) -> Self {
        let (a, b) = (Vector3::from(min_mm), Vector3::from(max_mm));
        self.options.keep_out.push(KeepOutBox {
            min_mm: a.inf(&b),
            max_mm: a.sup(&b),
        });
        self
    }

    /// Extend `dataset`'s measurement: its configurations (both splits) start the design and the
    /// plan adds new ones (ids `LP…`/`RP…` in the files).
    pub fn extend(mut self, dataset: &Dataset) -> Self {
        self.options.existing = PerSide::from_fn(|side| {
            dataset
                .data()
                .arm(side)
                .measurements
                .iter()
                .map(|m| m.q_rad.clone())
                .collect()
        });
        self.extending = true;
        self
    }

    /// The tracker's maximum permissible error, for the predicted σ (default: the paper's).
    pub fn tracker(mut self, tracker: TrackerSpec) -> Self {
        self.tracker = tracker;
        self
    }

    /// Every other option (range, joint-limit margin, clearance, draws per candidate): the engine's
    /// [`PlanOptions`], changed in place.
    pub fn options(mut self, change: impl FnOnce(&mut PlanOptions)) -> Self {
        change(&mut self.options);
        self
    }

    /// Plan both arms (the other arm resting at its home pose), then each arm's predicted σ and
    /// verification accuracy with the tracker's noise at its distance.
    pub fn run(self) -> Result<Planned> {
        let robot = self.robot.description();
        let reflectors_mm = crate::simulate::default_reflectors_for(robot).to_vec();
        let plans = crate::plan::plan(robot, &reflectors_mm, &self.options)?;
        let nominal = robot.nominal_model(reflectors_mm.clone());
        let predicted = PerSide::from_fn(|side| {
            crate::solver::uncertainty::predicted_for_tracker(
                robot,
                nominal.arm(side),
                side,
                &plans[side].configs,
                &plans[side].sample,
                &self.tracker,
                &self.options.tracker_in_body_mm,
            )
        });
        Ok(Planned {
            robot: self.robot.clone(),
            reflectors_mm,
            tracker: self.tracker,
            extending: self.extending,
            plans,
            predicted,
        })
    }
}

/// A plan: per arm the configurations in visiting order, via points, the design's figures and the
/// predicted accuracy; its files.
#[derive(Clone, Debug)]
pub struct Planned {
    robot: Robot,
    reflectors_mm: Vec<Vector3<f64>>,
    tracker: TrackerSpec,
    extending: bool,
    plans: PerSide<ArmPlan>,
    predicted: PerSide<Option<PredictedDesign>>,
}

impl Planned {
    /// The configurations to measure on `side`, in visiting order: joint values in chain order (rad;
    /// mm for a prismatic joint).
    pub fn configurations(&self, side: Side) -> &[Vec<f64>] {
        &self.plans[side].configs
    }

    /// The engine's plan of `side`: via points, path length, the design's criteria, its bound.
    pub fn arm(&self, side: Side) -> &ArmPlan {
        &self.plans[side]
    }

    /// The predicted 1σ of `side`'s parameters and verification accuracy (× the noise floor, on the
    /// candidates not chosen) with the tracker's noise (`None`: the information is singular).
    pub fn predicted(&self, side: Side) -> Option<&PredictedDesign> {
        self.predicted[side].as_ref()
    }

    /// The lines `dualcal plan` prints for each arm about the design and its bound.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        for side in Side::BOTH {
            let p = &self.plans[side];
            s += &crate::plan::summary_line(side, p);
            s.push('\n');
            if let Some(line) = crate::plan::bound_line(p) {
                s += &format!("  {line}\n");
            }
        }
        s
    }

    /// The files `dualcal plan --out` writes, name and text: per arm the dataset CSV to fill in
    /// (`left.csv`: `id,q1..qN,split`, degrees), the visiting sequence with via points
    /// (`path_left.csv`), for the YuMi RAPID modules (`plan_left.mod`), and `dataset.toml`.
    pub fn files(&self) -> Vec<(String, String)> {
        let out = PlanOutput {
            robot: self.robot.description(),
            robot_path: self.robot.file(),
            reflectors_mm: &self.reflectors_mm,
            tracker: self.tracker,
            extending: self.extending,
        };
        crate::plan::plan_files(&out, &self.plans)
    }

    /// Write [`Planned::files`] into the directory `out` (created), each file atomically. An existing
    /// non-empty `out` is refused unless `overwrite`.
    pub fn save(&self, out: impl AsRef<Path>, overwrite: bool) -> Result<()> {
        let out = out.as_ref();
        let non_empty = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
        if non_empty && !overwrite {
            return Err(OutputError::Exists {
                path: out.to_path_buf(),
            }
            .into());
        }
        let failed = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Write { path, source }
        };
        std::fs::create_dir_all(out).map_err(failed(out))?;
        for (name, text) in self.files() {
            let path = out.join(name);
            write_atomic(&path, text.as_bytes()).map_err(failed(&path))?;
        }
        Ok(())
    }
}
