//! What a plan is written as (`dualcal plan --out DIR`, the workbench's "Save plan"): per arm the
//! dataset CSV to fill in (`<arm>.csv`: `id,q1..qN,split`), the visiting sequence with its via points
//! (`path_<arm>.csv`), for the YuMi a RAPID module of `MoveAbsJ` targets (`plan_<arm>.mod`), and the
//! `dataset.toml` that reads them; plus the summary lines `dualcal plan` prints.

use super::ArmPlan;
use crate::dataset::TrackerSpec;
use crate::robot::{RobotDescription, arm_joint_name};
use crate::side::{PerSide, Side};
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::Path;

/// What the files of a plan say besides the plans.
pub struct PlanOutput<'a> {
    pub robot: &'a RobotDescription,
    /// The robot description's file (`None`: built in): the manifest names it and the arms' chains.
    pub robot_path: Option<&'a Path>,
    /// The reflectors' nominal positions in the tip frame, mm (named a, b, c, …).
    pub reflectors_mm: &'a [Vector3<f64>],
    pub tracker: TrackerSpec,
    /// New configurations beside an extended dataset's: ids `LP…`/`RP…` instead of `L…`/`R…`.
    pub extending: bool,
}

/// The files of a plan: name and contents, in the order they are written (the manifest last).
pub fn plan_files(out: &PlanOutput<'_>, plans: &PerSide<ArmPlan>) -> Vec<(String, String)> {
    let mut files = Vec::new();
    for side in Side::BOTH {
        let p = &plans[side];
        let linear = out.robot.arm(side).linear_joints();
        let prefix = id_prefix(side, out.extending);
        files.push((
            format!("{}.csv", side.name()),
            arm_csv(side, prefix, p, &linear),
        ));
        files.push((
            format!("path_{}.csv", side.name()),
            path_csv(side, prefix, p, &linear),
        ));
        if is_yumi(out.robot) {
            files.push((
                format!("plan_{}.mod", side.name()),
                rapid_module(side, prefix, p),
            ));
        }
    }
    files.push((
        crate::dataset::MANIFEST_FILE.to_string(),
        manifest(out.robot, out.robot_path, out.reflectors_mm, &out.tracker),
    ));
    files
}

/// The ids of an arm's planned configurations start with this.
pub fn id_prefix(side: Side, extending: bool) -> &'static str {
    match (side, extending) {
        (Side::Left, false) => "L",
        (Side::Right, false) => "R",
        // New ids beside the extended dataset's own.
        (Side::Left, true) => "LP",
        (Side::Right, true) => "RP",
    }
}

/// Whether the robot is a YuMi (the built-in one, or a description with its joint names): its plan
/// gets RAPID modules.
pub fn is_yumi(robot: &RobotDescription) -> bool {
    robot.is_builtin()
        || (robot
            .urdf
            .joints
            .iter()
            .any(|j| j.name == arm_joint_name(Side::Left, 0))
            // The YuMi's seven axes per arm, nothing shared: a YuMi-named robot on a torso is not one
            // whose controller takes these targets.
            && Side::BOTH
                .into_iter()
                .all(|side| robot.arm(side).chain.dof() == 7)
            && robot.shared_joints().is_empty())
}

/// The line `dualcal plan` prints for an arm: how many configurations from how many candidates, the
/// design's information against a random set's, its I-criterion after exchange against the greedy
/// pass's, the path, its via points and any leg still colliding.
pub fn summary_line(side: Side, p: &ArmPlan) -> String {
    format!(
        "{side} arm: {} configurations chosen from {} candidates ({} draws); log det of the design \
         {:.1} (the first {} candidates drawn: {:.1}); I-criterion {:.4} after {} exchange swap(s) \
         (greedy {:.4}); path {:.2} (joint space){}",
        p.configs.len(),
        p.candidates,
        p.attempts,
        p.log_det,
        p.configs.len(),
        p.log_det_random,
        p.criterion,
        p.swaps,
        p.criterion_greedy,
        p.path_length,
        via_summary(p)
    )
}

