//! What the viewport draws, built on the CPU: mesh instances for the robot (its URDF's meshes and
//! primitives), coloured line and triangle vertices for the grid, axes, reflector triangles and error
//! vectors. Rebuilt only when the data or the display options change.
//!
//! **Meshes** arrive after the robot (a background task loads and packs them, [`PackedMeshes`]); until
//! then each mesh is a placeholder box. A visual mesh that could not be loaded is drawn as its link's
//! collision geometry in a tinted colour (a *stand-in*), or as a box when that is missing too.

use super::mesh_pack::PackedMeshes;
use crate::analysis::{Analysis, ConfigRow};
use crate::app::colormap;
use crate::app::session::Session;
use crate::dataset::Split;
use crate::quality::Screening;
use crate::robot::{GeometryKind, PlacedShape, RobotDescription, ShapeKind};
use crate::side::{ConfigId, PerSide, Side};
use nalgebra::{Isometry3, Matrix3, Matrix4, Vector3};
use std::sync::Arc;

/// A unit primitive the mesh pipeline instances.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Primitive {
    /// Cube [-1, 1]³.
    Box,
    /// Radius 1, z from -1 to 1.
    Cylinder,
    /// Radius 1.
    Sphere,
}

/// What an instance draws: a unit primitive, or a mesh of the scene's [`PackedMeshes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Geometry {
    Primitive(Primitive),
    /// Index of the mesh in [`SceneData::meshes`] (vertices in metres).
    Mesh(u32),
}

impl From<Primitive> for Geometry {
    fn from(p: Primitive) -> Self {
        Geometry::Primitive(p)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshInstance {
    pub geometry: Geometry,
    /// Geometry → body frame (mm), columns.
    pub model: [[f32; 4]; 4],
    /// Normal matrix columns (xyz, w unused).
    pub normal: [[f32; 4]; 3],
    /// Linear RGBA.
    pub color: [f32; 4],
}

impl MeshInstance {
    /// A primitive or mesh scaled per axis, then placed by `body_from_shape`.
    pub fn new(
        geometry: impl Into<Geometry>,
        body_from_shape: &Isometry3<f64>,
        scale: Vector3<f64>,
        color: [f32; 4],
    ) -> Self {
        let iso: Matrix4<f32> = body_from_shape.to_homogeneous().cast();
        let s: Vector3<f32> = scale.cast();
        let model = iso * Matrix4::new_nonuniform_scaling(&s);
        let rot: Matrix3<f32> = body_from_shape
            .rotation
            .to_rotation_matrix()
            .matrix()
            .cast();
        let inv = Vector3::new(
            1.0 / s.x.max(1e-6),
            1.0 / s.y.max(1e-6),
            1.0 / s.z.max(1e-6),
        );
        let normal = rot * Matrix3::from_diagonal(&inv);
        Self {
            geometry: geometry.into(),
            model: std::array::from_fn(|c| std::array::from_fn(|r| model[(r, c)])),
            normal: std::array::from_fn(|c| [normal[(0, c)], normal[(1, c)], normal[(2, c)], 0.0]),
            color,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ColorVertex {
    pub position: [f32; 3],
    /// Linear RGBA.
    pub color: [f32; 4],
}

/// Everything uploaded to the GPU; `version` changes whenever the content does.
#[derive(Clone, Debug, Default)]
pub struct SceneData {
    pub version: u64,
    pub instances: Vec<MeshInstance>,
    /// The robot's meshes the instances refer to (uploaded once per pack).
    pub meshes: Option<Arc<PackedMeshes>>,
    pub lines: Vec<ColorVertex>,
    pub triangles: Vec<ColorVertex>,
}

/// Display options that change the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneOptions {
    pub show_robot: bool,
    pub show_grid: bool,
    pub show_measured: bool,
    pub show_model: bool,
    pub show_vectors: bool,
    /// Draw configurations of these splits.
    pub show_cal: bool,
    pub show_ver: bool,
    /// Draw configurations of these arms.
    pub show_arm: PerSide<bool>,
    /// Error vectors are drawn this many times their length.
    pub exaggeration: f32,
    /// Error (mm) at the top of the colour scale.
    pub color_max_mm: f32,
    /// Draw the calibrated model (if any) rather than the nominal one.
    pub use_calibrated: bool,
    /// Colour the configurations the screening flags by severity (else by their error).
    pub show_flags: bool,
    /// Which copy of the robot's meshes is drawn.
    pub mesh_detail: MeshDetail,
}

/// Which copy of the robot's meshes the viewport draws: the full meshes, or the simplified copy
/// ([`crate::meshes::lod`]; collision checks and exports always use the full ones). `Auto`: the
/// simplified copy on a software renderer (lavapipe, llvmpipe, SwiftShader), the full meshes on a
/// GPU. The launch options set the choice the workbench starts with (`DUALCAL_MESH_DETAIL`,
/// [`crate::app::LaunchOptions`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshDetail {
    #[default]
    Auto,
    Full,
    Simplified,
}

impl MeshDetail {
    pub const ALL: [MeshDetail; 3] = [MeshDetail::Auto, MeshDetail::Full, MeshDetail::Simplified];

    pub fn label(self) -> &'static str {
        match self {
            MeshDetail::Auto => "auto",
            MeshDetail::Full => "full",
            MeshDetail::Simplified => "simplified",
        }
    }

    /// `auto`, `full` or `simplified` (any case).
    pub fn parse(text: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|d| d.label().eq_ignore_ascii_case(text.trim()))
    }

    /// Whether to draw the simplified copy, on a software renderer or not.
    pub fn simplified(self, software_renderer: bool) -> bool {
        match self {
            MeshDetail::Auto => software_renderer,
            MeshDetail::Full => false,
            MeshDetail::Simplified => true,
        }
    }
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self {
            show_robot: true,
            show_grid: true,
            show_measured: true,
            show_model: true,
            show_vectors: true,
            show_cal: true,
            show_ver: true,
            show_arm: PerSide::new(true, true),
            exaggeration: 50.0,
            color_max_mm: 2.0,
            use_calibrated: true,
            show_flags: true,
            mesh_detail: MeshDetail::default(),
        }
    }
}

