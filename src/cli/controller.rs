//! `dualcal export` (the calibration in a controller's and a xacro's terms) and `dualcal compensate`
//! (joint targets moved for what a controller cannot take); the engine's `controller` module.

use super::common::{describe_robot, load_workspace};
use crate::controller::abb::{self, BaseFrame};
use crate::controller::compensate::{CompensationSettings, ControllerBase, Target, compensate_all};
use crate::controller::{controller_base_frames, targets};
use crate::dataset::{AngleUnit, LengthUnit};
use crate::output::{refuse_overwrite_input, write_atomic};
use crate::params::ParamsFile;
use crate::side::{PerSide, Side};
use crate::urdf_export::calibrated_overlay;
use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Dataset directory or its dataset.toml (its robot description is the one calibrated).
    pub dataset: PathBuf,
    /// Parameter file (dualcal-params/1).
    #[arg(long)]
    pub params: PathBuf,
    /// Write the arms' base frames as an ABB `MOC.cfg` fragment (`ROBOT` instances with
    /// `-base_frame_pos_*` in metres and `-base_frame_orient_u0…u3`, scalar first).
    #[arg(long)]
    pub abb_cfg: Option<PathBuf>,
    /// The mechanical units' names, LEFT,RIGHT.
    #[arg(long, default_value = "ROB_L,ROB_R")]
    pub abb_units: String,
    /// The controller's `MOC.cfg` (or a fragment) with the base frames it has now: the left arm keeps
    /// its frame and the right one is placed from it [default: the description's frames].
    #[arg(long)]
    pub abb_current: Option<PathBuf>,
    /// Write the calibrated joint origins as a kinematics YAML a xacro reads (UR style).
    #[arg(long)]
    pub kinematics_yaml: Option<PathBuf>,
}

/// `dualcal export`.
pub fn run_export(a: &ExportArgs) -> Result<()> {
    if a.abb_cfg.is_none() && a.kinematics_yaml.is_none() {
        bail!("nothing to write: give --abb-cfg and/or --kinematics-yaml");
    }
    let ws = load_workspace(&a.dataset)?;
    let model = ParamsFile::read(&a.params)?
        .to_model_for(&ws.robot)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.params.display()))?;
    let inputs: Vec<&Path> = [Some(a.params.as_path()), a.abb_current.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    outln!("{}", describe_robot(&ws.robot));
    if let Some(out) = &a.abb_cfg {
        refuse_overwrite_input(out, &inputs)?;
        let names = unit_names(&a.abb_units)?;
        let nominal = controller_base_frames(&ws.robot, &ws.nominal);
        let calibrated = controller_base_frames(&ws.robot, &model);
        // The frames the controller has now (its file, else the description's).
        let current = match &a.abb_current {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("{}: cannot read", path.display()))?;
                let frames =
                    abb::parse_cfg(&text).map_err(|e| anyhow::anyhow!("{}:{e}", path.display()))?;
                PerSide::try_from_fn(|side| {
                    abb::frame_of(&frames, &names, side)
                        .map(BaseFrame::isometry_mm)
                        .ok_or_else(|| {
                            anyhow::anyhow!(
                                "{}: no ROBOT \"{}\" with base-frame attributes",
                                path.display(),
                                names[side]
                            )
                        })
                })?
            }
            None => nominal,
        };
        // The left frame as the controller has it; the right one placed from it by the calibration.
        let anchor: Isometry3<f64> = current.left * nominal.left.inverse();
        let frames: Vec<BaseFrame> = Side::BOTH
            .iter()
            .map(|&side| BaseFrame::from_isometry_mm(&names[side], &(anchor * calibrated[side])))
            .collect();
        let comment = format!(
            "Base frames of {} calibrated by dualcal from {}.\nThe left arm's frame is the \
             controller's; the right arm's is placed from it by the calibration.\nLoad into the \
             controller's motion configuration (or type the values in) and restart.",
            ws.robot.name(),
            a.params.display()
        );
        write_atomic(out, abb::to_cfg(&frames, &comment).as_bytes())
            .with_context(|| format!("{}: cannot write", out.display()))?;
        outln!("ABB base frames (world frame; position m, orientation u0…u3 scalar first):");
        for (side, f) in Side::BOTH.iter().zip(&frames) {
            let was = BaseFrame::from_isometry_mm(&names[*side], &current[*side]);
            let change = current[*side].inverse() * f.isometry_mm();
            outln!(
                "  {:<6} pos {:.6} {:.6} {:.6}  orient {:.7} {:.7} {:.7} {:.7}   (was pos {:.6} {:.6} \
                 {:.6}  orient {:.7} {:.7} {:.7} {:.7}; moved {:.3} mm, {:.3} mrad)",
                f.name,
                f.pos_m.x,
                f.pos_m.y,
                f.pos_m.z,
                f.orient[0],
                f.orient[1],
                f.orient[2],
                f.orient[3],
                was.pos_m.x,
                was.pos_m.y,
                was.pos_m.z,
                was.orient[0],
                was.orient[1],
                was.orient[2],
                was.orient[3],
                change.translation.vector.norm(),
                change.rotation.angle() * 1000.0
            );
        }
        outln!(
            "wrote {} (what the controller cannot take — link lengths, joint origins — is for \
             `dualcal compensate`)",
            out.display()
        );
    }
    if let Some(out) = &a.kinematics_yaml {
        refuse_overwrite_input(out, &inputs)?;
        let overlay = calibrated_overlay(&ws.robot, &model)?;
        write_atomic(out, overlay.to_kinematics_yaml().as_bytes())
            .with_context(|| format!("{}: cannot write", out.display()))?;
        outln!(
            "wrote {} ({} joint origins)",
            out.display(),
            overlay.joints.len()
        );
    }
    Ok(())
}

