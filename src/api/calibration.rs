//! [`Calibration`] (what to run) and [`Calibrated`] (what came of it).

use super::dataset::Dataset;
use super::error::{Error, Result};
use crate::analysis::{Analysis, ConfigRow, Indicator};
use crate::controller::compensate::{
    Compensated, CompensationSettings, Refusal, Target, compensate_all,
};
use crate::controller::targets::TargetUnits;
use crate::dataset::Split;
use crate::kinematics::ErrorTerms;
use crate::metrics::AccuracyReport;
use crate::params::ParamsFile;
use crate::quality::{QualityRecord, ScreenSettings, Screening};
use crate::side::{ConfigId, PerSide, Side};
use crate::solver::uncertainty::ArmUncertainty;
use crate::solver::weak::WeakParameter;
use crate::solver::{
    BaseMethod, CalibrationEvent, CalibrationResult, CalibrationSettings, Calibrator, Method,
    StageSummary,
};
use std::path::Path;

/// A calibration to run on a [`Dataset`]: the paper's two steps with the command line's defaults
/// (`dualcal calibrate`), changed by the builder's methods.
///
/// ```
/// # let ds = dualcal::Dataset::load(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example"))?;
/// let result = dualcal::Calibration::new(&ds)
///     .method(dualcal::Method::LeastSquares)
///     .exclude(["L007"])
///     .max_iterations(100)
///     .run()?;
/// assert!(result.is_converged());
/// # Ok::<(), dualcal::Error>(())
/// ```
pub struct Calibration<'d> {
    dataset: &'d Dataset,
    settings: CalibrationSettings,
    method: Option<Method>,
    exclude: Vec<String>,
    observer: Option<EventObserver<'d>>,
}

/// What [`Calibration::on_event`] keeps.
type EventObserver<'d> = Box<dyn FnMut(&CalibrationEvent) + Send + 'd>;

impl<'d> Calibration<'d> {
    /// The command line's defaults: step 1 by the minimax method (the absolute positions where one
    /// marker per hand was measured in one camera frame), step 2 by minimax, the geometric model, the
    /// calibration split, 200 outer iterations per stage.
    pub fn new(dataset: &'d Dataset) -> Self {
        Self {
            dataset,
            settings: CalibrationSettings::default(),
            method: None,
            exclude: Vec::new(),
            observer: None,
        }
    }

    /// Step 1's method (each arm): [`Method::Minimax`] (the paper's), [`Method::LeastSquares`], … .
    pub fn method(mut self, method: Method) -> Self {
        self.method = Some(method);
        self
    }

    /// Step 2's method (the right-arm base in the left-arm base frame).
    pub fn base_method(mut self, method: BaseMethod) -> Self {
        self.settings.base_method = method;
        self
    }

    /// The error model: [`ErrorTerms::GEOMETRIC`] (the paper's) or one with joint elasticity and
    /// harmonics (`ErrorTerms::from_name("elastic")`).
    pub fn model(mut self, terms: ErrorTerms) -> Self {
        self.settings.model = terms;
        self
    }

    /// The configurations identified from: [`Split::Cal`] (default) or [`Split::All`].
    pub fn split(mut self, split: Split) -> Self {
        self.settings.split = split;
        self
    }

    /// Configurations left out of the identification and of the figures, by id (`L007`, or
    /// `left:7` for the 7th row of the left arm's file).
    pub fn exclude<I, S>(mut self, ids: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        self.exclude
            .extend(ids.into_iter().map(|s| s.as_ref().trim().to_string()));
        self
    }

    /// Outer iterations per stage at most.
    pub fn max_iterations(mut self, n: usize) -> Self {
        self.settings.max_iterations = n;
        self
    }

    /// Keep the weak parameters free (`true`) rather than holding them at their nominal values, as
    /// by default: the command line's `--keep-weak` ([`Calibrated::weak`] names them either way).
    pub fn keep_weak(mut self, keep: bool) -> Self {
        self.settings.keep_weak = keep;
        self
    }

    /// Every setting at once (the builder's other methods change these).
    pub fn settings(mut self, settings: CalibrationSettings) -> Self {
        self.method = Some(settings.method);
        self.settings = settings;
        self
    }

