//! The planning view's state: what `dualcal plan` is told (the tracker's position, the number of
//! configurations, the candidates, the limits, the cell's keep-out boxes), the plan the engine made
//! ([`crate::plan::plan_arm`], one arm per step of [`super::job::plan`]), the planned pose shown in
//! 3D with the tracker and the lines of sight ([`PlanOverlay`]), and the plan's files as one `.zip`
//! ([`crate::plan::plan_files`]). The window is drawn by [`super::panels::plan_ui`].

use super::viewport::scene::PlanOverlay;
use crate::collision::KeepOutBox;
use crate::dataset::TrackerSpec;
use crate::plan::{ArmPlan, PlanOptions, PlanOutput, plan_files};
use crate::robot::RobotDescription;
use crate::side::{PerSide, Side};
use crate::solver::uncertainty::PredictedDesign;
use nalgebra::{Point3, Vector3};
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

/// What the user enters.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanInputs {
    /// The tracker's position in the robot's root (body) frame, mm.
    pub tracker_mm: [f64; 3],
    pub per_arm: usize,
    pub candidates: usize,
    pub seed: u64,
    pub max_incidence_deg: f64,
    pub max_range_m: f64,
    /// Fraction of each joint's range kept clear at both ends.
    pub joint_margin: f64,
    pub clearance_mm: f64,
    /// Keep-out boxes, one `X0,Y0,Z0,X1,Y1,Z1` (mm, root frame) per line.
    pub keep_out: String,
    /// Start from the loaded dataset's configurations and add new ones.
    pub extend: bool,
    /// The predicted accuracy to reach (× the noise floor): the smallest number of configurations
    /// that reaches it instead of `per_arm` (`dualcal plan --target`).
    pub target: Option<f64>,
}

impl Default for PlanInputs {
    fn default() -> Self {
        let d = PlanOptions::default();
        Self {
            tracker_mm: [
                d.tracker_in_body_mm.x,
                d.tracker_in_body_mm.y,
                d.tracker_in_body_mm.z,
            ],
            per_arm: d.per_arm,
            candidates: d.candidates,
            seed: d.seed,
            max_incidence_deg: d.max_incidence_deg,
            max_range_m: d.max_range_mm / 1e3,
            joint_margin: d.joint_limit_margin_fraction,
            clearance_mm: d.clearance_mm,
            keep_out: String::new(),
            extend: false,
            target: None,
        }
    }
}

/// The robot, reflectors and tracker a plan is made for (the workbench's current ones).
#[derive(Clone)]
pub struct PlanTarget {
    pub robot: Arc<RobotDescription>,
    /// The robot description's file (`None`: built in).
    pub robot_path: Option<PathBuf>,
    pub reflectors_mm: Vec<Vector3<f64>>,
    pub tracker: TrackerSpec,
    /// The loaded dataset's configurations per arm (rad), for "extend".
    pub existing: PerSide<Vec<Vec<f64>>>,
}

/// One arm's plan and what it predicts (the parameters' σ, the verification accuracy).
pub struct ArmOutcome {
    pub plan: ArmPlan,
    pub sigma: Option<PredictedDesign>,
}

/// A plan, filled in as each arm is planned.
pub struct PlanResult {
    pub target: PlanTarget,
    pub options: PlanOptions,
    pub arms: PerSide<Option<ArmOutcome>>,
    /// Identifies the plan (the 3D overlay's revision).
    pub revision: u64,
}

impl PlanResult {
    /// Both arms, once planned.
    pub fn plans(&self) -> Option<PerSide<ArmPlan>> {
        match (&self.arms.left, &self.arms.right) {
            (Some(l), Some(r)) => Some(PerSide::new(l.plan.clone(), r.plan.clone())),
            _ => None,
        }
    }
}

/// The view.
#[derive(Default)]
pub struct PlanView {
    pub open: bool,
    pub inputs: PlanInputs,
    /// The running or last plan.
    pub result: Option<PlanResult>,
    /// Why the last plan could not be made (options, too few candidates).
    pub error: Option<String>,
    /// The planned configuration drawn per arm (index into its plan; `None`: home).
    pub shown: PerSide<Option<usize>>,
    revisions: u64,
    /// What the last overlay was made of.
    overlay_key: Option<OverlayKey>,
}

