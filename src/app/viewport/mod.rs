//! The 3D viewport: camera interaction, picking, legends, and the hand-off to the wgpu pipeline.

pub mod camera;
pub mod gpu;
pub mod mesh_pack;
mod primitives;
pub mod scene;

use crate::analysis::{Analysis, ConfigRow};
use crate::app::colormap;
use crate::app::command::Command;
use crate::app::plots::LIVE_COLOR;
use crate::app::session::{self, After, Session};
use crate::side::{ConfigId, PerSide};
use camera::OrbitCamera;
use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2};
use eframe::egui_wgpu::{self, wgpu};
use gpu::{FrameUniform, ViewportCallback, ViewportGpu};
use nalgebra::Matrix4;
use scene::{SceneData, SceneOptions};
use std::sync::Arc;

/// Picking radius around a configuration's anchor, points.
const PICK_RADIUS_POINTS: f32 = 14.0;

/// Create the viewport's GPU resources once; call from `WorkbenchApp::new`.
/// Returns false when the app does not run on wgpu (the viewport then shows a note).
pub fn install_gpu(render_state: Option<&egui_wgpu::RenderState>, sample_count: u32) -> bool {
    let Some(rs) = render_state else {
        return false;
    };
    let gpu = ViewportGpu::new(&rs.device, sample_count);
    rs.renderer.write().callback_resources.insert(gpu);
    true
}

/// View state of the viewport (camera, display options, cached scene).
pub struct ViewportState {
    pub camera: OrbitCamera,
    /// Where "Reset view" and a double click put the camera: framing the robot and its data.
    pub home_camera: OrbitCamera,
    pub options: SceneOptions,
    /// Measurement index each arm is drawn in (`None`: home pose).
    pub poses: PerSide<Option<usize>>,
    scene: Arc<SceneData>,
    scene_key: Option<SceneKey>,
    version: u64,
    texture: Option<egui::TextureId>,
    /// Choose exaggeration and colour range from the errors when a model arrives.
    pub auto_scale: bool,
    /// The configuration under the pointer.
    pub hovered_config: Option<ConfigId>,
    /// The adapter renders on the CPU (lavapipe, llvmpipe, SwiftShader): `MeshDetail::Auto` draws
    /// the simplified meshes.
    pub software_renderer: bool,
    /// A measurement plan drawn instead of the dataset (the planning view, while it is open).
    pub plan: Option<scene::PlanOverlay>,
}

/// What the cached scene was built from.
#[derive(Clone, Debug, PartialEq)]
struct SceneKey {
    /// `None`: no session (the built-in robot alone is drawn).
    session_generation: Option<u64>,
    options: SceneOptions,
    poses: PerSide<Option<usize>>,
    selection: Option<ConfigId>,
    plan: Option<scene::PlanOverlay>,
}

/// Each arm drawn in its first configuration.
const FIRST_POSES: PerSide<Option<usize>> = PerSide::new(Some(0), Some(0));

impl Default for ViewportState {
    fn default() -> Self {
        Self {
            camera: OrbitCamera::default(),
            home_camera: OrbitCamera::default(),
            options: SceneOptions::default(),
            poses: FIRST_POSES,
            scene: Arc::new(SceneData::default()),
            scene_key: None,
            version: 0,
            texture: None,
            hovered_config: None,
            auto_scale: true,
            software_renderer: false,
            plan: None,
        }
    }
}

impl ViewportState {
    /// Draw each arm in its first configuration (a new dataset).
    pub fn reset_poses(&mut self) {
        self.poses = FIRST_POSES;
    }

    /// Whether the simplified meshes are drawn (the choice, resolved for this adapter).
    pub fn draws_simplified_meshes(&self) -> bool {
        self.options.mesh_detail.simplified(self.software_renderer)
    }

    /// The scene last built (what the GPU draws).
    pub fn scene(&self) -> &SceneData {
        &self.scene
    }