    /// Called with each event of the run (stage started, each outer iteration, stage finished).
    pub fn on_event(mut self, observer: impl FnMut(&CalibrationEvent) + Send + 'd) -> Self {
        self.observer = Some(Box::new(observer));
        self
    }

    /// The settings the run will use (the defaults worked out for this dataset).
    pub fn resolved_settings(&self) -> Result<CalibrationSettings> {
        let ws = &self.dataset.workspace;
        let mut settings = self.settings.clone();
        settings.method = self
            .method
            .unwrap_or_else(|| crate::solver::default_method(&ws.dataset));
        settings.gravity_in_left_base = settings
            .gravity_in_left_base
            .or_else(|| Some(ws.robot.gravity_in_left_base(None)));
        if !settings.model.is_geometric() && settings.held_masses.iter().all(|(_, m)| m.is_none()) {
            settings.held_masses = PerSide::from_fn(|side| ws.robot.lumped_masses(side));
        }
        if settings.model.harmonics > 0 && settings.gear_ratios.is_empty() {
            settings.gear_ratios = ws.robot.gear_ratios();
        }
        for id in &self.exclude {
            let config = ws.dataset.config_by_id(id).map_err(Error::Invalid)?;
            if !settings.exclude.contains(&config) {
                settings.exclude.push(config);
            }
        }
        Ok(settings)
    }

    /// Run both steps; then the screening of the result, each arm's uncertainty and the figures the
    /// parameter file records — what `dualcal calibrate` writes.
    pub fn run(mut self) -> Result<Calibrated> {
        let settings = self.resolved_settings()?;
        let ws = &self.dataset.workspace;
        let refusals: Vec<String> = ws.refusals().iter().map(|f| f.message.clone()).collect();
        if !refusals.is_empty() {
            return Err(Error::Refused(refusals));
        }
        let mut calibrator = Calibrator::new(&ws.dataset, &ws.nominal).settings(settings);
        if let Some(observer) = self.observer.as_mut() {
            calibrator = calibrator.observer(observer);
        }
        let result = calibrator.run()?;
        Ok(Calibrated::new(self.dataset, result))
    }
}

/// The nominal and calibrated figures (the paper's eqs. 5–8) of one split.
#[derive(Clone, Debug)]
pub struct SplitAccuracy {
    /// The nominal model's figures.
    pub nominal: AccuracyReport,
    /// The calibrated model's figures.
    pub calibrated: AccuracyReport,
}

/// Accuracy before and after on both splits, without the excluded configurations (`None`: a split
/// the dataset does not have).
#[derive(Clone, Debug)]
pub struct Accuracy {
    /// The configurations identified from.
    pub calibration: Option<SplitAccuracy>,
    /// The configurations held out (the honest figures).
    pub verification: Option<SplitAccuracy>,
}

/// One parameter of an arm: its name, unit, nominal and calibrated values and 1σ.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// `d2`, `θ3`, `t_a.x`, a URDF joint's `joint.x`, … (the parameter file's names).
    pub name: String,
    /// `mm`, `rad`, or an error term's own unit.
    pub unit: &'static str,
    /// The nominal model's value, in `unit`.
    pub nominal: f64,
    /// The calibrated value, in `unit`.
    pub calibrated: f64,
    /// Whether the calibration identified it (else it is held at nominal: not determined by the data).
    pub identified: bool,
    /// One standard deviation, in `unit` (`None`: not identified, or no uncertainty for the method).
    pub sigma: Option<f64>,
}

/// A calibration's result with everything the command line reports and writes.
#[derive(Clone, Debug)]
pub struct Calibrated {
    dataset: crate::dataset::Dataset,
    robot: crate::robot::RobotDescription,
    result: CalibrationResult,
    screening: Screening,
    uncertainty: PerSide<Option<ArmUncertainty>>,
    params: ParamsFile,
}