/// What [`ArmPlan::bound`] says, for `dualcal plan` and the planning window: no design of as many of
/// these candidates predicts a better verification accuracy than the bound; the relaxed design's and
/// this design's with an efficient fit of the distances beside it, and the method that fits them so:
/// the absolute positions with the tracker's pose (`position`, ref. \[18\]) measures within a few
/// thousandths of that prediction in simulation, where the distance methods (least squares, the
/// paper's minimax) measure above the least-squares one (docs/planning.md).
pub fn bound_line(p: &ArmPlan) -> Option<String> {
    let b = p.bound.as_ref()?;
    Some(format!(
        "bound: no {} of these candidates predict better than {:.3}× (relaxed design {:.3}× on {} \
         candidates); this design {:.3}× with an efficient fit of its distances (calibrating with \
         `--method position` fits them so: docs/planning.md)",
        b.per_arm,
        b.ratio(),
        b.relaxed_ratio(),
        b.support,
        b.design_ratio()
    ))
}

/// The via points and the legs still colliding, for the summary line.
fn via_summary(p: &ArmPlan) -> String {
    let mut s = String::new();
    if !p.vias.is_empty() {
        let _ = write!(
            s,
            "; {} leg(s) re-routed through a via point ({:?})",
            p.vias.len(),
            p.vias.iter().map(|v| v.leg + 1).collect::<Vec<_>>()
        );
    }
    if !p.colliding_legs.is_empty() {
        let _ = write!(
            s,
            "; WARNING: the straight joint motion of legs {:?} collides and no via point clears it — \
             move the robot there by hand",
            p.colliding_legs.iter().map(|k| k + 1).collect::<Vec<_>>()
        );
    }
    s
}

/// One joint vector as CSV fields: degrees, mm for a prismatic joint.
fn joint_fields(s: &mut String, q: &[f64], linear: &[bool]) {
    for (k, v) in q.iter().enumerate() {
        let v = if linear.get(k).copied().unwrap_or(false) {
            *v
        } else {
            v.to_degrees()
        };
        let _ = write!(s, ",{v:.6}");
    }
}

fn q_header(s: &mut String, n: usize) {
    for k in 1..=n {
        let _ = write!(s, ",q{k}");
    }
}

/// `id,q1..qN,split`: degrees (mm for a prismatic joint), every configuration a calibration one.
fn arm_csv(side: Side, prefix: &str, p: &ArmPlan, linear: &[bool]) -> String {
    let n = p.configs.first().map_or(0, Vec::len);
    let mut s = format!(
        "# dualcal plan: {side} arm, {} configurations in visiting order; q in degrees (mm for a \
         prismatic joint), chain order. Add the reflector columns <name>x,<name>y,<name>z (mm) from the \
         measurement.\nid",
        p.configs.len()
    );
    q_header(&mut s, n);
    s.push_str(",split\n");
    for (i, q) in p.configs.iter().enumerate() {
        let _ = write!(s, "{prefix}{:03}", i + 1);
        joint_fields(&mut s, q, linear);
        s.push_str(",cal\n");
    }
    s
}

/// The visiting sequence: `step,kind,target,q1..qN` — each configuration to measure (`measure`, its
/// id) and each via point (`via`, `V<k>` after configuration k), in the order the arm moves.
fn path_csv(side: Side, prefix: &str, p: &ArmPlan, linear: &[bool]) -> String {
    let n = p.configs.first().map_or(0, Vec::len);
    let mut s = format!(
        "# dualcal plan: {side} arm, the visiting sequence — {} configurations to measure and {} via \
         point(s) where the straight joint motion would collide; q in degrees (mm for a prismatic \
         joint), chain order.\nstep,kind,target",
        p.configs.len(),
        p.vias.len()
    );
    q_header(&mut s, n);
    s.push('\n');
    let mut step = 0;
    for (i, q) in p.configs.iter().enumerate() {
        step += 1;
        let _ = write!(s, "{step},measure,{prefix}{:03}", i + 1);
        joint_fields(&mut s, q, linear);
        s.push('\n');
        for via in p.vias.iter().filter(|v| v.leg == i) {
            step += 1;
            let _ = write!(s, "{step},via,V{:03}", i + 1);
            joint_fields(&mut s, &via.q, linear);
            s.push('\n');
        }
    }
    s
}