impl SceneOptions {
    pub fn shows(&self, row: &ConfigRow) -> bool {
        let split_shown = match row.split {
            Split::Cal => self.show_cal,
            Split::Ver => self.show_ver,
            Split::All => self.show_cal || self.show_ver,
        };
        split_shown && self.show_arm[row.config.side]
    }

    /// The figures of the model drawn: the calibrated one if chosen and there is one.
    pub fn analysis<'a>(&self, session: &'a Session) -> &'a Analysis {
        session.newest_or_nominal(self.use_calibrated)
    }

    /// The screening that goes with the model drawn: the last calibration's, or the nominal one.
    pub fn screening<'a>(&self, session: &'a Session) -> &'a Screening {
        match (&session.calibrated, self.use_calibrated) {
            (Some(c), true) => &c.screening,
            _ => &session.screening,
        }
    }
}

fn srgb_linear(rgb: [u8; 3], alpha: f32) -> [f32; 4] {
    let [r, g, b] = rgb.map(|c| colormap::srgb_to_linear(c as f32 / 255.0));
    [r, g, b, alpha]
}

/// Half size of the box drawn for a mesh that is loading or missing, mm.
const PLACEHOLDER_HALF_MM: f64 = 20.0;
/// Colour of a placeholder box while the meshes load.
const LOADING_RGBA: [f32; 4] = [0.35, 0.36, 0.38, 1.0];
/// Colour of a placeholder box for a mesh that could not be loaded.
const MISSING_RGBA: [f32; 4] = [0.85, 0.5, 0.16, 1.0];