impl Calibrated {
    fn new(dataset: &Dataset, result: CalibrationResult) -> Self {
        let ws = &dataset.workspace;
        let ds = &ws.dataset;
        let ((screening, uncertainty), mut params) = crate::par::join(
            || {
                (
                    crate::exclusion::screen_result(ds, &result, &ScreenSettings::default()),
                    crate::solver::uncertainty::for_result(ds, &result),
                )
            },
            || ParamsFile::from_calibration(&result, ds),
        );
        params.record_uncertainty(&uncertainty);
        params.quality =
            serde_json::to_value(QualityRecord::new(ds, &screening, &result.settings.exclude)).ok();
        Self {
            dataset: ds.clone(),
            robot: ws.robot.clone(),
            result,
            screening,
            uncertainty,
            params,
        }
    }

    /// Whether every stage ran and converged.
    pub fn is_converged(&self) -> bool {
        self.result.is_converged()
    }

    /// The stages that ran, each with its iterations, termination and final ψ.
    pub fn stages(&self) -> &[StageSummary] {
        &self.result.stages
    }

    /// The settings the calibration ran with (method, model, exclusions, …).
    pub fn settings(&self) -> &CalibrationSettings {
        &self.result.settings
    }

    /// The configurations left out.
    pub fn excluded(&self) -> &[ConfigId] {
        &self.result.settings.exclude
    }

    /// Warnings of the run (divergence, parameters that lost their identifiability, …).
    pub fn warnings(&self) -> Vec<String> {
        self.result.warnings()
    }

    /// Every parameter of `side`'s arm in parameter order (the arm not measured: empty).
    pub fn parameters(&self, side: Side) -> Vec<Parameter> {
        let nominal = self.result.nominal.arm(side);
        let calibrated = self.result.calibrated.arm(side);
        let (x0, x) = (nominal.to_vector(), calibrated.to_vector());
        let free: Option<&[usize]> = self.result.identifiability[side]
            .as_ref()
            .map(|r| r.free.as_slice());
        let Some(free) = free else {
            return Vec::new();
        };
        let sigmas = self.uncertainty[side].as_ref();
        (0..calibrated.param_count())
            .map(|k| {
                let name = calibrated.param_name(k);
                let sigma = sigmas.and_then(|u| {
                    u.parameters
                        .iter()
                        .find(|p| p.name == name)
                        .map(|p| p.sigma)
                });
                Parameter {
                    unit: calibrated.param_unit(k),
                    nominal: x0[k],
                    calibrated: x[k],
                    identified: free.contains(&k),
                    sigma,
                    name,
                }
            })
            .collect()
    }

    /// The right-arm base in the left-arm base frame, calibrated (mm).
    pub fn left_base_from_right_base(&self) -> nalgebra::Isometry3<f64> {
        self.result.calibrated.left_base_from_right_base
    }

    /// `side`'s weak parameters: identified, but barely constrained by the configurations across the
    /// workspace, each with the reason in words and whether it was held at its nominal value
    /// ([`Calibration::keep_weak`]); empty when there are none.
    pub fn weak(&self, side: Side) -> &[WeakParameter] {
        &self.result.weak[side]
    }

    /// Each arm's uncertainty: σ of every identified parameter (its units as in
    /// [`ArmUncertainty::parameters`]), the strongly correlated pairs, the condition number.
    pub fn uncertainty(&self, side: Side) -> Option<&ArmUncertainty> {
        self.uncertainty[side].as_ref()
    }

    /// The paper's accuracy figures (eqs. 5–8), nominal and calibrated, on both splits, without the
    /// excluded configurations: the command line's summary table.
    pub fn accuracy(&self) -> Result<Accuracy> {
        let ds = self.dataset.excluding(&self.result.settings.exclude);
        let split = |split: Split| -> Result<Option<SplitAccuracy>> {
            if !crate::metrics::has_split(&ds, split) {
                return Ok(None);
            }
            Ok(Some(SplitAccuracy {
                nominal: crate::metrics::evaluate(&ds, &self.result.nominal, split)?,
                calibrated: crate::metrics::evaluate(&ds, &self.result.calibrated, split)?,
            }))
        };
        Ok(Accuracy {
            calibration: split(Split::Cal)?,
            verification: split(Split::Ver)?,
        })
    }