/// A RAPID module of `MoveAbsJ` targets for one YuMi arm: robot axes 1–6 (ABB order) and axis 7 as
/// the external axis `eax_a`, in degrees; chain order is ABB axes 1, 2, 7, 3, 4, 5, 6. Via points
/// are passed with a zone, not stopped at.
fn rapid_module(side: Side, prefix: &str, p: &ArmPlan) -> String {
    let name = format!("dualcal_plan_{}", side.name());
    let mut s = format!(
        "MODULE {name}\n    ! dualcal plan, {side} arm: {} configurations in visiting order ({prefix}001 \
         is p001).\n    ! Move to each, stop, measure the reflectors, go on.\n    ! The other arm rests at its \
         home pose meanwhile: the plan's collision checks assume it there.\n",
        p.configs.len()
    );
    let target = |s: &mut String, name: &str, q: &[f64]| {
        let d: Vec<f64> = q.iter().map(|v| v.to_degrees()).collect();
        let _ = writeln!(
            s,
            "    CONST jointtarget {name} := [[{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}],[{:.4},9E9,9E9,9E9,9E9,9E9]];",
            d[0], d[1], d[3], d[4], d[5], d[6], d[2]
        );
    };
    for (i, q) in p.configs.iter().enumerate() {
        target(&mut s, &format!("p{:03}", i + 1), q);
    }
    for via in &p.vias {
        target(&mut s, &format!("v{:03}", via.leg + 1), &via.q);
    }
    s.push_str("\n    PROC measure_all()\n");
    for i in 0..p.configs.len() {
        let _ = writeln!(
            s,
            "        MoveAbsJ p{:03}, v100, fine, tool0;\n        WaitTime 2; ! measure p{:03}",
            i + 1,
            i + 1
        );
        if p.vias.iter().any(|v| v.leg == i) {
            let _ = writeln!(
                s,
                "        MoveAbsJ v{:03}, v100, z50, tool0; ! via point: the straight motion to p{:03} collides",
                i + 1,
                i + 2
            );
        }
    }
    s.push_str("    ENDPROC\nENDMODULE\n");
    s
}

/// The dataset manifest for the planned files.
fn manifest(
    robot: &RobotDescription,
    robot_path: Option<&Path>,
    reflectors: &[Vector3<f64>],
    tracker: &TrackerSpec,
) -> String {
    let mut s = String::from("format = \"dualcal-dataset/1\"\n");
    if let Some(path) = robot_path {
        let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        let _ = writeln!(s, "robot = {:?}", path.display().to_string());
    }
    let _ = write!(
        s,
        "description = \"planned by dualcal plan: fill in the reflector columns\"\n\n[units]\nlength = \
         \"mm\"\nangle = \"deg\"\n\n[tracker]\nmpe_um = {:?}\nmpe_um_per_m = {:?}\n\n[reflectors]\n",
        tracker.mpe_um, tracker.mpe_um_per_m
    );
    for (name, r) in crate::kinematics::default_reflector_names(reflectors.len())
        .iter()
        .zip(reflectors)
    {
        let _ = writeln!(s, "{name} = [{:?}, {:?}, {:?}]", r.x, r.y, r.z);
    }
    for side in Side::BOTH {
        let _ = write!(
            s,
            "\n[[arms]]\nname = \"{}\"\nfile = \"{}.csv\"\n",
            side.name(),
            side.name()
        );
        if robot_path.is_some() {
            let links = &robot.arm(side).links;
            let _ = write!(
                s,
                "base_link = {:?}\ntip_link = {:?}\n",
                links.base_link, links.tip_link
            );
        }
    }
    s
}