/// A stand-in (a missing visual mesh drawn as its link's collision geometry): the visual's colour
/// turned towards amber, so it reads as "not the real mesh".
pub fn stand_in_rgba(rgba: [f32; 4]) -> [f32; 4] {
    let amber = [0.85, 0.5, 0.16];
    std::array::from_fn(|i| {
        if i < 3 {
            0.55 * rgba[i] + 0.45 * amber[i]
        } else {
            1.0
        }
    })
}

/// The robot's meshes as the scene sees them.
#[derive(Clone, Copy, Debug)]
pub enum MeshSource<'a> {
    /// Not loaded (yet, or at all): every mesh is a placeholder box.
    Placeholders,
    /// Loaded: each mesh from the pack; one that is not in it is a stand-in.
    Packed(&'a PackedMeshes),
}

/// One shape as instances: a primitive, or a mesh of `meshes` (of geometry `kind`). Returns false for
/// a mesh that is not in `meshes` (nothing added).
fn push_shape(
    shape: &PlacedShape,
    kind: GeometryKind,
    meshes: Option<&PackedMeshes>,
    color: [f32; 4],
    out: &mut Vec<MeshInstance>,
) -> bool {
    let pose = &shape.body_from_shape;
    match &shape.kind {
        ShapeKind::Box { half_extents_mm } => {
            out.push(MeshInstance::new(
                Primitive::Box,
                pose,
                *half_extents_mm,
                color,
            ));
        }
        ShapeKind::Cylinder {
            radius_mm,
            half_length_mm,
        } => out.push(MeshInstance::new(
            Primitive::Cylinder,
            pose,
            Vector3::new(*radius_mm, *radius_mm, *half_length_mm),
            color,
        )),
        ShapeKind::Capsule {
            radius_mm,
            half_length_mm,
        } => {
            out.push(MeshInstance::new(
                Primitive::Cylinder,
                pose,
                Vector3::new(*radius_mm, *radius_mm, *half_length_mm),
                color,
            ));
            for z in [-half_length_mm, *half_length_mm] {
                let end = pose * Isometry3::translation(0.0, 0.0, z);
                out.push(MeshInstance::new(
                    Primitive::Sphere,
                    &end,
                    Vector3::repeat(*radius_mm),
                    color,
                ));
            }
        }
        ShapeKind::Sphere { radius_mm } => out.push(MeshInstance::new(
            Primitive::Sphere,
            pose,
            Vector3::repeat(*radius_mm),
            color,
        )),
        ShapeKind::Mesh {
            filename, scale, ..
        } => {
            let Some(index) = meshes.and_then(|m| m.index_of(kind, filename, (*scale).into()))
            else {
                return false;
            };
            // The mesh is in metres (its element's scale applied): scale it to mm.
            out.push(MeshInstance::new(
                Geometry::Mesh(index),
                pose,
                Vector3::repeat(1000.0),
                color,
            ));
        }
    }
    true
}

fn placeholder(shape: &PlacedShape, color: [f32; 4]) -> MeshInstance {
    MeshInstance::new(
        Primitive::Box,
        &shape.body_from_shape,
        Vector3::repeat(PLACEHOLDER_HALF_MM),
        color,
    )
}

/// The robot's visual shapes as instances. A mesh not in `meshes` is a placeholder box while they
/// load; once loaded, a missing one is drawn as its link's `collision` shapes (a stand-in, tinted), or
/// as a box. `collision` is only called when a stand-in is needed.
pub fn robot_instances(
    visual: &[PlacedShape],
    meshes: MeshSource<'_>,
    collision: impl FnOnce() -> Vec<PlacedShape>,
    out: &mut Vec<MeshInstance>,
) {
    let packed = match meshes {
        MeshSource::Placeholders => None,
        MeshSource::Packed(p) => Some(p),
    };
    let mut missing: Vec<&PlacedShape> = Vec::new();
    for shape in visual {
        if !push_shape(shape, GeometryKind::Visual, packed, shape.rgba, out) {
            match packed {
                None => out.push(placeholder(shape, LOADING_RGBA)),
                Some(_) => missing.push(shape),
            }
        }
    }
    if missing.is_empty() {
        return;
    }
    let collision = collision();
    let mut done: Vec<&str> = Vec::new();
    for shape in missing {
        if done.contains(&shape.link.as_str()) {
            continue;
        }
        done.push(&shape.link);
        let color = stand_in_rgba(shape.rgba);
        let mut drawn = false;
        for c in collision.iter().filter(|c| c.link == shape.link) {
            drawn |= push_shape(c, GeometryKind::Collision, packed, color, out);
        }
        if !drawn {
            out.push(placeholder(shape, MISSING_RGBA));
        }
    }
}

