//! The app's view of the engine: a loaded dataset and robot, the nominal model, (after a run) the
//! calibrated one and (during a run) the model the run has reached, each with its [`Analysis`]
//! (accuracy figures, histograms and the per-configuration rows the panels show).

use super::viewport::mesh_pack::PackedMeshes;
use crate::analysis::{Analysis, ConfigRow};
use crate::dataset::Dataset;
use crate::quality::{Flag, Screening};
use crate::robot::RobotDescription;
use crate::side::{ConfigId, Side};
use crate::solver::{CalibrationResult, CalibrationSettings, Stage};
use crate::source::Files;
use crate::workspace::{Workspace, WorkspaceOptions};
use anyhow::Context as _;
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A finished calibration and its figures.
#[derive(Clone, Debug)]
pub struct Calibrated {
    pub result: CalibrationResult,
    pub analysis: Analysis,
    /// The configurations screened with the calibrated model ([`crate::exclusion::screen_result`]).
    pub screening: Screening,
    /// Each arm's parameter uncertainty ([`crate::solver::uncertainty`]), computed once.
    pub uncertainty: crate::side::PerSide<Option<crate::solver::uncertainty::ArmUncertainty>>,
    /// The calibration's parameter file (the one `dualcal calibrate --out` writes, with the screening
    /// and the uncertainty), made once: the export writes it, the browser's status shows it.
    pub params: crate::params::ParamsFile,
    /// Time the solver's own steps took, s: without the live figures, the final figures and (stepped
    /// in frames) the frames between steps.
    pub solver_secs: f64,
}

/// What the last Auto-exclude did ([`crate::exclusion::auto_exclude`]).
#[derive(Clone, Debug)]
pub struct AutoExcludeSummary {
    /// The configurations it left out, each with the flag that removed it.
    pub excluded: Vec<Flag>,
    /// Fits it ran.
    pub rounds: usize,
    /// Why it stopped short of excluding every suspect, if it did.
    pub stopped: Option<String>,
}

/// The model a running calibration has reached, with its figures: what the workbench shows instead of
/// the last finished calibration until the run ends.
#[derive(Clone, Debug)]
pub struct LiveFigures {
    /// The stage the model is from (the one running, or the one that just ended).
    pub stage: Stage,
    /// Outer iterations of `stage` done.
    pub iteration: usize,
    /// Whether `stage` had ended: its parameters are final.
    pub stage_finished: bool,
    pub analysis: Analysis,
    /// How long the worker took to compute `analysis`.
    pub evaluation_secs: f64,
}

impl LiveFigures {
    /// "iteration k of step s", as the panels mark the live figures.
    pub fn label(&self) -> String {
        if self.stage_finished {
            format!("iteration {} of {}, stage done", self.iteration, self.stage)
        } else {
            format!("iteration {} of {}", self.iteration, self.stage)
        }
    }
}

/// What the "after" figures are of.
#[derive(Clone, Copy, Debug)]
pub enum After<'a> {
    /// A run is going: the model it has reached.
    Live(&'a LiveFigures),
    /// The last finished calibration.
    Calibrated(&'a Calibrated),
}

impl<'a> After<'a> {
    pub fn analysis(self) -> &'a Analysis {
        match self {
            After::Live(live) => &live.analysis,
            After::Calibrated(c) => &c.analysis,
        }
    }

    /// A short name for a column or a legend: "calibrated" or "iteration k".
    pub fn short_name(self) -> String {
        match self {
            After::Live(live) => format!("iteration {}", live.iteration),
            After::Calibrated(_) => "calibrated".into(),
        }
    }
}

/// The robot's meshes, loaded and packed off the UI thread after the robot ([`super::job::meshes::MeshWork`]).
#[derive(Clone, Debug, Default)]
pub enum RobotMeshes {
    /// The description has no mesh geometry.
    #[default]
    None,
    /// Being loaded: meshes are drawn as placeholder boxes.
    Loading,
    Loaded(Arc<LoadedMeshes>),
    /// The loading stopped unexpectedly (why): meshes stay placeholder boxes.
    Failed(String),
}

impl RobotMeshes {
    /// The packed meshes, once loaded.
    pub fn packed(&self) -> Option<&Arc<PackedMeshes>> {
        match self {
            RobotMeshes::Loaded(m) => Some(&m.packed),
            _ => None,
        }
    }

    /// The packed meshes to draw, once loaded: with `simplified`, the simplified copy where there is
    /// one (else the full meshes).
    pub fn packed_for(&self, simplified: bool) -> Option<&Arc<PackedMeshes>> {
        match self {
            RobotMeshes::Loaded(m) if simplified => m.simplified.as_ref().or(Some(&m.packed)),
            _ => self.packed(),
        }
    }
}

