//! Loading and packing the session's robot meshes ([`MeshWork`]); placeholders are drawn until they
//! arrive. It goes on when a dataset with the same robot loads.

use super::{Flow, Job, JobContext, Lane};
use crate::app::session::{LoadedMeshes, RobotMeshes, Session};
use crate::app::task::{BackgroundTask, Step, TaskContext, Work};
use crate::app::viewport::mesh_pack::{MeshKey, PackedMeshes};
use crate::meshes::{GeometryKind, MeshWarning, lod};
use crate::robot::{RobotDescription, ShapeKind};
use crate::side::Side;
use std::sync::Arc;
use web_time::Instant;

/// Load a robot's visual meshes and pack them for the GPU. Links whose visual mesh cannot be loaded
/// get their collision meshes loaded too (drawn as stand-ins).
pub struct MeshWork {
    pub robot: Arc<RobotDescription>,
}

impl Work for MeshWork {
    type Event = Box<LoadedMeshes>;

    fn step(&mut self, task: &TaskContext<Box<LoadedMeshes>>) -> Step {
        task.report(Box::new(load_meshes(&self.robot)));
        Step::Done
    }
}

/// Does the robot draw any mesh?
pub fn has_visual_meshes(robot: &RobotDescription) -> bool {
    robot.urdf.links.iter().any(|l| {
        l.visual
            .iter()
            .any(|v| matches!(v.geometry, urdf_rs::Geometry::Mesh { .. }))
    })
}

/// The robot's visual meshes packed, with the collision meshes of the links whose visual mesh is
/// missing; and a simplified copy of that pack for software renderers (not in the browser).
pub fn load_meshes(robot: &RobotDescription) -> LoadedMeshes {
    let started = Instant::now();
    let visual = robot.load_meshes(GeometryKind::Visual);
    let home = |side| robot.home_q_rad(side);
    let (ql, qr) = (home(Side::Left), home(Side::Right));
    let missing_links: Vec<String> = robot
        .shapes(&ql, &qr, GeometryKind::Visual)
        .into_iter()
        .filter(|s| match &s.kind {
            ShapeKind::Mesh {
                filename, scale, ..
            } => visual.get(filename, (*scale).into()).is_none(),
            _ => false,
        })
        .map(|s| s.link)
        .collect();
    let collision = if missing_links.is_empty() {
        Default::default()
    } else {
        robot.load_meshes(GeometryKind::Collision)
    };
    let stand_ins: Vec<(MeshKey, &crate::meshes::TriangleMesh)> = robot
        .shapes(&ql, &qr, GeometryKind::Collision)
        .into_iter()
        .filter(|s| missing_links.contains(&s.link))
        .filter_map(|s| match s.kind {
            ShapeKind::Mesh {
                filename, scale, ..
            } => {
                let scale: [f64; 3] = scale.into();
                let mesh = collision.get(&filename, scale)?;
                Some((
                    MeshKey::new(GeometryKind::Collision, &filename, scale),
                    &**mesh,
                ))
            }
            _ => None,
        })
        .collect();
    let visual_meshes = visual.meshes.iter().map(|((filename, bits), mesh)| {
        (
            MeshKey {
                kind: GeometryKind::Visual,
                filename: filename.clone(),
                scale_bits: *bits,
            },
            &**mesh,
        )
    });
    let (packed, simplified) =
        PackedMeshes::pack_with_lod(visual_meshes.chain(stand_ins), lod::ROBOT_TRIANGLES);
    // Files not found are named by the robot's own warnings already (per link).
    let warnings = visual
        .warnings
        .iter()
        .filter(|w| {
            !matches!(
                w,
                MeshWarning::NotFound { .. }
                    | MeshWarning::UnknownPackage { .. }
                    | MeshWarning::UnsupportedScheme { .. }
            )
        })
        .map(|w| format!("{w}; drawn as a placeholder"))
        .collect();
    LoadedMeshes {
        packed: Arc::new(packed),
        simplified: simplified.map(Arc::new),
        visual_files: visual.meshes.len(),
        visual_triangles: visual.triangle_count(),
        visual_missing: visual.warnings.len(),
        warnings,
        elapsed_secs: started.elapsed().as_secs_f64(),
    }
}

pub struct MeshJob;

impl MeshJob {
    pub fn lane() -> Lane {
        Lane::of::<Self>()
    }
}

impl Job for MeshJob {
    type Event = Box<LoadedMeshes>;

    fn survives_load(&self) -> bool {
        // [`start`] decides.
        true
    }

    fn on_event(
        &mut self,
        cx: &mut JobContext<'_>,
        _: &BackgroundTask,
        loaded: Box<LoadedMeshes>,
    ) -> Flow {
        set_meshes(cx, RobotMeshes::Loaded(Arc::new(*loaded)));
        Flow::Ended
    }

    fn on_failed(&mut self, cx: &mut JobContext<'_>, _: &BackgroundTask, message: String) {
        set_meshes(cx, RobotMeshes::Failed(message));
    }
}

fn set_meshes(cx: &mut JobContext<'_>, meshes: RobotMeshes) {
    if let Some(session) = cx.scene.edit() {
        session.meshes = meshes;
    }
}

/// Load the new session's robot meshes on a background task (placeholders are drawn until they
/// arrive); the same robot as before keeps its meshes.
pub fn start(cx: &mut JobContext<'_>, session: &mut Session, same_robot: bool) {
    if same_robot && let Some(old) = cx.scene.get() {
        session.meshes = old.meshes.clone();
        if cx.jobs.is_running(MeshJob::lane()) {
            // Still loading for the previous session: the event updates the new one.
            return;
        }
        if !matches!(session.meshes, RobotMeshes::Failed(_)) {
            return;
        }
    }
    cx.jobs.stop(MeshJob::lane());
    if !has_visual_meshes(&session.robot) {
        session.meshes = RobotMeshes::None;
        return;
    }
    let work = MeshWork {
        robot: session.robot.clone(),
    };
    match cx.start_job("meshes", MeshJob, work) {
        Ok(()) => session.meshes = RobotMeshes::Loading,
        Err(e) => session.meshes = RobotMeshes::Failed(format!("cannot start loading: {e}")),
    }
}