fn line(out: &mut Vec<ColorVertex>, a: Vector3<f64>, b: Vector3<f64>, color: [f32; 4]) {
    let a: Vector3<f32> = a.cast();
    let b: Vector3<f32> = b.cast();
    out.push(ColorVertex {
        position: a.into(),
        color,
    });
    out.push(ColorVertex {
        position: b.into(),
        color,
    });
}

fn grid(out: &mut Vec<ColorVertex>) {
    let half = 1000.0;
    let step = 100.0;
    let n = (2.0 * half / step) as i32;
    for k in 0..=n {
        let t = -half + k as f64 * step;
        let major = k % 5 == 0;
        let c = if major {
            [0.09, 0.10, 0.12, 1.0]
        } else {
            [0.035, 0.04, 0.05, 1.0]
        };
        line(
            out,
            Vector3::new(t, -half, 0.0),
            Vector3::new(t, half, 0.0),
            c,
        );
        line(
            out,
            Vector3::new(-half, t, 0.0),
            Vector3::new(half, t, 0.0),
            c,
        );
    }
    let len = 250.0;
    line(
        out,
        Vector3::zeros(),
        Vector3::new(len, 0.0, 0.0),
        [0.8, 0.08, 0.06, 1.0],
    );
    line(
        out,
        Vector3::zeros(),
        Vector3::new(0.0, len, 0.0),
        [0.08, 0.6, 0.08, 1.0],
    );
    line(
        out,
        Vector3::zeros(),
        Vector3::new(0.0, 0.0, len),
        [0.1, 0.2, 0.9, 1.0],
    );
}

/// Length of the axes drawn at each link's frame of a robot without geometry, mm.
const FRAME_AXIS_MM: f64 = 40.0;
/// Colour of the links of a robot without geometry.
const SKELETON_RGBA: [f32; 4] = [0.75, 0.77, 0.80, 1.0];

/// A robot without geometry: a line from each joint's parent link's origin to its child's (the
/// links), and at every link's frame its axes (x red, y green, z blue; one frame per origin).
fn skeleton(joints: &[(Isometry3<f64>, Isometry3<f64>)], out: &mut Vec<ColorVertex>) {
    let mut drawn: Vec<Vector3<f64>> = Vec::new();
    for (parent, child) in joints {
        let (from, to) = (parent.translation.vector, child.translation.vector);
        if (to - from).norm() > 1e-6 {
            line(out, from, to, SKELETON_RGBA);
        }
        for frame in [parent, child] {
            let origin = frame.translation.vector;
            if !drawn.iter().any(|p| (p - origin).norm() < 1e-6) {
                drawn.push(origin);
                frame_axes(frame, out);
            }
        }
    }
}

/// A frame's axes, x red, y green, z blue.
fn frame_axes(frame: &Isometry3<f64>, out: &mut Vec<ColorVertex>) {
    let axes = [
        (Vector3::x(), [0.9, 0.15, 0.1, 1.0]),
        (Vector3::y(), [0.2, 0.8, 0.2, 1.0]),
        (Vector3::z(), [0.25, 0.4, 1.0, 1.0]),
    ];
    let origin = frame.translation.vector;
    for (axis, color) in axes {
        line(
            out,
            origin,
            origin + frame.rotation * axis * FRAME_AXIS_MM,
            color,
        );
    }
}