/// A robot's visual meshes, packed for the GPU, and what could not be loaded.
#[derive(Debug)]
pub struct LoadedMeshes {
    /// The visual meshes, and the collision meshes of links whose visual mesh is missing (stand-ins).
    pub packed: Arc<PackedMeshes>,
    /// The same meshes simplified (`crate::meshes::lod`), drawn on software renderers; `None` where
    /// the build has no simplifier (the browser).
    pub simplified: Option<Arc<PackedMeshes>>,
    /// Distinct visual mesh files loaded, and their triangles.
    pub visual_files: usize,
    pub visual_triangles: usize,
    /// Visual mesh files that could not be loaded (each drawn as a stand-in or a placeholder).
    pub visual_missing: usize,
    /// Problems the robot's own warnings do not already name (unreadable, empty or unsupported files).
    pub warnings: Vec<String>,
    pub elapsed_secs: f64,
}

/// A loaded dataset with its robot and figures.
#[derive(Clone)]
pub struct Session {
    pub dataset: Arc<Dataset>,
    pub robot: Arc<RobotDescription>,
    /// Where the robot came from (`None`: built in).
    pub robot_source: Option<PathBuf>,
    /// The robot's meshes (loaded after the session).
    pub meshes: RobotMeshes,
    /// The nominal model's figures (without the excluded configurations).
    pub nominal: Analysis,
    /// The configurations screened with the nominal model when the dataset was loaded
    /// ([`crate::quality::screen`], as `dualcal calibrate` does before fitting).
    pub screening: Screening,
    /// Configurations left out of the calibration and the figures (indices into the dataset).
    pub exclude: Vec<ConfigId>,
    /// What the last Auto-exclude removed (cleared when the exclusions are edited by hand).
    pub auto_exclusion: Option<AutoExcludeSummary>,
    /// The last finished calibration.
    pub calibrated: Option<Calibrated>,
    /// While a calibration runs: the model it has reached (cleared when it ends).
    pub live: Option<LiveFigures>,
    /// Beside a calibration with errors beyond geometry (`Model` other than geometric): the geometric
    /// model's calibration of the same data and settings, evaluated — the accuracy view's "geometric"
    /// column between nominal and the full model.
    pub geometric: Option<Analysis>,
}

impl Session {
    /// Load a dataset (directory or `dataset.toml`) with the given robot, or the one the dataset names,
    /// or the built-in IRB 14000.
    pub fn load(dataset_path: &Path, urdf: Option<&Path>) -> anyhow::Result<Self> {
        Self::load_from(&Files::default(), dataset_path, urdf)
    }

    /// [`Session::load`] reading the files through `files` (in a browser: the files in memory).
    pub fn load_from(
        files: &Files,
        dataset_path: &Path,
        urdf: Option<&Path>,
    ) -> anyhow::Result<Self> {
        let options = WorkspaceOptions {
            robot: urdf.map(Path::to_path_buf),
            files: files.clone(),
            ..Default::default()
        };
        let ws = Workspace::load(dataset_path, &options)?;
        let robot_path = urdf
            .map(Path::to_path_buf)
            .or_else(|| ws.dataset.robot.clone());
        Self::from_workspace(ws, robot_path)
    }

    pub fn new(
        dataset: Dataset,
        robot: RobotDescription,
        robot_source: Option<PathBuf>,
    ) -> anyhow::Result<Self> {
        let ws = Workspace::new(dataset, robot, &Default::default())?;
        Self::from_workspace(ws, robot_source)
    }

    /// The session of a loaded workspace (the engine's load pipeline: checks, nominal model and
    /// screening as `dualcal calibrate` does them), with the nominal model's figures.
    pub fn from_workspace(ws: Workspace, robot_source: Option<PathBuf>) -> anyhow::Result<Self> {
        let Workspace {
            dataset,
            robot,
            nominal: nominal_model,
            screening,
        } = ws;
        let nominal = Analysis::compute(
            &dataset,
            &nominal_model,
            &robot.body_from_arm_base(Side::Left),
        )
        .context("nominal accuracy")?;
        Ok(Self {
            dataset: Arc::new(dataset),
            robot: Arc::new(robot),
            robot_source,
            meshes: RobotMeshes::None,
            nominal,
            screening,
            exclude: Vec::new(),
            auto_exclusion: None,
            calibrated: None,
            live: None,
            geometric: None,
        })
    }

    /// The newest model's figures: the running calibration's iterate, else the last finished
    /// calibration, else the nominal model.
    pub fn current(&self) -> &Analysis {
        self.newest_or_nominal(true)
    }