    /// Every configuration of both arms (left first) under the calibrated model: its largest
    /// position and orientation error over the pairs it is in, and each reflector's point error
    /// after registration ([`ConfigRow::point_errors_mm`]); excluded ones marked.
    pub fn configurations(&self) -> Result<Vec<ConfigRow>> {
        self.configurations_of(&self.result.calibrated)
    }

    /// [`Calibrated::configurations`] under the nominal model.
    pub fn nominal_configurations(&self) -> Result<Vec<ConfigRow>> {
        self.configurations_of(&self.result.nominal)
    }

    fn configurations_of(&self, model: &crate::kinematics::DualArmModel) -> Result<Vec<ConfigRow>> {
        Ok(self.analysis_of(model)?.configs)
    }

    /// The per-pair samples of the paper's histograms and box plots (Figs. 6–8) on `split` (`Cal` or
    /// `Ver`), under the calibrated model or, with `nominal`, the nominal one: for each indicator
    /// the data measure, per pair the signed `Δd` of the worst reflector (mm) or `Δo` (rad).
    pub fn pair_samples(&self, split: Split, nominal: bool) -> Result<Vec<(Indicator, Vec<f32>)>> {
        let model = if nominal {
            &self.result.nominal
        } else {
            &self.result.calibrated
        };
        let analysis = self.analysis_of(model)?;
        Ok(Indicator::ALL
            .iter()
            .filter_map(|&i| analysis.samples(split, i).map(|s| (i, s.to_vec())))
            .collect())
    }

    fn analysis_of(&self, model: &crate::kinematics::DualArmModel) -> Result<Analysis> {
        let body_from_left_base = self.robot.body_from_arm_base(Side::Left);
        Ok(Analysis::compute_excluding(
            &self.dataset,
            model,
            &body_from_left_base,
            &self.result.settings.exclude,
        )?)
    }

    /// The screening of the calibrated model (suspect configurations, whole-file findings).
    pub fn screening(&self) -> &Screening {
        &self.screening
    }

    /// The parameter file (`dualcal-params/1`), as `dualcal calibrate --out` writes it.
    pub fn params(&self) -> &ParamsFile {
        &self.params
    }

    /// The parameter file as JSON text.
    pub fn params_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(&self.params).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Write the parameter file (atomically; never over one of the dataset's or robot's files).
    pub fn save_params(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.refuse_input(path)?;
        self.params.write(path)?;
        Ok(())
    }

    /// The calibrated URDF: the user's own description with only the arm joints' origins changed
    /// (the built-in robot's: its DH origins).
    pub fn urdf(&self) -> Result<String> {
        Ok(crate::urdf_export::calibrated_urdf(
            &self.robot,
            &self.result.calibrated,
        )?)
    }

    /// Write the calibrated URDF (atomically; never over an input file).
    pub fn save_urdf(&self, path: impl AsRef<Path>) -> Result<()> {
        let text = self.urdf()?;
        self.write(path.as_ref(), text.as_bytes())
    }

    /// The calibration's changes to the description as an overlay: YAML, or JSON with `json`.
    pub fn overlay(&self, json: bool) -> Result<String> {
        let overlay = crate::urdf_export::calibrated_overlay(&self.robot, &self.result.calibrated)?;
        Ok(if json {
            overlay.to_json()
        } else {
            overlay.to_yaml()
        })
    }

    /// Each arm's controller base frame under the calibrated model as an ABB `MOC.cfg` fragment
    /// (`ROB_L`/`ROB_R`; the left arm's kept, the right arm's placed by step 2).
    pub fn abb_base_frames(&self) -> String {
        let frames =
            crate::controller::controller_base_frames(&self.robot, &self.result.calibrated);
        let names = crate::controller::abb::unit_names(None);
        let frames: Vec<crate::controller::abb::BaseFrame> = Side::BOTH
            .iter()
            .map(|&side| {
                crate::controller::abb::BaseFrame::from_isometry_mm(&names[side], &frames[side])
            })
            .collect();
        crate::controller::abb::to_cfg(&frames, "dualcal: the calibrated base frames")
    }