/// The built-in IRB 14000, created once (drawn while no dataset is loaded).
pub fn builtin_robot() -> &'static RobotDescription {
    static ROBOT: std::sync::OnceLock<RobotDescription> = std::sync::OnceLock::new();
    ROBOT.get_or_init(RobotDescription::builtin_irb14000)
}

/// The robot with the arms in joint positions `q_rad`, and the grid.
fn robot_scene(
    robot: &RobotDescription,
    meshes: Option<&Arc<PackedMeshes>>,
    q_rad: PerSide<Vec<f64>>,
    options: &SceneOptions,
    version: u64,
) -> SceneData {
    let mut scene = SceneData {
        version,
        meshes: meshes.cloned(),
        ..Default::default()
    };
    if options.show_robot {
        let shapes = robot.shapes(&q_rad.left, &q_rad.right, GeometryKind::Visual);
        if shapes.is_empty() {
            // No geometry to draw: the robot as its frames and links.
            skeleton(&robot.skeleton(&q_rad.left, &q_rad.right), &mut scene.lines);
        }
        let source = match meshes {
            Some(m) => MeshSource::Packed(m),
            None => MeshSource::Placeholders,
        };
        robot_instances(
            &shapes,
            source,
            || robot.shapes(&q_rad.left, &q_rad.right, GeometryKind::Collision),
            &mut scene.instances,
        );
    }
    if options.show_grid {
        grid(&mut scene.lines);
    }
    scene
}

/// The robot alone, both arms in the home pose, and the grid.
pub fn build_robot_scene(
    robot: &RobotDescription,
    options: &SceneOptions,
    version: u64,
) -> SceneData {
    robot_scene(
        robot,
        None,
        PerSide::from_fn(|side| robot.home_q_rad(side)),
        options,
        version,
    )
}

/// Build the whole scene. `poses` holds the measurement index each arm is drawn in (`None`: home);
/// `software_renderer` resolves [`MeshDetail::Auto`].
pub fn build_scene(
    session: &Session,
    options: &SceneOptions,
    poses: PerSide<Option<usize>>,
    selection: Option<ConfigId>,
    software_renderer: bool,
    version: u64,
) -> SceneData {
    let mut scene = robot_scene(
        &session.robot,
        session
            .meshes
            .packed_for(options.mesh_detail.simplified(software_renderer)),
        scene_q_rad(session, poses, selection),
        options,
        version,
    );
    let flags = options.screening(session).by_config();
    for row in options
        .analysis(session)
        .configs
        .iter()
        .filter(|r| options.shows(r))
    {
        // A flagged configuration in its flag's colour (severity), outlined; an excluded one grey.
        let flag = flags
            .get(&row.config)
            .filter(|_| options.show_flags && !row.excluded)
            .map(|f| colormap::flag_linear(f[0].severity()));
        let selected = selection == Some(row.config);
        if options.show_measured {
            measured_points(&mut scene, row, flag, selected, options);
        }
        if options.show_model {
            model_points(&mut scene.lines, row, selected);
        }
        if options.show_vectors {
            error_vectors(&mut scene.lines, row, options);
        }
        if selected {
            let c = srgb_linear([255, 255, 255], 1.0);
            for p in &row.measured_body_mm {
                scene.instances.push(MeshInstance::new(
                    Primitive::Sphere,
                    &Isometry3::translation(p.x, p.y, p.z),
                    Vector3::repeat(8.0),
                    c,
                ));
            }
        }
    }
    scene
}

/// The joint values each arm is drawn in: the measurement `poses` names, else home. Joints both arms
/// share (a torso) are posed by the left arm's values — by the right arm's when a right
/// configuration is selected.
fn scene_q_rad(
    session: &Session,
    poses: PerSide<Option<usize>>,
    selection: Option<ConfigId>,
) -> PerSide<Vec<f64>> {
    let mut q_rad = poses.map(|side, pose| {
        pose.and_then(|i| session.dataset.arm(side).measurements.get(i))
            .map_or_else(|| session.robot.home_q_rad(side), |m| m.q_rad.clone())
    });
    if selection.is_some_and(|c| c.side == Side::Right) {
        let shared = session.nominal.model.shared_joints();
        q_rad.left = shared.left_with_right_values(&q_rad.left, &q_rad.right);
    }
    q_rad
}

