//! Orbit camera around a target point, in the robot's body frame (mm, z up).

use eframe::egui;
use nalgebra::{Matrix4, Point3, Vector3, Vector4};

/// An orbit camera: yaw and pitch about the target, distance from it, perspective projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target_mm: Vector3<f32>,
    pub yaw_rad: f32,
    pub pitch_rad: f32,
    pub distance_mm: f32,
    pub fov_y_rad: f32,
}

impl Default for OrbitCamera {
    /// Looking at the robot's chest from the front-right, slightly above.
    fn default() -> Self {
        Self {
            target_mm: Vector3::new(150.0, 0.0, 350.0),
            yaw_rad: 0.55,
            pitch_rad: 0.32,
            distance_mm: 1900.0,
            fov_y_rad: 40f32.to_radians(),
        }
    }
}

const MIN_DISTANCE_MM: f32 = 50.0;
const MAX_DISTANCE_MM: f32 = 50_000.0;
const PITCH_LIMIT_RAD: f32 = 1.55;

impl OrbitCamera {
    /// Camera position.
    pub fn eye_mm(&self) -> Vector3<f32> {
        let (sy, cy) = self.yaw_rad.sin_cos();
        let (sp, cp) = self.pitch_rad.sin_cos();
        self.target_mm + self.distance_mm * Vector3::new(cp * cy, cp * sy, sp)
    }

    pub fn view(&self) -> Matrix4<f32> {
        Matrix4::look_at_rh(
            &Point3::from(self.eye_mm()),
            &Point3::from(self.target_mm),
            &Vector3::z(),
        )
    }

    /// Perspective projection with wgpu's depth range 0..1 (reversed-free, near/far from the distance).
    pub fn projection(&self, aspect: f32) -> Matrix4<f32> {
        let near = (self.distance_mm * 0.01).max(1.0);
        let far = self.distance_mm * 20.0 + 5000.0;
        let f = 1.0 / (self.fov_y_rad * 0.5).tan();
        let aspect = aspect.max(1e-3);
        Matrix4::new(
            f / aspect,
            0.0,
            0.0,
            0.0,
            0.0,
            f,
            0.0,
            0.0,
            0.0,
            0.0,
            far / (near - far),
            near * far / (near - far),
            0.0,
            0.0,
            -1.0,
            0.0,
        )
    }

    pub fn view_proj(&self, aspect: f32) -> Matrix4<f32> {
        self.projection(aspect) * self.view()
    }

    /// Seen from the default direction, a camera whose view holds every point of `points_mm` (the
    /// sphere around their bounding box).
    pub fn framing(points_mm: &[Vector3<f32>]) -> Self {
        let default = Self::default();
        let Some(first) = points_mm.first() else {
            return default;
        };
        let (lo, hi) = points_mm
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let radius_mm = ((hi - lo).norm() * 0.5).max(100.0);
        Self {
            target_mm: (lo + hi) * 0.5,
            distance_mm: (radius_mm / (default.fov_y_rad * 0.5).sin())
                .clamp(MIN_DISTANCE_MM, MAX_DISTANCE_MM),
            ..default
        }
    }