    /// Show a plan (or the dataset again, `None`); a new plan is framed with the tracker in view
    /// (the robot at home, the tracker, the planned reflectors).
    pub fn set_plan(
        &mut self,
        plan: Option<scene::PlanOverlay>,
        robot: &crate::robot::RobotDescription,
    ) {
        let new_plan = plan.as_ref().is_some_and(|p| {
            self.plan
                .as_ref()
                .is_none_or(|old| old.revision != p.revision)
        });
        if let (true, Some(p)) = (new_plan, &plan) {
            let q = PerSide::from_fn(|side| robot.home_q_rad(side));
            let points: Vec<nalgebra::Vector3<f32>> = robot
                .link_poses(&q.left, &q.right)
                .into_iter()
                .map(|(_, pose)| pose.translation.vector)
                .chain(std::iter::once(p.tracker_mm))
                .chain(
                    p.points_mm
                        .iter()
                        .flat_map(|(_, c)| c.iter().flatten().copied()),
                )
                .filter(|v| v.iter().all(|c| c.is_finite()))
                .map(|v| v.cast())
                .collect();
            self.camera = OrbitCamera::framing(&points);
        }
        self.plan = plan;
    }

    /// Frame a new robot and its data: the built-in robot's default view, any other robot seen from
    /// the same direction at a distance that fits its links and the measured points.
    pub fn frame(&mut self, session: &Session) {
        self.home_camera = if session.robot.is_builtin() {
            OrbitCamera::default()
        } else {
            let robot = &session.robot;
            let q = PerSide::from_fn(|side| robot.home_q_rad(side));
            let links = robot
                .link_poses(&q.left, &q.right)
                .into_iter()
                .map(|(_, pose)| pose.translation.vector);
            let measured = session
                .nominal
                .configs
                .iter()
                .flat_map(|r| r.measured_body_mm.iter().copied());
            let points: Vec<nalgebra::Vector3<f32>> = links
                .chain(measured)
                .filter(|p| p.iter().all(|c| c.is_finite()))
                .map(|p| p.cast())
                .collect();
            OrbitCamera::framing(&points)
        };
        self.camera = self.home_camera;
    }

    /// With auto scale on: draw the 95th-percentile point error as about 60 mm and put about 1.5
    /// times it at the top of the colour bar.
    pub fn auto_scale(&mut self, session: &Session) {
        if !self.auto_scale {
            return;
        }
        let mut errors: Vec<f64> = self
            .options
            .analysis(session)
            .configs
            .iter()
            .flat_map(|r| r.point_errors_mm())
            .filter(|e| e.is_finite())
            .collect();
        if errors.is_empty() {
            return;
        }
        crate::sort::sort_f64(&mut errors);
        let p95 = errors[(errors.len() * 95 / 100).min(errors.len() - 1)];
        if p95 > 0.0 {
            self.options.exaggeration = nice_round(60.0 / p95).clamp(1.0, 5000.0) as f32;
            self.options.color_max_mm = nice_round(1.5 * p95).clamp(0.005, 50.0) as f32;
        }
    }