/// A configuration's measured reflectors: the triangle filled for three, a marker per reflector
/// otherwise; coloured by the mean error (or the `flag`'s severity, outlined), grey when excluded.
fn measured_points(
    scene: &mut SceneData,
    row: &ConfigRow,
    flag: Option<[f32; 3]>,
    selected: bool,
    options: &SceneOptions,
) {
    let errors = row.point_errors_mm();
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    let ([r, g, b], alpha) = match (row.excluded, flag) {
        (true, _) => ([0.3; 3], if selected { 0.8 } else { 0.15 }),
        (false, Some(c)) => (c, if selected { 0.95 } else { 0.6 }),
        (false, None) => (
            colormap::linear(mean as f32 / options.color_max_mm.max(1e-6)),
            if selected { 0.95 } else { 0.3 },
        ),
    };
    let points = &row.measured_body_mm;
    if points.len() == 3 {
        // The paper's set-up: the measured reflector triangle, filled.
        for p in points {
            scene.triangles.push(ColorVertex {
                position: p.cast::<f32>().into(),
                color: [r, g, b, alpha],
            });
        }
    } else {
        // One, two or four reflectors: a marker per reflector.
        for p in points {
            scene.instances.push(MeshInstance::new(
                Primitive::Sphere,
                &Isometry3::translation(p.x, p.y, p.z),
                Vector3::repeat(MARKER_MM),
                [r, g, b, alpha.max(0.6)],
            ));
        }
    }
    if let Some([r, g, b]) = flag {
        for (i, j) in outline(points.len()) {
            line(&mut scene.lines, points[i], points[j], [r, g, b, 1.0]);
        }
    }
}

/// Colour of the model's reflector outlines.
const MODEL_RGBA: [f32; 4] = [0.35, 0.37, 0.40, 0.8];
/// Colour of an excluded configuration's model outline and error vectors.
const EXCLUDED_RGBA: [f32; 4] = [0.25, 0.25, 0.25, 0.5];

/// A configuration's model reflectors (forward kinematics) outlined; a single one as a small cross.
fn model_points(lines: &mut Vec<ColorVertex>, row: &ConfigRow, selected: bool) {
    let c = if selected {
        [1.0, 1.0, 1.0, 1.0]
    } else if row.excluded {
        EXCLUDED_RGBA
    } else {
        MODEL_RGBA
    };
    let points = &row.model_body_mm;
    for (i, j) in outline(points.len()) {
        line(lines, points[i], points[j], c);
    }
    if points.len() == 1 {
        for axis in [Vector3::x(), Vector3::y(), Vector3::z()] {
            let d = axis * MARKER_MM;
            line(lines, points[0] - d, points[0] + d, c);
        }
    }
}

/// From each model reflector towards its measured one, exaggerated, coloured by its error.
fn error_vectors(lines: &mut Vec<ColorVertex>, row: &ConfigRow, options: &SceneOptions) {
    let max = options.color_max_mm.max(1e-6);
    for ((error, from), measured) in row
        .point_errors_mm()
        .iter()
        .zip(row.model_body_mm.iter().copied())
        .zip(row.measured_body_mm.iter().copied())
    {
        let color = if row.excluded {
            EXCLUDED_RGBA
        } else {
            let [r, g, b] = colormap::linear(*error as f32 / max);
            [r, g, b, 1.0]
        };
        let to = from + (measured - from) * options.exaggeration as f64;
        line(lines, from, to, color);
    }
}