/// The world (the left arm's model base frame) from the tracker frame of `side`'s measurements: the
/// best rigid fit of the calibrated model's reflector points to the measured ones, over both arms
/// when they share a station; with its RMS, mm.
fn register_tracker(
    ds: &crate::dataset::Dataset,
    model: &crate::kinematics::DualArmModel,
    side: Side,
) -> Result<(Isometry3<f64>, f64)> {
    let shared = ds.arm(Side::Left).station == ds.arm(Side::Right).station;
    let (mut tracker, mut world) = (Vec::new(), Vec::new());
    for s in Side::BOTH.into_iter().filter(|&s| shared || s == side) {
        let base = model.left_base_from(s);
        for m in &ds.arm(s).measurements {
            let fk = model.arm(s).reflector_fk(&m.q_rad);
            for (p, t) in fk.points_mm.iter().zip(&m.tracker_points_mm) {
                tracker.push(*t);
                world.push(base.transform_point(&nalgebra::Point3::from(*p)).coords);
            }
        }
    }
    let fit = crate::analysis::best_fit_rigid(&tracker, &world).ok_or_else(|| {
        anyhow::anyhow!(
            "the tracker frame cannot be registered: the measured points are degenerate"
        )
    })?;
    let rms = (tracker
        .iter()
        .zip(&world)
        .map(|(t, w)| (fit.transform_point(&nalgebra::Point3::from(*t)).coords - w).norm_squared())
        .sum::<f64>()
        / tracker.len().max(1) as f64)
        .sqrt();
    Ok((fit, rms))
}

fn unit_names(s: &str) -> Result<PerSide<String>> {
    match s.split(',').map(str::trim).collect::<Vec<_>>().as_slice() {
        [l, r] if !l.is_empty() && !r.is_empty() && l != r => {
            Ok(PerSide::new(l.to_string(), r.to_string()))
        }
        _ => bail!("--abb-units `{s}`: expected two different names LEFT,RIGHT"),
    }
}

/// Which arm on the command line.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum ArmArg {
    Left,
    Right,
}

/// The base frames the controller uses.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum ControllerBaseArg {
    /// Its nominal frames: the relative base error is compensated in the joints too.
    Nominal,
    /// The calibrated frames of `dualcal export --abb-cfg` are loaded.
    Calibrated,
}

/// The frame of pose targets.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum FrameArg {
    Base,
    Tracker,
}

/// Angle unit of the target list.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum AngleArg {
    Deg,
    Rad,
}

/// Length unit of the target list.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum LengthArg {
    Mm,
    M,
}

#[derive(Args, Debug)]
pub struct CompensateArgs {
    /// Dataset directory or its dataset.toml (its robot description is the one calibrated).
    pub dataset: PathBuf,
    /// Parameter file (dualcal-params/1).
    #[arg(long)]
    pub params: PathBuf,
    /// The arm whose targets these are.
    #[arg(long, value_enum)]
    pub arm: ArmArg,
    /// The targets: `id,q1..qN` (nominal joint values) or `id,x,y,z,qw,qx,qy,qz[,q1..qN]` (flange
    /// poses in the arm's model base frame, optional seed joints); docs/formats.md.
    #[arg(long)]
    pub targets: PathBuf,
    /// Output CSV: the compensated joints, the change, the residual, `ok` or why a target was refused.
    #[arg(long)]
    pub out: PathBuf,
    /// The base frames the controller uses.
    #[arg(long, value_enum, default_value_t = ControllerBaseArg::Nominal)]
    pub controller_base: ControllerBaseArg,
    /// Angle unit of the joint values, in and out.
    #[arg(long, value_enum, default_value_t = AngleArg::Deg)]
    pub angle_unit: AngleArg,
    /// Length unit of positions and prismatic joints, in and out.
    #[arg(long, value_enum, default_value_t = LengthArg::Mm)]
    pub length_unit: LengthArg,
    /// The frame of pose targets: `base` (the arm's model base frame, as the controller's nominal
    /// model places the pose) or `tracker` (where the pose physically is, in the dataset's tracker
    /// frame: registered with the calibrated model on the dataset's points).
    #[arg(long, value_enum, default_value_t = FrameArg::Base)]
    pub frame: FrameArg,
    /// Refuse a target whose compensation moves a revolute joint by more than this (near a singular
    /// configuration), degrees.
    #[arg(long, default_value_t = 20.0)]
    pub max_change_deg: f64,
    /// The same for a prismatic joint, mm.
    #[arg(long, default_value_t = 50.0)]
    pub max_change_mm: f64,
}