    /// Draw the viewport into the remaining space of `ui`. `generation` identifies the session's
    /// content (bump it when the session or its models change). A click selects the configuration
    /// under the pointer, or none.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        frame: &eframe::Frame,
        session: Option<&Session>,
        generation: u64,
        selection: Option<ConfigId>,
    ) -> Option<Command> {
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        if rect.width() < 2.0 || rect.height() < 2.0 {
            return None;
        }
        self.camera.handle_input(&response);
        if response.double_clicked() {
            self.camera = self.home_camera;
        }
        self.update_scene(session, generation, selection);
        let view_proj = self.camera.view_proj(rect.width() / rect.height());
        let clicked = self.pick_ui(&response, session, &view_proj);
        let painter = ui.painter_at(rect);
        if !self.paint_scene(&painter, rect, frame, &view_proj) {
            return clicked;
        }
        if self.plan.is_some() {
            // A plan, not the dataset: its own label, no error legend, no dataset selection.
            corner_label(
                &painter,
                rect,
                "measurement plan: tracker yellow, lines of sight; planned reflectors of the left \
                 arm blue, of the right arm orange",
            );
            return None;
        }
        self.legends_ui(&painter, rect, session);
        if let Some(session) = session {
            self.model_label_ui(&painter, rect, session);
            meshes_label_ui(&painter, rect, session);
        }
        if let (Some(session), Some(config)) = (session, selection) {
            self.selection_label_ui(&painter, rect, &view_proj, session, config);
        }
        if let (Some(session), Some(config)) = (session, self.hovered_config)
            && let Some(m) = session
                .dataset
                .arm(config.side)
                .measurements
                .get(config.index)
        {
            response.on_hover_text_at_pointer(format!(
                "{} ({} arm) — click to select",
                m.id, config.side
            ));
        }
        clicked
    }

    /// Rebuild the scene when something it depends on changed. Without a dataset the built-in
    /// robot is drawn in its home pose, so the window never opens on an empty view.
    fn update_scene(
        &mut self,
        session: Option<&Session>,
        generation: u64,
        selection: Option<ConfigId>,
    ) {
        let key = SceneKey {
            session_generation: session.map(|_| generation),
            options: self.options.clone(),
            poses: self.poses,
            selection,
            plan: self.plan.clone(),
        };
        if self.scene_key.as_ref() == Some(&key) {
            return;
        }
        self.version += 1;
        self.scene = Arc::new(match (session, &self.plan) {
            (_, Some(plan)) => {
                let robot: &crate::robot::RobotDescription = match session {
                    Some(s) => &s.robot,
                    None => scene::builtin_robot(),
                };
                let meshes = session.and_then(|s| {
                    s.meshes
                        .packed_for(self.options.mesh_detail.simplified(self.software_renderer))
                });
                scene::build_plan_scene(robot, meshes, plan, &self.options, self.version)
            }
            (Some(session), None) => scene::build_scene(
                session,
                &self.options,
                self.poses,
                selection,
                self.software_renderer,
                self.version,
            ),
            (None, None) => {
                scene::build_robot_scene(scene::builtin_robot(), &self.options, self.version)
            }
        });
        self.scene_key = Some(key);
    }

    /// Picking on the CPU: the hovered configuration, and the selection a click makes.
    fn pick_ui(
        &mut self,
        response: &egui::Response,
        session: Option<&Session>,
        view_proj: &Matrix4<f32>,
    ) -> Option<Command> {
        let Some(session) = session else {
            self.hovered_config = None;
            return None;
        };
        let analysis = self.options.analysis(session);
        let pick = |pos: Pos2| self.nearest_config(analysis, view_proj, response.rect, pos);
        let hovered = response.hover_pos().and_then(pick);
        let clicked = response
            .clicked()
            .then(|| response.interact_pointer_pos())
            .flatten()
            .map(|pos| Command::Select {
                config: pick(pos),
                reveal_in_table: true,
            });
        self.hovered_config = hovered;
        clicked
    }

    /// The shown configuration drawn nearest to `pos`, if within the pick radius.
    fn nearest_config(
        &self,
        analysis: &Analysis,
        view_proj: &Matrix4<f32>,
        rect: Rect,
        pos: Pos2,
    ) -> Option<ConfigId> {
        let mut best: Option<(f32, ConfigId)> = None;
        for row in analysis.configs.iter().filter(|r| self.options.shows(r)) {
            if let Some(at) = self.screen_pos(view_proj, rect, row) {
                let d = (at - pos).length();
                if d < PICK_RADIUS_POINTS && best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, row.config));
                }
            }
        }
        best.map(|(_, config)| config)
    }

    /// Where a configuration's anchor is drawn in `rect` (`None`: behind the camera).
    fn screen_pos(&self, view_proj: &Matrix4<f32>, rect: Rect, row: &ConfigRow) -> Option<Pos2> {
        let anchor = scene::pick_anchor(row);
        let [x, y] = self
            .camera
            .project_with(view_proj, &anchor, rect.width(), rect.height())?;
        Some(Pos2::new(rect.left() + x, rect.top() + y))
    }

    /// The scene, rendered offscreen at the rect's size in physical pixels and drawn by egui as an
    /// image. Without wgpu, a note instead (returns false).
    fn paint_scene(
        &mut self,
        painter: &egui::Painter,
        rect: Rect,
        frame: &eframe::Frame,
        view_proj: &Matrix4<f32>,
    ) -> bool {
        let Some(rs) = frame.wgpu_render_state() else {
            painter.rect_filled(rect, 0.0, Color32::from_gray(20));
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "The 3D viewport needs the wgpu renderer.",
                egui::FontId::proportional(14.0),
                Color32::LIGHT_GRAY,
            );
            return false;
        };
        let ppp = painter.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        ];
        self.register_target(rs, size_px);
        let eye = self.camera.eye_mm();
        let to_eye = (eye - self.camera.target_mm).normalize();
        // Head light, a little above and to the side of the view direction.
        let light = (to_eye + nalgebra::Vector3::new(0.0, 0.0, 0.6)).normalize();
        let uniform = FrameUniform {
            view_proj: view_proj.as_slice().try_into().unwrap_or([0.0; 16]),
            light_dir: [light.x, light.y, light.z, 0.28],
            eye: [eye.x, eye.y, eye.z, 1.0],
        };
        painter.add(egui_wgpu::Callback::new_paint_callback(
            rect,
            ViewportCallback {
                scene: self.scene.clone(),
                uniform,
            },
        ));
        if let Some(id) = self.texture {
            painter.image(
                id,
                rect,
                Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        true
    }

    /// Size the offscreen target and (re)register it as the egui texture drawn.
    fn register_target(&mut self, rs: &egui_wgpu::RenderState, size_px: [u32; 2]) {
        let mut renderer = rs.renderer.write();
        let new_view = renderer
            .callback_resources
            .get_mut::<ViewportGpu>()
            .and_then(|gpu| gpu.ensure_targets(&rs.device, size_px));
        let Some(view) = new_view else {
            return;
        };
        match self.texture {
            Some(id) => renderer.update_egui_texture_from_wgpu_texture(
                &rs.device,
                &view,
                wgpu::FilterMode::Linear,
                id,
            ),
            None => {
                self.texture = Some(renderer.register_native_texture(
                    &rs.device,
                    &view,
                    wgpu::FilterMode::Linear,
                ));
            }
        }
    }

    /// Which model is drawn, in the top-left corner; during a run, which iterate.
    fn model_label_ui(&self, painter: &egui::Painter, rect: Rect, session: &Session) {
        let (text, color) = match (self.options.use_calibrated, session.after()) {
            (true, Some(After::Live(live))) => (format!("live: {}", live.label()), LIVE_COLOR),
            (true, Some(After::Calibrated(_))) => {
                ("calibrated model".to_string(), Color32::from_gray(220))
            }
            _ => ("nominal model".to_string(), Color32::from_gray(220)),
        };
        let galley = painter.layout_no_wrap(text, egui::FontId::proportional(13.0), color);
        backed_galley(painter, rect, galley, color);
    }

    /// Label the selected configuration where it is drawn.
    fn selection_label_ui(
        &self,
        painter: &egui::Painter,
        rect: Rect,
        view_proj: &Matrix4<f32>,
        session: &Session,
        config: ConfigId,
    ) {
        let Some(row) = session::config_row(self.options.analysis(session), config) else {
            return;
        };
        let Some(at) = self.screen_pos(view_proj, rect, row) else {
            return;
        };
        painter.circle_stroke(at, 10.0, Stroke::new(2.0, Color32::WHITE));
        let text = format!("{} ({})", row.id, config.side);
        let galley = painter.layout_no_wrap(text, egui::FontId::proportional(13.0), Color32::WHITE);
        let pos = at + Vec2::new(13.0, -8.0);
        painter.rect_filled(
            Rect::from_min_size(pos, galley.size()).expand(3.0),
            3.0,
            Color32::from_black_alpha(170),
        );
        painter.galley(pos, galley, Color32::WHITE);
    }

    /// Colour bar and exaggeration legend in the bottom-left corner.
    fn legends_ui(&self, painter: &egui::Painter, rect: Rect, session: Option<&Session>) {
        let text_color = Color32::from_gray(220);
        let text = |pos: Pos2, anchor: egui::Align2, text: String| {
            painter.text(
                pos,
                anchor,
                text,
                egui::FontId::proportional(12.0),
                text_color,
            );
        };
        let bar_w = 180.0;
        let bar_h = 12.0;
        let origin = Pos2::new(rect.left() + 14.0, rect.bottom() - 48.0);
        let bar = Rect::from_min_size(origin, Vec2::new(bar_w, bar_h));
        let bg = Rect::from_min_max(
            Pos2::new(bar.left() - 8.0, bar.top() - 22.0),
            Pos2::new(bar.right() + 70.0, bar.bottom() + 34.0),
        );
        painter.rect_filled(bg, 4.0, Color32::from_black_alpha(150));
        painter.add(egui::Shape::mesh(color_bar_mesh(bar)));
        let below = bar.bottom() + 3.0;
        text(
            Pos2::new(bar.left(), bar.top() - 4.0),
            egui::Align2::LEFT_BOTTOM,
            "point error after registration".into(),
        );
        text(
            Pos2::new(bar.left(), below),
            egui::Align2::LEFT_TOP,
            "0 mm".into(),
        );
        text(
            Pos2::new(bar.right(), below),
            egui::Align2::RIGHT_TOP,
            format!("≥ {:.2} mm", self.options.color_max_mm),
        );
        text(
            Pos2::new(bar.left(), bar.bottom() + 18.0),
            egui::Align2::LEFT_TOP,
            format!(
                "error vectors ×{:.0} (1 mm drawn as {:.0} mm)",
                self.options.exaggeration, self.options.exaggeration
            ),
        );
        if let Some(session) = session
            && self.options.show_flags
        {
            let flagged = self.options.screening(session).suspects().len();
            if flagged > 0 {
                let at = Pos2::new(bar.left(), bg.top() - 6.0);
                let galley = painter.layout_no_wrap(
                    format!(
                        "{flagged} flagged: magenta to red by severity; excluded: grey (X toggles)"
                    ),
                    egui::FontId::proportional(12.0),
                    crate::app::colormap::flag_color32(2.0),
                );
                let r = Rect::from_min_size(at - Vec2::new(0.0, galley.size().y), galley.size());
                painter.rect_filled(r.expand(4.0), 4.0, Color32::from_black_alpha(150));
                painter.galley(r.min, galley, Color32::WHITE);
            }
        }
        if session.is_none() {
            painter.text(
                Pos2::new(rect.center().x, rect.top() + rect.height() * 0.8),
                egui::Align2::CENTER_CENTER,
                "No dataset loaded — open one or drop a dataset.toml here",
                egui::FontId::proportional(16.0),
                text_color,
            );
        }
        painter.rect_stroke(
            rect,
            0.0,
            Stroke::new(1.0, Color32::from_gray(40)),
            egui::StrokeKind::Inside,
        );
    }
}