/// A measurement plan, drawn instead of the dataset while the planning view is open: the arms in a
/// planned configuration, the tracker, the lines of sight from the shown reflectors to it, and every
/// planned configuration's reflectors.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanOverlay {
    /// Identifies the plan.
    pub revision: u64,
    /// The tracker in the robot's root (body) frame, mm.
    pub tracker_mm: Vector3<f64>,
    /// The planned configuration each arm is drawn in (`None`: home).
    pub q_rad: PerSide<Option<Vec<f64>>>,
    /// Every planned configuration's reflectors (body frame, mm), per arm.
    pub points_mm: PerSide<Vec<Vec<Vector3<f64>>>>,
    /// The reflectors of the arms as drawn: a line of sight from each to the tracker.
    pub sight_mm: Vec<Vector3<f64>>,
}

/// Colour of each arm's planned reflectors (sRGB).
const PLAN_COLORS: PerSide<[u8; 3]> = PerSide::new([90, 160, 255], [255, 150, 60]);
/// The tracker's marker: radius, mm.
const TRACKER_MM: f64 = 40.0;

/// The robot in the plan's poses, the tracker, the lines of sight and the planned reflectors.
pub fn build_plan_scene(
    robot: &RobotDescription,
    meshes: Option<&Arc<PackedMeshes>>,
    plan: &PlanOverlay,
    options: &SceneOptions,
    version: u64,
) -> SceneData {
    let q_rad = PerSide::from_fn(|side| {
        plan.q_rad[side]
            .clone()
            .unwrap_or_else(|| robot.home_q_rad(side))
    });
    let mut scene = robot_scene(robot, meshes, q_rad, options, version);
    let t = plan.tracker_mm;
    scene.instances.push(MeshInstance::new(
        Primitive::Sphere,
        &Isometry3::translation(t.x, t.y, t.z),
        Vector3::repeat(TRACKER_MM),
        srgb_linear([250, 210, 60], 1.0),
    ));
    for p in &plan.sight_mm {
        line(&mut scene.lines, *p, t, srgb_linear([250, 210, 60], 0.9));
    }
    for side in Side::BOTH {
        let color = srgb_linear(PLAN_COLORS[side], 0.85);
        for points in &plan.points_mm[side] {
            for p in points {
                scene.instances.push(MeshInstance::new(
                    Primitive::Sphere,
                    &Isometry3::translation(p.x, p.y, p.z),
                    Vector3::repeat(MARKER_MM),
                    color,
                ));
            }
            for (i, j) in outline(points.len()) {
                line(&mut scene.lines, points[i], points[j], color);
            }
        }
    }
    scene
}

/// Screen-space anchor of a configuration for picking: the centroid of its measured reflectors (the
/// triangle's, for three).
pub fn pick_anchor(row: &ConfigRow) -> Vector3<f32> {
    let n = row.measured_body_mm.len().max(1) as f64;
    (row.measured_body_mm.iter().sum::<Vector3<f64>>() / n).cast()
}

/// Size of a reflector marker (one or two reflectors, or a single model point), mm.
const MARKER_MM: f64 = 6.0;