    /// Joint targets of `side` compensated: the joint values with which the calibrated robot reaches
    /// the pose its controller's nominal model meant (nominal joint targets, or flange poses in the
    /// arm's base frame) — `dualcal compensate` (docs/controller.md). One result per target, in
    /// order: the compensated joints, or why the target was refused (out of reach, beyond a joint
    /// limit, near a singular configuration).
    ///
    /// ```
    /// # let ds = dualcal::Dataset::load(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/datasets/example"))?;
    /// # let result = dualcal::Calibration::new(&ds).max_iterations(5).run()?;
    /// use dualcal::controller::compensate::{CompensationSettings, Target};
    /// let q = ds.data().arm(dualcal::Side::Left).measurements[0].q_rad.clone(); // rad, chain order
    /// let out = result.compensate(dualcal::Side::Left, &[Target::Joints(q)], &CompensationSettings::default());
    /// let q = out[0].as_ref().expect("reached");
    /// assert!(q.residual_mm < 1e-3);
    /// # Ok::<(), dualcal::Error>(())
    /// ```
    pub fn compensate(
        &self,
        side: Side,
        targets: &[Target],
        settings: &CompensationSettings,
    ) -> Vec<Result<Compensated, Refusal>> {
        compensate_all(
            &self.result.nominal,
            &self.result.calibrated,
            side,
            targets,
            &self.robot.arm_joint_names(side),
            settings,
        )
    }

    /// A target list file of `side` (`id,q1..qN` nominal joints, or `id,x,y,z,qw,qx,qy,qz[,q1..qN]`
    /// flange poses in the arm's base frame; docs/formats.md) compensated: the table `dualcal
    /// compensate --out` writes (the joints, the change, the residual, `ok` or why a row was refused).
    pub fn compensate_file(
        &self,
        side: Side,
        targets: impl AsRef<Path>,
        units: TargetUnits,
        settings: &CompensationSettings,
    ) -> Result<String> {
        let path = targets.as_ref();
        let text =
            std::fs::read_to_string(path).map_err(|e| crate::output::FileError::read(path, e))?;
        let names = self.robot.arm_joint_names(side);
        let linear = self.result.nominal.arm(side).linear_joints();
        let rows = crate::controller::targets::parse(path, &text, &names, &linear, units)?;
        let targets: Vec<Target> = rows.iter().map(|r| r.target.clone()).collect();
        let results = self.compensate(side, &targets, settings);
        Ok(crate::controller::targets::to_csv(
            &rows, &results, &names, &linear, units,
        ))
    }

    /// The engine's whole result (history, identifiability, stages).
    pub fn result(&self) -> &CalibrationResult {
        &self.result
    }

    fn refuse_input(&self, path: &Path) -> Result<()> {
        let mut inputs: Vec<std::path::PathBuf> = self.dataset.files().to_vec();
        inputs.extend(self.dataset.robot.clone());
        inputs.extend(self.robot.source.clone());
        let inputs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
        Ok(crate::output::refuse_overwrite_input(path, &inputs)?)
    }

    fn write(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.refuse_input(path)?;
        crate::output::write_atomic(path, bytes).map_err(|source| Error::Write {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// The accuracy of a parameter file's model on `dataset` (both splits, every configuration): what
/// `dualcal evaluate` prints.
pub fn evaluate(dataset: &Dataset, params: impl AsRef<Path>) -> Result<PerSplit> {
    let ws = &dataset.workspace;
    let model = ParamsFile::read(params.as_ref())?.to_model_for(&ws.robot)?;
    let ds = &ws.dataset;
    let split = |split: Split| -> Result<Option<AccuracyReport>> {
        if !crate::metrics::has_split(ds, split) {
            return Ok(None);
        }
        Ok(Some(crate::metrics::evaluate(ds, &model, split)?))
    };
    Ok(PerSplit {
        calibration: split(Split::Cal)?,
        verification: split(Split::Ver)?,
    })
}

/// A model's figures on both splits (`None`: a split the dataset does not have).
#[derive(Clone, Debug)]
pub struct PerSplit {
    /// The calibration configurations.
    pub calibration: Option<AccuracyReport>,
    /// The verification configurations.
    pub verification: Option<AccuracyReport>,
}