/// While the robot's meshes load (or if they could not be), a note in the top-right corner.
fn meshes_label_ui(painter: &egui::Painter, rect: Rect, session: &Session) {
    let text = match &session.meshes {
        session::RobotMeshes::Loading => "loading meshes…",
        session::RobotMeshes::Failed(_) => "meshes not loaded (see Robot)",
        _ => return,
    };
    let color = Color32::from_gray(200);
    let galley = painter.layout_no_wrap(text.into(), egui::FontId::proportional(13.0), color);
    let pos = rect.right_top() + Vec2::new(-12.0 - galley.size().x, 10.0);
    painter.rect_filled(
        Rect::from_min_size(pos, galley.size()).expand(4.0),
        3.0,
        Color32::from_black_alpha(150),
    );
    painter.galley(pos, galley, color);
}

/// The colour map as a horizontal bar filling `bar`.
fn color_bar_mesh(bar: Rect) -> egui::Mesh {
    let mut mesh = egui::Mesh::default();
    let n = 32;
    for k in 0..=n {
        let t = k as f32 / n as f32;
        let x = bar.left() + t * bar.width();
        let c = colormap::color32(t);
        mesh.colored_vertex(Pos2::new(x, bar.top()), c);
        mesh.colored_vertex(Pos2::new(x, bar.bottom()), c);
        if k > 0 {
            let i = 2 * k as u32;
            mesh.add_triangle(i - 2, i - 1, i);
            mesh.add_triangle(i - 1, i + 1, i);
        }
    }
    mesh
}