/// The segments that outline a configuration's reflectors: the triangle's sides for three, the one
/// distance for two, none for one; every neighbour in order otherwise.
fn outline(n: usize) -> Vec<(usize, usize)> {
    match n {
        0 | 1 => Vec::new(),
        2 => vec![(0, 1)],
        n => (0..n).map(|k| (k, (k + 1) % n)).collect(),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn mesh_detail_parses_and_auto_follows_the_adapter() {
        assert_eq!(MeshDetail::parse("full"), Some(MeshDetail::Full));
        assert_eq!(
            MeshDetail::parse(" Simplified "),
            Some(MeshDetail::Simplified)
        );
        assert_eq!(MeshDetail::parse("auto"), Some(MeshDetail::Auto));
        assert_eq!(MeshDetail::parse("coarse"), None);
        assert!(MeshDetail::Auto.simplified(true));
        assert!(!MeshDetail::Auto.simplified(false));
        assert!(!MeshDetail::Full.simplified(true));
        assert!(MeshDetail::Simplified.simplified(false));
    }

    #[test]
    fn without_a_dataset_the_robot_alone_is_drawn() {
        let options = SceneOptions::default();
        let scene = build_robot_scene(builtin_robot(), &options, 1);
        let home = PerSide::from_fn(crate::robot::home_q_rad);
        let shapes = builtin_robot().shapes(&home.left, &home.right, GeometryKind::Visual);
        assert!(!shapes.is_empty());
        assert!(!scene.instances.is_empty(), "no robot drawn");
        assert!(
            scene.triangles.is_empty(),
            "no reflector triangles without data"
        );
        let hidden = build_robot_scene(
            builtin_robot(),
            &SceneOptions {
                show_robot: false,
                ..options
            },
            2,
        );
        assert!(hidden.instances.is_empty());
    }

    use super::*;

    /// A robot whose URDF has no visual geometry is drawn as its frames and links: a line per
    /// joint between link origins apart, axes at each frame, no instances; with geometry, none of it.
    #[test]
    fn a_robot_without_geometry_is_drawn_as_its_frames_and_links() {
        let mut text = crate::test_robots::single_ur_like_urdf();
        while let (Some(a), Some(b)) = (text.find("<visual>"), text.find("</visual>")) {
            text.replace_range(a..b + "</visual>".len(), "");
        }
        let (base, tip) = crate::test_robots::SINGLE_UR_ARM;
        let links = crate::robot::ArmLinks::new(base, tip);
        let robot = RobotDescription::load(
            crate::robot::RobotSource::Text {
                text: &text,
                path: None,
            },
            &crate::robot::LoadOptions {
                arms: PerSide::new(Some(links.clone()), Some(links)),
                ..Default::default()
            },
        )
        .unwrap();
        let home = PerSide::from_fn(|side| robot.home_q_rad(side));
        assert!(
            robot
                .shapes(&home.left, &home.right, GeometryKind::Visual)
                .is_empty()
        );
        let options = SceneOptions {
            show_grid: false,
            ..SceneOptions::default()
        };
        let scene = build_robot_scene(&robot, &options, 1);
        assert!(scene.instances.is_empty());
        let joints = robot.skeleton(&home.left, &home.right);
        let apart = joints
            .iter()
            .filter(|(p, c)| (c.translation.vector - p.translation.vector).norm() > 1e-6)
            .count();
        assert!(apart >= 6, "{apart} links apart");
        let frames = scene.lines.len() / 2 - apart;
        assert!(
            frames.is_multiple_of(3) && frames / 3 > apart,
            "{frames} axis lines for {apart} links"
        );
        // Every link line ends at a frame's origin, where its axes start.
        for (_, child) in &joints {
            let origin: Vector3<f32> = child.translation.vector.cast();
            assert!(
                scene
                    .lines
                    .iter()
                    .any(|v| (Vector3::from(v.position) - origin).norm() < 1e-3)
            );
        }
        let with_geometry = build_robot_scene(builtin_robot(), &options, 2);
        assert!(with_geometry.lines.is_empty(), "no skeleton over geometry");
    }

    #[test]
    fn instance_scales_then_places() {
        let pose = Isometry3::translation(10.0, 20.0, 30.0);
        let inst = MeshInstance::new(Primitive::Box, &pose, Vector3::new(2.0, 3.0, 4.0), [1.0; 4]);
        // Corner (1, 1, 1) of the unit cube maps to (12, 23, 34).
        let m = Matrix4::from_fn(|r, c| inst.model[c][r]);
        let p = m * nalgebra::Vector4::new(1.0, 1.0, 1.0, 1.0);
        assert!(
            (p.x - 12.0).abs() < 1e-5 && (p.y - 23.0).abs() < 1e-5 && (p.z - 34.0).abs() < 1e-5
        );
        // The normal matrix undoes the scale: the +x face normal stays along x.
        assert!((inst.normal[0][0] - 0.5).abs() < 1e-6);
    }
}