    /// The newest model other than the nominal one: the live iterate while a calibration runs, else
    /// the last finished calibration.
    pub fn after(&self) -> Option<After<'_>> {
        match (&self.live, &self.calibrated) {
            (Some(live), _) => Some(After::Live(live)),
            (None, Some(c)) => Some(After::Calibrated(c)),
            (None, None) => None,
        }
    }

    /// The figures the view shows: the newest model's ([`Self::after`]: the running calibration's
    /// iterate, else the last finished calibration) when `newest` is asked for and there is one, else
    /// the nominal model's.
    pub fn newest_or_nominal(&self, newest: bool) -> &Analysis {
        match self.after() {
            Some(after) if newest => after.analysis(),
            _ => &self.nominal,
        }
    }

    /// The settings a run starts with: the user's `settings`, leaving out the session's excluded
    /// configurations (the session owns them; the run and its figures derive from it).
    pub fn run_settings(&self, settings: &CalibrationSettings) -> CalibrationSettings {
        CalibrationSettings {
            exclude: self.exclude.clone(),
            ..settings.clone()
        }
    }

    /// The newest screening: the last finished calibration's, else the nominal one's.
    pub fn current_screening(&self) -> &Screening {
        match &self.calibrated {
            Some(c) => &c.screening,
            None => &self.screening,
        }
    }

    /// Whole-file findings of the nominal screening that `dualcal calibrate` refuses to go on with.
    pub fn refusals(&self) -> Vec<&str> {
        self.screening
            .errors()
            .map(|f| f.message.as_str())
            .collect()
    }

    /// `settings` with what the elastic models take from the robot: gravity's direction (−z of its
    /// root link in the left arm's base) unless the settings name one, the lumped masses of its
    /// inertials where it has them, and — for the harmonic models — the gear ratios of its
    /// `<transmission>` elements (motor-side harmonics) unless the settings give some.
    pub fn with_gravity(&self, mut settings: CalibrationSettings) -> CalibrationSettings {
        settings
            .gravity_in_left_base
            .get_or_insert_with(|| self.robot.gravity_in_left_base(None));
        if !settings.model.is_geometric()
            && settings.held_masses.left.is_none()
            && settings.held_masses.right.is_none()
        {
            settings.held_masses = crate::side::PerSide::from_fn(|s| self.robot.lumped_masses(s));
        }
        if settings.model.harmonics > 0 && settings.gear_ratios.is_empty() {
            settings.gear_ratios = self.robot.gear_ratios();
        }
        settings
    }

    pub fn body_from_left_base(&self) -> Isometry3<f64> {
        self.robot.body_from_arm_base(Side::Left)
    }
}

/// One configuration's row of an analysis.
pub fn config_row(analysis: &Analysis, config: ConfigId) -> Option<&ConfigRow> {
    analysis.configs.iter().find(|r| r.config == config)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/datasets/example")
    }

    /// With the true parameters the registered measured points land on the model's (up to the
    /// tracker noise); with the nominal ones they do not. This checks the whole drawing chain:
    /// tracker → left base (registration) → body frame.
    #[test]
    fn registration_of_the_example_matches_the_truth_to_the_noise() {
        let session = Session::load(&example(), None).unwrap();
        let truth = crate::params::read_model(&example().join("truth.json")).unwrap();
        let analysis =
            Analysis::compute(&session.dataset, &truth, &session.body_from_left_base()).unwrap();
        assert!(
            analysis.registration_rms_mm < 0.05,
            "registration RMS with the truth {} mm",
            analysis.registration_rms_mm
        );
        assert!(
            session.nominal.registration_rms_mm > 10.0 * analysis.registration_rms_mm,
            "nominal {} mm vs truth {} mm",
            session.nominal.registration_rms_mm,
            analysis.registration_rms_mm
        );
        let worst_point = analysis
            .configs
            .iter()
            .flat_map(|r| r.point_errors_mm())
            .fold(0.0f64, f64::max);
        assert!(
            worst_point < 0.2,
            "worst point error with the truth {worst_point} mm"
        );
        // Every configuration of both arms is listed once, in dataset order.
        let n = session.dataset.arms.left.measurements.len()
            + session.dataset.arms.right.measurements.len();
        assert_eq!(analysis.configs.len(), n);
        assert_eq!(
            analysis.configs[0].id,
            session.dataset.arms.left.measurements[0].id
        );
        // The model points sit where the robot's flange is drawn (body frame, not a base frame).
        let row = &analysis.configs[0];
        let flange = session
            .robot
            .body_from_flange(Side::Left, &session.dataset.arms.left.measurements[0].q_rad);
        let centroid = row.model_body_mm.iter().sum::<nalgebra::Vector3<f64>>() / 3.0;
        let d = (centroid - flange.translation.vector).norm();
        assert!(d < 150.0, "reflectors {d} mm from the drawn flange");
    }

    #[test]
    fn a_missing_dataset_is_an_error_naming_it() {
        let err = Session::load(Path::new("/nonexistent/dataset"), None)
            .err()
            .expect("error");
        assert!(
            format!("{err:#}").contains("/nonexistent/dataset"),
            "{err:#}"
        );
    }
}