    /// Mouse input on the viewport: drag orbits, right/middle or shift-drag pans, the wheel zooms (a
    /// double click, handled by the viewport, resets the view).
    pub fn handle_input(&mut self, response: &egui::Response) {
        let (shift, scroll) = response
            .ctx
            .input(|i| (i.modifiers.shift, i.smooth_scroll_delta.y));
        let d = response.drag_delta();
        let primary = response.dragged_by(egui::PointerButton::Primary);
        if primary && !shift {
            self.orbit(d.x, d.y);
        } else if primary
            || response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            self.pan(d.x, d.y, response.rect.height());
        }
        if response.hovered() && scroll != 0.0 {
            self.zoom((-scroll * 0.002).exp());
        }
    }

    /// Orbit by a drag of `dx`, `dy` points.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw_rad -= dx * 0.008;
        self.pitch_rad = (self.pitch_rad + dy * 0.008).clamp(-PITCH_LIMIT_RAD, PITCH_LIMIT_RAD);
    }

    /// Move the target in the view plane by a drag of `dx`, `dy` points in a view `height` points tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let mm_per_point = 2.0 * self.distance_mm * (self.fov_y_rad * 0.5).tan() / height.max(1.0);
        let forward = (self.target_mm - self.eye_mm()).normalize();
        let right = forward.cross(&Vector3::z());
        let right = if right.norm() < 1e-6 {
            Vector3::x()
        } else {
            right.normalize()
        };
        let up = right.cross(&forward);
        self.target_mm += (-dx * right + dy * up) * mm_per_point;
    }

    /// Zoom by a factor (> 1 moves away).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance_mm = (self.distance_mm * factor).clamp(MIN_DISTANCE_MM, MAX_DISTANCE_MM);
        }
    }

    /// Project a body-frame point to viewport coordinates in points (origin top-left), or `None`
    /// when it is behind the camera.
    pub fn project(&self, p_mm: &Vector3<f32>, width: f32, height: f32) -> Option<[f32; 2]> {
        self.project_with(
            &self.view_proj(width / height.max(1.0)),
            p_mm,
            width,
            height,
        )
    }

    /// Like [`project`](Self::project) with a precomputed view-projection matrix.
    pub fn project_with(
        &self,
        view_proj: &Matrix4<f32>,
        p_mm: &Vector3<f32>,
        width: f32,
        height: f32,
    ) -> Option<[f32; 2]> {
        let clip = view_proj * Vector4::new(p_mm.x, p_mm.y, p_mm.z, 1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc_x = clip.x / clip.w;
        let ndc_y = clip.y / clip.w;
        Some([(ndc_x * 0.5 + 0.5) * width, (0.5 - ndc_y * 0.5) * height])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_projects_to_the_centre() {
        let cam = OrbitCamera::default();
        let [x, y] = cam.project(&cam.target_mm, 800.0, 600.0).unwrap();
        assert!(
            (x - 400.0).abs() < 1e-2 && (y - 300.0).abs() < 1e-2,
            "{x} {y}"
        );
    }

    #[test]
    fn a_point_above_the_target_is_drawn_higher() {
        let cam = OrbitCamera::default();
        let up = cam.target_mm + Vector3::new(0.0, 0.0, 100.0);
        let [_, y] = cam.project(&up, 800.0, 600.0).unwrap();
        assert!(y < 300.0, "{y}");
    }

    #[test]
    fn depth_stays_in_the_unit_range_between_near_and_far() {
        let cam = OrbitCamera::default();
        let vp = cam.view_proj(1.5);
        let clip = vp * Vector4::new(cam.target_mm.x, cam.target_mm.y, cam.target_mm.z, 1.0);
        let depth = clip.z / clip.w;
        assert!(depth > 0.0 && depth < 1.0, "{depth}");
    }

    #[test]
    fn framing_sees_every_point() {
        let points = [
            Vector3::new(-400.0, 2000.0, -900.0),
            Vector3::new(300.0, 2600.0, 700.0),
            Vector3::new(0.0, 2300.0, 0.0),
        ];
        let cam = OrbitCamera::framing(&points);
        for p in &points {
            let [x, y] = cam.project(p, 800.0, 600.0).unwrap();
            assert!(
                (0.0..=800.0).contains(&x) && (0.0..=600.0).contains(&y),
                "{p:?} at {x} {y}"
            );
        }
        assert_eq!(OrbitCamera::framing(&[]), OrbitCamera::default());
    }

    #[test]
    fn pan_moves_the_target_and_zoom_is_clamped() {
        let mut cam = OrbitCamera::default();
        let before = cam.target_mm;
        cam.pan(10.0, 0.0, 600.0);
        assert!((cam.target_mm - before).norm() > 1.0);
        cam.zoom(1e-9);
        assert_eq!(cam.distance_mm, MIN_DISTANCE_MM);
    }
}