/// Round to 1, 2 or 5 times a power of ten.
fn nice_round(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    let m = x / p;
    let m = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    m * p
}

/// A label in the viewport's top-left corner, on a dark backing.
fn corner_label(painter: &egui::Painter, rect: Rect, text: &str) {
    let color = Color32::from_gray(220);
    let galley = painter.layout(
        text.to_string(),
        egui::FontId::proportional(13.0),
        color,
        (rect.width() - 32.0).max(40.0),
    );
    backed_galley(painter, rect, galley, color);
}

/// Text laid out in the viewport's top-left corner, on a dark backing.
fn backed_galley(
    painter: &egui::Painter,
    rect: Rect,
    galley: std::sync::Arc<egui::Galley>,
    color: Color32,
) {
    let pos = rect.left_top() + Vec2::new(12.0, 10.0);
    painter.rect_filled(
        Rect::from_min_size(pos, galley.size()).expand(4.0),
        3.0,
        Color32::from_black_alpha(150),
    );
    painter.galley(pos, galley, color);
}

#[cfg(test)]
mod tests {
    use super::nice_round;

    #[test]
    fn nice_round_picks_1_2_5() {
        assert!((nice_round(0.031) - 0.02).abs() < 1e-12);
        assert_eq!(nice_round(42.0), 50.0);
        assert_eq!(nice_round(1.2), 1.0);
        assert_eq!(nice_round(f64::NAN), 1.0);
    }
}
