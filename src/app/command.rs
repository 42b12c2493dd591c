//! What the user can ask for: the [`Command`]s the panels, the viewport and the prompt return, and
//! the kinds they name. This file imports only plain state types of the app (a view's inputs and
//! options, which import no command) and not the handler ([`super::apply`]), so every module below
//! the app can name a command without an import circle.
//!
//! The `Set…` commands put what a view's widgets edit in place (the settings, the display options,
//! the camera, the import's and the plan's inputs) in one go: how a script or a test drives the
//! workbench ([`super::WorkbenchApp::apply`]) without reaching into its state.

use super::import::ImportInputs;
pub use super::import::ImportSlot;
use super::plan_view::PlanInputs;
use super::viewport::camera::OrbitCamera;
use super::viewport::scene::SceneOptions;
use crate::side::{ConfigId, Side};
use crate::solver::CalibrationSettings;
use std::path::PathBuf;

/// What the user wants to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpenKind {
    /// A `dataset.toml` (or its directory).
    Dataset,
    /// A robot description.
    Urdf,
    /// A tracker export or joint log for the import view.
    ImportFile(ImportSlot),
    /// The folder the import view writes its dataset to.
    ImportFolder,
}

/// What to export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Export {
    Params,
    Urdf,
    Csv,
    PlotPng,
    /// The calibration report (`dualcal report`): one self-contained HTML file.
    Report,
}

/// Something the user asked for.
#[derive(Debug)]
pub enum Command {
    /// Load a dataset (directory or `dataset.toml`); the current one stays until it has loaded.
    OpenDataset(PathBuf),
    /// Reload the current dataset with another robot description (used for later datasets too).
    OpenUrdf(PathBuf),
    /// Reload the current dataset with the robot it names (drop the one opened with [`Self::OpenUrdf`]).
    UseDatasetRobot,
    /// Ask the user for a file to open: the native dialog, or the in-app path prompt without one.
    ChooseFile(OpenKind),
    /// Calibrate the current dataset with the current settings.
    StartCalibration,
    /// Stop the running calibration; the last finished calibration (or the nominal model) is shown
    /// again, the model the run reached is discarded.
    CancelCalibration,
    /// Select a configuration (or none); `reveal_in_table` scrolls the table to it.
    Select {
        config: Option<ConfigId>,
        reveal_in_table: bool,
    },
    /// Select the configuration with the largest |Δd| of the current model.
    SelectWorst,
    /// Leave a configuration out (or take it back in) and calibrate again at once.
    ToggleExclude(ConfigId),
    /// Take every excluded configuration back in and calibrate again.
    ClearExclusions,
    /// Apply the Auto-exclude rule (`dualcal calibrate --auto-exclude`): screen, leave the suspects
    /// out, fit, screen again; its calibration becomes the current one.
    AutoExclude,
    Export(Export),
    /// The path typed into the path prompt.
    ConfirmPrompt(PathBuf),
    ClosePrompt,
    /// Remove the error message at this index.
    DismissError(usize),
    /// Open (or close) the comparison view.
    ShowComparison(bool),
    /// Run the picked methods on the current dataset, one after another in the background.
    StartComparison,
    /// Stop the running comparison (finished methods stay listed).
    CancelComparison,
    /// Make the compared method's result (by its key) the current calibration.
    AdoptCompared(&'static str),
    /// Put a picked file into the import view.
    SetImportFile(ImportSlot, PathBuf),
    /// The folder the import view writes to.
    SetImportFolder(PathBuf),
    /// Open (or close) the import view.
    ShowImport(bool),
    /// Read the import's files again (they may have changed on disk).
    RefreshImport,
    /// Write the previewed import as a dataset (in a browser: in memory) and open it.
    FinishImport,
    /// Open (or close) the planning view.
    ShowPlan(bool),
    /// Plan the measurement with the planning view's inputs, in the background.
    StartPlan,
    /// Save the plan's files as one `.zip`.
    SavePlan,
    /// Draw an arm in one of its planned configurations (`None`: home).
    ShowPlannedPose(Side, Option<usize>),
    /// The calibration settings, as the settings panel edits them (a changed step-1 method counts
    /// as picked: a new dataset no longer sets its default).
    SetSettings(Box<CalibrationSettings>),
    /// Pick exactly the comparison's methods with these keys (unknown keys are ignored).
    PickComparedMethods(Vec<String>),
    /// The 3D view's display options, as its View section edits them.
    SetViewOptions(Box<SceneOptions>),
    /// Put the 3D view's camera (as dragging and scrolling in it do).
    SetCamera(Box<OrbitCamera>),
    /// Choose the exaggeration and colour range from the errors when a model arrives (or not).
    SetAutoScale(bool),
    /// The import view's inputs, as its fields edit them.
    SetImportInputs(Box<ImportInputs>),
    /// The planning view's inputs, as its fields edit them.
    SetPlanInputs(Box<PlanInputs>),
}

impl Command {
    /// Open a file the user chose.
    pub fn open(kind: OpenKind, path: PathBuf) -> Self {
        match kind {
            OpenKind::Dataset => Command::OpenDataset(path),
            OpenKind::Urdf => Command::OpenUrdf(path),
            OpenKind::ImportFile(slot) => Command::SetImportFile(slot, path),
            OpenKind::ImportFolder => Command::SetImportFolder(path),
        }
    }
}

/// The answer to a file request (a dialog, a browser upload, a typed path).
#[derive(Debug)]
pub enum FileReply {
    Open(OpenKind, PathBuf),
    Saved(PathBuf),
    Failed(String),
    /// The user closed the dialog.
    Cancelled,
}