/// Targets `dualcal compensate` refused (the file is written, each reason in its row): the command
/// exits with [`TargetsRefused::EXIT_CODE`].
#[derive(Debug, thiserror::Error)]
#[error("{0} of the targets were refused (their rows say why)")]
pub struct TargetsRefused(pub usize);

impl TargetsRefused {
    /// Exit status when targets were refused (1 is for errors, 2 for a calibration that did not
    /// converge).
    pub const EXIT_CODE: u8 = 3;
}

/// `dualcal compensate`.
pub fn run_compensate(a: &CompensateArgs) -> Result<()> {
    if !(a.max_change_deg > 0.0 && a.max_change_mm > 0.0) {
        bail!("--max-change-deg and --max-change-mm: expected positive numbers");
    }
    let ws = load_workspace(&a.dataset)?;
    let model = ParamsFile::read(&a.params)?
        .to_model_for(&ws.robot)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.params.display()))?;
    refuse_overwrite_input(&a.out, &[a.params.as_path(), a.targets.as_path()])?;
    let side = match a.arm {
        ArmArg::Left => Side::Left,
        ArmArg::Right => Side::Right,
    };
    let units = targets::TargetUnits {
        angle: match a.angle_unit {
            AngleArg::Deg => AngleUnit::Deg,
            AngleArg::Rad => AngleUnit::Rad,
        },
        length: match a.length_unit {
            LengthArg::Mm => LengthUnit::Mm,
            LengthArg::M => LengthUnit::M,
        },
    };
    let names = ws.robot.arm_joint_names(side);
    let linear = ws.nominal.arm(side).linear_joints();
    let text = std::fs::read_to_string(&a.targets)
        .with_context(|| format!("{}: cannot read", a.targets.display()))?;
    let mut rows = targets::parse(&a.targets, &text, &names, &linear, units)?;
    if a.frame == FrameArg::Tracker {
        let (world_from_tracker, rms_mm) = register_tracker(&ws.dataset, &model, side)?;
        outln!(
            "tracker frame registered on the dataset's points with the calibrated model (RMS {rms_mm:.4}              mm)"
        );
        for row in &mut rows {
            match &row.target {
                Target::Pose {
                    base_from_flange,
                    seed,
                } => {
                    row.target = Target::WorldPose {
                        left_base_from_flange: world_from_tracker * base_from_flange,
                        seed: seed.clone(),
                    };
                }
                Target::Joints(_) | Target::WorldPose { .. } => bail!(
                    "{}: --frame tracker takes poses (`id,x,y,z,qw,qx,qy,qz`), not joint targets",
                    a.targets.display()
                ),
            }
        }
    }
    let settings = CompensationSettings {
        controller_base: match a.controller_base {
            ControllerBaseArg::Nominal => ControllerBase::Nominal,
            ControllerBaseArg::Calibrated => ControllerBase::Calibrated,
        },
        max_change_rad: a.max_change_deg.to_radians(),
        max_change_mm: a.max_change_mm,
        ..CompensationSettings::default()
    };
    let results = compensate_all(
        &ws.nominal,
        &model,
        side,
        rows.iter().map(|r| &r.target),
        &names,
        &settings,
    );
    write_atomic(
        &a.out,
        targets::to_csv(&rows, &results, &names, &linear, units).as_bytes(),
    )
    .with_context(|| format!("{}: cannot write", a.out.display()))?;
    outln!("{}", describe_robot(&ws.robot));
    let refused: Vec<String> = rows
        .iter()
        .zip(&results)
        .filter_map(|(r, res)| {
            res.as_ref()
                .err()
                .map(|e| format!("{} (line {}): {e}", r.id, r.line))
        })
        .collect();
    let ok: Vec<_> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    let largest_mm = ok.iter().map(|c| c.residual_mm).fold(0.0, f64::max);
    outln!(
        "{side} arm: {} of {} targets compensated (largest remaining error of the calibrated model \
         {largest_mm:.1e} mm); wrote {}",
        ok.len(),
        rows.len(),
        a.out.display()
    );
    if !refused.is_empty() {
        for r in &refused {
            eprintln!("refused: {r}");
        }
        return Err(TargetsRefused(refused.len()).into());
    }
    Ok(())
}