/// What an overlay is made of: the view open, the plan's revision, the arms planned, the poses shown.
type OverlayKey = (bool, u64, [bool; 2], PerSide<Option<usize>>);

impl PlanView {
    /// The engine's options from the inputs; an input that does not read is an error naming it.
    pub fn options(&self, target: &PlanTarget) -> Result<PlanOptions, String> {
        let i = &self.inputs;
        if !(i.max_incidence_deg > 0.0 && i.max_incidence_deg <= 90.0) {
            return Err("largest incidence: expected an angle in (0, 90] degrees".into());
        }
        if !i.tracker_mm.iter().all(|v| v.is_finite()) {
            return Err("tracker position: expected three numbers (mm)".into());
        }
        let keep_out = i
            .keep_out
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .map(|(k, l)| {
                KeepOutBox::parse(l.trim()).map_err(|e| format!("keep-out line {}: {e}", k + 1))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(PlanOptions {
            per_arm: i.per_arm,
            candidates: i.candidates,
            seed: i.seed,
            tracker_in_body_mm: Vector3::from(i.tracker_mm),
            max_incidence_deg: i.max_incidence_deg,
            max_range_mm: i.max_range_m * 1e3,
            joint_limit_margin_fraction: i.joint_margin,
            clearance_mm: i.clearance_mm,
            keep_out,
            existing: if i.extend {
                target.existing.clone()
            } else {
                PerSide::new(Vec::new(), Vec::new())
            },
            target: i.target,
            ..PlanOptions::default()
        })
    }

    /// A new plan starts: the previous one is dropped.
    pub fn started(&mut self, target: PlanTarget, options: PlanOptions) {
        self.revisions += 1;
        self.error = None;
        self.shown = PerSide::new(Some(0), Some(0));
        self.result = Some(PlanResult {
            target,
            options,
            arms: PerSide::new(None, None),
            revision: self.revisions,
        });
    }

    /// The overlay when what it shows changed since the last call (`Some(None)`: draw the dataset
    /// again), else `None`.
    pub fn overlay_if_changed(&mut self) -> Option<Option<PlanOverlay>> {
        let key = (
            self.open,
            self.result.as_ref().map_or(0, |r| r.revision),
            self.result.as_ref().map_or([false; 2], |r| {
                [r.arms.left.is_some(), r.arms.right.is_some()]
            }),
            self.shown,
        );
        if self.overlay_key.as_ref() == Some(&key) {
            return None;
        }
        self.overlay_key = Some(key);
        Some(self.overlay())
    }

    /// The plan of another robot is not drawn on a new one: a newly loaded dataset drops it.
    pub fn dataset_replaced(&mut self) {
        self.result = None;
        self.error = None;
        self.shown = PerSide::new(None, None);
    }

    /// What the viewport draws while the view is open and a plan (or part of one) exists.
    pub fn overlay(&self) -> Option<PlanOverlay> {
        if !self.open {
            return None;
        }
        let result = self.result.as_ref()?;
        let robot = &result.target.robot;
        let nominal = robot.nominal_model(result.target.reflectors_mm.clone());
        let body_points = |side: Side, q: &[f64]| -> Vec<Vector3<f64>> {
            let body_from_base = robot.body_from_arm_base(side);
            nominal
                .arm(side)
                .reflector_fk(q)
                .points_mm
                .iter()
                .map(|p| body_from_base.transform_point(&Point3::from(*p)).coords)
                .collect()
        };
        let planned = |side: Side| result.arms[side].as_ref().map(|a| &a.plan);
        let q_rad = PerSide::from_fn(|side| {
            let plan = planned(side)?;
            plan.configs.get(self.shown[side]?).cloned()
        });
        let points_mm = PerSide::from_fn(|side| {
            planned(side).map_or_else(Vec::new, |p| {
                p.configs.iter().map(|q| body_points(side, q)).collect()
            })
        });
        let sight_mm = Side::BOTH
            .iter()
            .filter_map(|&side| q_rad[side].as_ref().map(|q| body_points(side, q)))
            .flatten()
            .collect();
        Some(PlanOverlay {
            revision: result.revision,
            tracker_mm: result.options.tracker_in_body_mm,
            q_rad,
            points_mm,
            sight_mm,
        })
    }

    /// The plan's files (`dualcal plan --out`'s) as one `.zip`.
    pub fn zip(&self) -> Result<Vec<u8>, String> {
        let result = self.result.as_ref().ok_or("no plan yet")?;
        let plans = result.plans().ok_or("the plan is not finished")?;
        let output = PlanOutput {
            robot: &result.target.robot,
            robot_path: result.target.robot_path.as_deref(),
            reflectors_mm: &result.target.reflectors_mm,
            tracker: result.target.tracker,
            extending: !result.options.existing.left.is_empty()
                || !result.options.existing.right.is_empty(),
        };
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        for (name, text) in plan_files(&output, &plans) {
            zip.start_file(format!("plan/{name}"), options)
                .and_then(|()| zip.write_all(text.as_bytes()).map_err(Into::into))
                .map_err(|e| format!("{name}: {e}"))?;
        }
        zip.finish()
            .map(std::io::Cursor::into_inner)
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target() -> PlanTarget {
        let robot = Arc::new(RobotDescription::builtin_irb14000());
        PlanTarget {
            reflectors_mm: crate::simulate::default_reflectors_for(&robot).to_vec(),
            robot,
            robot_path: None,
            tracker: TrackerSpec::default(),
            existing: PerSide::new(Vec::new(), Vec::new()),
        }
    }

    #[test]
    fn inputs_become_the_command_lines_options_and_bad_ones_are_named() {
        let mut view = PlanView::default();
        let t = target();
        let o = view.options(&t).unwrap();
        assert_eq!(o, PlanOptions::default());
        view.inputs.keep_out = "0,0,0,100,100,100\n\n1,2,3".into();
        let err = view.options(&t).unwrap_err();
        assert!(err.starts_with("keep-out line 3:"), "{err}");
        view.inputs.keep_out = "0,0,0,100,100,100".into();
        assert_eq!(view.options(&t).unwrap().keep_out.len(), 1);
        view.inputs.max_incidence_deg = 120.0;
        assert!(view.options(&t).unwrap_err().contains("incidence"));
    }

    #[test]
    fn the_overlay_shows_the_chosen_pose_and_the_zip_holds_the_commands_files() {
        let mut view = PlanView {
            open: true,
            ..Default::default()
        };
        view.inputs.per_arm = 6;
        view.inputs.candidates = 30;
        let t = target();
        let options = view.options(&t).unwrap();
        view.started(t.clone(), options.clone());
        assert!(view.zip().is_err(), "nothing planned yet");
        for side in Side::BOTH {
            let plan = crate::plan::plan_arm(&t.robot, &t.reflectors_mm, &options, side).unwrap();
            view.result.as_mut().unwrap().arms[side] = Some(ArmOutcome { plan, sigma: None });
        }
        view.shown.right = Some(2);
        let overlay = view.overlay().unwrap();
        let plans = view.result.as_ref().unwrap().plans().unwrap();
        assert_eq!(overlay.q_rad.right.as_ref(), Some(&plans.right.configs[2]));
        assert_eq!(overlay.points_mm.left.len(), 6);
        assert_eq!(overlay.sight_mm.len(), 6, "both arms' three reflectors");
        let bytes = view.zip().unwrap();
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
        let names: Vec<String> = archive
            .file_names()
            .map(|n| n.unwrap().into_owned())
            .collect();
        for name in [
            "left.csv",
            "path_right.csv",
            "plan_left.mod",
            "dataset.toml",
        ] {
            assert!(names.contains(&format!("plan/{name}")), "{names:?}");
        }
        let mut csv = String::new();
        std::io::Read::read_to_string(&mut archive.by_name("plan/left.csv").unwrap(), &mut csv)
            .unwrap();
        assert_eq!(csv.lines().filter(|l| l.starts_with('L')).count(), 6);
        view.open = false;
        assert!(view.overlay().is_none());
    }
}
