//! Collision checking of the two arms against each other, against the body, and against
//! themselves, with the URDF's collision geometry (parry3d, f32).
//!
//! The engine stays in nalgebra f64 and mm; poses cross into parry's glam `Pose` at one seam
//! ([`to_parry_pose`]: translation + scaled rotation axis). Shapes are in mm. A mesh collision
//! element of an arm link becomes the convex hull of its mesh (arm links are convex-ish, and hulls
//! are fast and safe); one of the body is checked as its triangle surface (a parry `TriMesh`, as
//! MoveIt checks meshes), because the hull of a torso such as the YuMi's fills the space where the
//! arms rest. A link wholly inside the body's closed surface without touching it is not seen, which
//! random sampling of whole arms practically never produces. A mesh that cannot be loaded is left
//! out with a warning.
//!
//! Pairs that are never checked: links of the same rigid group (joined by fixed joints), adjacent
//! links (joined by one movable joint — this includes link_1 and the body), and pairs of the same arm
//! that touch in every one of a fixed set of sampled configurations (like MoveIt's "always in
//! collision" pairs: on a compact arm such as the YuMi, link i and link i+2 share a short offset
//! link and overlap by design). [`CollisionWorld::excluded_pairs`] lists them.

use crate::meshes::{GeometryKind, MeshSet};
use crate::robot::{Kinematics, Owner, RobotDescription, ShapeKind};
use crate::side::{PerSide, Side};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use parry3d::math::{Pose, Vector};
use parry3d::query;
use parry3d::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, Shape, TriMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An axis-aligned box in the body frame, mm: a keep-out zone of the cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeepOutBox {
    pub min_mm: Vector3<f64>,
    pub max_mm: Vector3<f64>,
}

impl KeepOutBox {
    /// `X0,Y0,Z0,X1,Y1,Z1` (mm, body frame; the corners in any order).
    pub fn parse(s: &str) -> Result<Self, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("`{s}`: expected X0,Y0,Z0,X1,Y1,Z1 (mm)"))?;
        match v.as_slice() {
            [a, b, c, d, e, f] if v.iter().all(|x| x.is_finite()) => Ok(Self {
                min_mm: Vector3::new(a.min(*d), b.min(*e), c.min(*f)),
                max_mm: Vector3::new(a.max(*d), b.max(*e), c.max(*f)),
            }),
            _ => Err(format!(
                "`{s}`: expected X0,Y0,Z0,X1,Y1,Z1, six numbers (mm)"
            )),
        }
    }
}

/// Number of sampled configurations used to find same-arm pairs that are always in contact.
const ALWAYS_TOUCHING_SAMPLES: usize = 64;

/// Why a link pair is not checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exclusion {
    /// Same rigid group or joined by one movable joint.
    Adjacent,
    /// Same arm, touching in every sampled configuration.
    AlwaysTouching,
}

/// What a checked pair is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairKind {
    /// A link of the left arm and one of the right arm.
    InterArm,
    /// An arm link and a body link.
    ArmBody,
    /// Two non-adjacent links of the same arm.
    SelfArm,
}

enum Prim {
    Ball(Ball),
    Cuboid(Cuboid),
    Cylinder(Cylinder),
    Capsule(Capsule),
    Convex(ConvexPolyhedron),
    Mesh(TriMesh),
}

impl Prim {
    fn shape(&self) -> &dyn Shape {
        match self {
            Prim::Ball(s) => s,
            Prim::Cuboid(s) => s,
            Prim::Cylinder(s) => s,
            Prim::Capsule(s) => s,
            Prim::Convex(s) => s,
            Prim::Mesh(s) => s,
        }
    }
}

struct CollisionShape {
    prim: Prim,
    /// The parry shape's frame in the link frame (parry cylinders run along y: turned here).
    link_from_shape: Isometry3<f64>,
    /// Radius of a sphere about the shape's origin that contains it, mm.
    bound_radius_mm: f64,
}

struct CollisionLink {
    link: usize,
    name: String,
    shapes: Vec<CollisionShape>,
}

struct Pair {
    a: usize,
    b: usize,
    kind: PairKind,
}

/// Collision geometry of a robot, compiled once.
pub struct CollisionWorld {
    kin: Kinematics,
    links: Vec<CollisionLink>,
    pairs: Vec<Pair>,
    excluded: Vec<(String, String, Exclusion)>,
    /// Collision geometry that could not be used (a mesh that is missing or cannot be read).
    pub warnings: Vec<String>,
}

/// The seam between nalgebra (f64) and parry (f32 glam): translation + scaled rotation axis.
pub fn to_parry_pose(iso: &Isometry3<f64>) -> Pose {
    let t = iso.translation.vector;
    let r = iso.rotation.scaled_axis();
    Pose::new(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Vector::new(r.x as f32, r.y as f32, r.z as f32),
    )
}

/// A mesh element (its vertices in metres, scaled to mm): its convex hull, or its triangle surface.
fn mesh_shape(
    filename: &str,
    scale: &Vector3<f64>,
    meshes: &MeshSet,
    hull: bool,
) -> Result<(Prim, f64), String> {
    let mesh = meshes
        .get(filename, [scale.x, scale.y, scale.z])
        .ok_or_else(|| format!("mesh `{filename}` could not be loaded"))?;
    let points: Vec<Vector> = mesh
        .positions_m
        .iter()
        .map(|p| Vector::new(p[0] * 1000.0, p[1] * 1000.0, p[2] * 1000.0))
        .collect();
    let bound = points
        .iter()
        .map(|p| f64::from(p.length()))
        .fold(0.0, f64::max);
    if hull {
        let hull = ConvexPolyhedron::from_convex_hull(&points)
            .ok_or_else(|| format!("mesh `{filename}` has no convex hull (flat or degenerate)"))?;
        return Ok((Prim::Convex(hull), bound));
    }
    let indices: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let trimesh = TriMesh::new(points, indices)
        .map_err(|e| format!("mesh `{filename}` is not a usable triangle mesh ({e:?})"))?;
    Ok((Prim::Mesh(trimesh), bound))
}

fn compile_shape(
    kind: &ShapeKind,
    link_from_shape: &Isometry3<f64>,
    meshes: &MeshSet,
    owner: Owner,
) -> Result<CollisionShape, String> {
    let (prim, extra, bound) = match kind {
        ShapeKind::Box { half_extents_mm: h } => (
            Prim::Cuboid(Cuboid::new(Vector::new(h.x as f32, h.y as f32, h.z as f32))),
            Isometry3::identity(),
            h.norm(),
        ),
        ShapeKind::Sphere { radius_mm } => (
            Prim::Ball(Ball::new(*radius_mm as f32)),
            Isometry3::identity(),
            *radius_mm,
        ),
        ShapeKind::Cylinder {
            radius_mm,
            half_length_mm,
        } => (
            Prim::Cylinder(Cylinder::new(*half_length_mm as f32, *radius_mm as f32)),
            // parry's cylinder axis is y; URDF's is z: Rx(π/2) takes y to z.
            Isometry3::from_parts(
                nalgebra::Translation3::identity(),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
            ),
            radius_mm.hypot(*half_length_mm),
        ),
        ShapeKind::Capsule {
            radius_mm,
            half_length_mm,
        } => (
            Prim::Capsule(Capsule::new_z(*half_length_mm as f32, *radius_mm as f32)),
            Isometry3::identity(),
            radius_mm + half_length_mm,
        ),
        ShapeKind::Mesh {
            filename, scale, ..
        } => {
            let hull = matches!(owner, Owner::Arm(_));
            let (prim, bound) = mesh_shape(filename, scale, meshes, hull)?;
            (prim, Isometry3::identity(), bound)
        }
    };
    Ok(CollisionShape {
        prim,
        link_from_shape: link_from_shape * extra,
        bound_radius_mm: bound,
    })
}

impl CollisionWorld {
    /// Compile the collision geometry of `robot` and choose the pairs to check.
    pub fn new(robot: &RobotDescription) -> Self {
        let kin = robot.kin.clone();
        let mut warnings = Vec::new();
        let mut links: Vec<CollisionLink> = Vec::new();
        let has_meshes = kin
            .collision
            .iter()
            .any(|s| matches!(s.kind, ShapeKind::Mesh { .. }));
        let meshes = if has_meshes {
            robot.load_meshes(GeometryKind::Collision)
        } else {
            MeshSet::default()
        };
        for s in &kin.collision {
            if !kin.reachable[s.link] {
                continue;
            }
            let shape = match compile_shape(&s.kind, &s.link_from_shape, &meshes, kin.owner[s.link])
            {
                Ok(shape) => shape,
                Err(why) => {
                    warnings.push(format!(
                        "link `{}`: {why}; this collision element is ignored",
                        kin.link_names[s.link]
                    ));
                    continue;
                }
            };
            match links.iter_mut().find(|l| l.link == s.link) {
                Some(l) => l.shapes.push(shape),
                None => links.push(CollisionLink {
                    link: s.link,
                    name: kin.link_names[s.link].clone(),
                    shapes: vec![shape],
                }),
            }
        }

        let group = kin.rigid_groups();
        let moving = kin.moving_joint_links();
        let adjacent = |a: usize, b: usize| {
            let (ga, gb) = (group[a], group[b]);
            ga == gb
                || moving.iter().any(|&(p, c)| {
                    (group[p] == ga && group[c] == gb) || (group[p] == gb && group[c] == ga)
                })
        };

        let mut pairs = Vec::new();
        let mut excluded = Vec::new();
        for a in 0..links.len() {
            for b in a + 1..links.len() {
                let (la, lb) = (links[a].link, links[b].link);
                let kind = match (kin.owner[la], kin.owner[lb]) {
                    (Owner::Body, Owner::Body) => continue,
                    (Owner::Arm(x), Owner::Arm(y)) if x == y => PairKind::SelfArm,
                    (Owner::Arm(_), Owner::Arm(_)) => PairKind::InterArm,
                    _ => PairKind::ArmBody,
                };
                if adjacent(la, lb) {
                    excluded.push((
                        links[a].name.clone(),
                        links[b].name.clone(),
                        Exclusion::Adjacent,
                    ));
                    continue;
                }
                pairs.push(Pair { a, b, kind });
            }
        }

        let mut world = Self {
            kin,
            links,
            pairs,
            excluded,
            warnings,
        };
        world.exclude_always_touching(robot);
        world
    }

    /// Drop same-arm pairs that intersect in the zero pose and in every sampled configuration.
    fn exclude_always_touching(&mut self, robot: &RobotDescription) {
        let limits = Side::BOTH.map(|s| {
            robot
                .joint_limits_rad(s)
                .into_iter()
                .map(|(lo, hi)| {
                    if lo.is_finite() && hi.is_finite() && lo < hi {
                        (lo, hi)
                    } else {
                        (-3.0, 3.0)
                    }
                })
                .collect::<Vec<_>>()
        });
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_c011);
        let mut always: Vec<bool> = self
            .pairs
            .iter()
            .map(|p| p.kind == PairKind::SelfArm)
            .collect();
        for sample in 0..=ALWAYS_TOUCHING_SAMPLES {
            let q: [Vec<f64>; 2] = if sample == 0 {
                [vec![0.0; limits[0].len()], vec![0.0; limits[1].len()]]
            } else {
                std::array::from_fn(|s| {
                    limits[s]
                        .iter()
                        .map(|&(lo, hi)| rng.random_range(lo..hi))
                        .collect()
                })
            };
            let placed = self.place(&q[0], &q[1]);
            for (i, p) in self.pairs.iter().enumerate() {
                if always[i] && !self.pair_hits(&placed, p, 0.0) {
                    always[i] = false;
                }
            }
        }
        let mut keep = Vec::new();
        for (p, a) in std::mem::take(&mut self.pairs).into_iter().zip(always) {
            if a {
                self.excluded.push((
                    self.links[p.a].name.clone(),
                    self.links[p.b].name.clone(),
                    Exclusion::AlwaysTouching,
                ));
            } else {
                keep.push(p);
            }
        }
        self.pairs = keep;
    }

    /// Poses of every collision shape (per link) in the body frame.
    fn place(&self, q_left: &[f64], q_right: &[f64]) -> Vec<Vec<(Pose, Vector3<f64>)>> {
        let poses = self.kin.body_from_links(q_left, q_right);
        self.links
            .iter()
            .map(|l| {
                l.shapes
                    .iter()
                    .map(|s| {
                        let iso = poses[l.link] * s.link_from_shape;
                        (to_parry_pose(&iso), iso.translation.vector)
                    })
                    .collect()
            })
            .collect()
    }

    fn pair_hits(&self, placed: &[Vec<(Pose, Vector3<f64>)>], p: &Pair, margin_mm: f64) -> bool {
        let (la, lb) = (&self.links[p.a], &self.links[p.b]);
        for (sa, (pose_a, ca)) in la.shapes.iter().zip(&placed[p.a]) {
            for (sb, (pose_b, cb)) in lb.shapes.iter().zip(&placed[p.b]) {
                if (ca - cb).norm() > sa.bound_radius_mm + sb.bound_radius_mm + margin_mm {
                    continue;
                }
                let meshes = matches!(sa.prim, Prim::Mesh(_)) || matches!(sb.prim, Prim::Mesh(_));
                let hit = if margin_mm > 0.0 && meshes {
                    // A search bounded by the margin: triangle meshes are pruned by it, where a
                    // full distance query would visit every triangle pair near the closest one.
                    query::closest_points(
                        pose_a,
                        sa.prim.shape(),
                        pose_b,
                        sb.prim.shape(),
                        margin_mm as f32,
                    )
                    .is_ok_and(|c| !matches!(c, query::ClosestPoints::Disjoint))
                } else if margin_mm > 0.0 {
                    query::distance(pose_a, sa.prim.shape(), pose_b, sb.prim.shape())
                        .is_ok_and(|d| f64::from(d.distance) < margin_mm)
                } else {
                    query::intersection_test(pose_a, sa.prim.shape(), pose_b, sb.prim.shape())
                        .is_ok_and(|r| r.intersecting)
                };
                if hit {
                    return true;
                }
            }
        }
        false
    }

    /// True if any link of one arm intersects (or is closer than `margin_mm` to) the other arm's
    /// links or the body, or two non-adjacent links of the same arm intersect. Joint values in
    /// chain order, rad.
    pub fn in_collision(&self, q_left: &[f64], q_right: &[f64], margin_mm: f64) -> bool {
        let placed = self.place(q_left, q_right);
        self.pairs
            .iter()
            .any(|p| self.pair_hits(&placed, p, self.pair_margin(p, margin_mm)))
    }

    /// True if the straight line from one of `points_mm` (body frame: the reflectors) to `target_mm`
    /// (the tracker) passes through a link of the robot at `q_left`, `q_right` — the body or either
    /// arm. The first `skip_mm` of each line are not checked (the reflector's own mount).
    pub fn line_of_sight_blocked(
        &self,
        q_left: &[f64],
        q_right: &[f64],
        points_mm: &[Vector3<f64>],
        target_mm: &Vector3<f64>,
        skip_mm: f64,
    ) -> bool {
        let placed = self.place(q_left, q_right);
        points_mm.iter().any(|p| {
            let dir = target_mm - p;
            let length = dir.norm();
            if length <= skip_mm {
                return false;
            }
            let unit = dir / length;
            let start = p + unit * skip_mm;
            let ray = parry3d::query::Ray::new(
                Vector::new(start.x as f32, start.y as f32, start.z as f32),
                Vector::new(unit.x as f32, unit.y as f32, unit.z as f32),
            );
            let reach = (length - skip_mm) as f32;
            self.links.iter().zip(&placed).any(|(link, shapes)| {
                link.shapes
                    .iter()
                    .zip(shapes)
                    .any(|(shape, (pose, centre))| {
                        // The segment's closest approach to the shape's bounding sphere first.
                        let along = (centre - start).dot(&unit).clamp(0.0, length - skip_mm);
                        if (start + unit * along - centre).norm() > shape.bound_radius_mm {
                            return false;
                        }
                        shape
                            .prim
                            .shape()
                            .cast_ray(pose, &ray, reach, true)
                            .is_some()
                    })
            })
        })
    }

    /// True if a link of either arm at `q_left`, `q_right` is within `margin_mm` of one of the
    /// keep-out boxes (the cell's fixtures, the tracker's stand).
    pub fn in_keep_out(
        &self,
        q_left: &[f64],
        q_right: &[f64],
        boxes: &[KeepOutBox],
        margin_mm: f64,
    ) -> bool {
        if boxes.is_empty() {
            return false;
        }
        let placed = self.place(q_left, q_right);
        self.links.iter().zip(&placed).any(|(link, shapes)| {
            matches!(self.kin.owner[link.link], Owner::Arm(_))
                && link
                    .shapes
                    .iter()
                    .zip(shapes)
                    .any(|(shape, (pose, centre))| {
                        boxes.iter().any(|b| {
                            let half = (b.max_mm - b.min_mm) / 2.0;
                            let mid = (b.max_mm + b.min_mm) / 2.0;
                            if (centre - mid).norm()
                                > half.norm() + shape.bound_radius_mm + margin_mm
                            {
                                return false;
                            }
                            let cuboid = Cuboid::new(Vector::new(
                                half.x as f32,
                                half.y as f32,
                                half.z as f32,
                            ));
                            let box_pose =
                                to_parry_pose(&Isometry3::translation(mid.x, mid.y, mid.z));
                            query::distance(pose, shape.prim.shape(), &box_pose, &cuboid)
                                .is_ok_and(|d| f64::from(d.distance) <= margin_mm)
                        })
                    })
        })
    }

    /// Every colliding pair (link names and what kind of pair), for diagnostics and drawing.
    pub fn colliding_pairs(
        &self,
        q_left: &[f64],
        q_right: &[f64],
        margin_mm: f64,
    ) -> Vec<(String, String, PairKind)> {
        let placed = self.place(q_left, q_right);
        self.pairs
            .iter()
            .filter(|p| self.pair_hits(&placed, p, self.pair_margin(p, margin_mm)))
            .map(|p| {
                (
                    self.links[p.a].name.clone(),
                    self.links[p.b].name.clone(),
                    p.kind,
                )
            })
            .collect()
    }

    /// Which arms take part in a collision (as [`CollisionWorld::in_collision`] sees it).
    pub fn colliding_arms(&self, q_left: &[f64], q_right: &[f64], margin_mm: f64) -> PerSide<bool> {
        let placed = self.place(q_left, q_right);
        let mut out = PerSide::new(false, false);
        for p in &self.pairs {
            if self.pair_hits(&placed, p, self.pair_margin(p, margin_mm)) {
                for l in [p.a, p.b] {
                    if let Owner::Arm(side) = self.kin.owner[self.links[l].link] {
                        out[side] = true;
                    }
                }
            }
        }
        out
    }

    fn pair_margin(&self, p: &Pair, margin_mm: f64) -> f64 {
        match p.kind {
            PairKind::SelfArm => 0.0,
            PairKind::InterArm | PairKind::ArmBody => margin_mm.max(0.0),
        }
    }

    /// Link pairs that are never checked, and why.
    pub fn excluded_pairs(&self) -> &[(String, String, Exclusion)] {
        &self.excluded
    }

    /// Number of link pairs checked per query.
    pub fn checked_pair_count(&self) -> usize {
        self.pairs.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::home_q_rad;

    use crate::kinematics::N_JOINTS;

    fn home() -> ([f64; N_JOINTS], [f64; N_JOINTS]) {
        (home_q_rad(Side::Left), home_q_rad(Side::Right))
    }

    #[test]
    fn seam_keeps_poses() {
        let iso = Isometry3::from_parts(
            nalgebra::Translation3::new(10.0, -20.0, 30.0),
            UnitQuaternion::from_euler_angles(0.3, -1.2, 2.9),
        );
        let p = to_parry_pose(&iso);
        let x = Vector3::new(1.0, 2.0, 3.0);
        let a = iso * nalgebra::Point3::from(x);
        let b = p * Vector::new(1.0, 2.0, 3.0);
        assert!(
            (a.x - f64::from(b.x)).abs() < 1e-4
                && (a.y - f64::from(b.y)).abs() < 1e-4
                && (a.z - f64::from(b.z)).abs() < 1e-4
        );
    }

    #[test]
    fn home_pose_is_free() {
        let robot = RobotDescription::builtin_irb14000();
        let world = CollisionWorld::new(&robot);
        let (l, r) = home();
        assert!(
            world.colliding_pairs(&l, &r, 0.0).is_empty(),
            "{:?}",
            world.colliding_pairs(&l, &r, 0.0)
        );
        assert!(!world.in_collision(&l, &r, 5.0));
        // The check can fail: a large margin reaches the body from the tucked-in home pose.
        assert!(world.in_collision(&l, &r, 100.0));
    }

    #[test]
    fn arms_driven_into_each_other_collide() {
        let robot = RobotDescription::builtin_irb14000();
        let world = CollisionWorld::new(&robot);
        let (home_l, home_r) = home();
        // At q = 0 both arms reach forward and their wrists meet in front of the body.
        let zero = [0.0; N_JOINTS];
        // Each arm alone at zero (the other at home) is free ...
        assert!(
            !world.in_collision(&zero, &home_r, 0.0),
            "{:?}",
            world.colliding_pairs(&zero, &home_r, 0.0)
        );
        assert!(
            !world.in_collision(&home_l, &zero, 0.0),
            "{:?}",
            world.colliding_pairs(&home_l, &zero, 0.0)
        );
        // ... both at zero collide, arm against arm.
        let pairs = world.colliding_pairs(&zero, &zero, 0.0);
        assert!(world.in_collision(&zero, &zero, 0.0));
        assert!(
            !pairs.is_empty() && pairs.iter().all(|p| p.2 == PairKind::InterArm),
            "{pairs:?}"
        );
        assert!(
            pairs
                .iter()
                .any(|(a, b, _)| a == "yumi_link_7_l" && b == "yumi_link_7_r"),
            "{pairs:?}"
        );
    }

    #[test]
    fn arm_folded_into_the_body_collides() {
        let robot = RobotDescription::builtin_irb14000();
        let world = CollisionWorld::new(&robot);
        let (mut l, r) = home();
        // Swing the left shoulder (axis 1) by 60 degrees towards the body: the upper arm and the
        // elbow go into the torso.
        l[0] += 60f64.to_radians();
        let pairs = world.colliding_pairs(&l, &r, 0.0);
        assert!(world.in_collision(&l, &r, 0.0));
        assert!(
            !pairs.is_empty()
                && pairs
                    .iter()
                    .all(|(a, _, k)| *k == PairKind::ArmBody && a == "yumi_body"),
            "{pairs:?}"
        );
        // The mirror image for the right arm.
        let (l, mut r) = home();
        r[0] -= 60f64.to_radians();
        let pairs = world.colliding_pairs(&l, &r, 0.0);
        assert!(
            !pairs.is_empty()
                && pairs
                    .iter()
                    .all(|(_, b, k)| *k == PairKind::ArmBody && b.ends_with("_r")),
            "{pairs:?}"
        );
    }

    #[test]
    fn adjacent_pairs_are_excluded_and_none_always_touch() {
        let robot = RobotDescription::builtin_irb14000();
        let world = CollisionWorld::new(&robot);
        let ex = world.excluded_pairs();
        assert!(ex.iter().any(|(a, b, e)| a == "yumi_body"
            && b == "yumi_link_1_l"
            && *e == Exclusion::Adjacent));
        assert!(ex.iter().any(|(a, b, e)| a == "yumi_link_3_r"
            && b == "yumi_link_4_r"
            && *e == Exclusion::Adjacent));
        // Our geometry keeps links i and i+2 apart: nothing is excluded as always touching.
        assert!(ex.iter().all(|e| e.2 == Exclusion::Adjacent), "{ex:?}");
        // 2 arms x (15 same-arm non-adjacent pairs + 6 against the body) + 49 inter-arm pairs
        assert_eq!(world.checked_pair_count(), 2 * (15 + 6) + 49);
        assert!(world.warnings.is_empty());
    }

    #[test]
    fn mesh_collision_geometry_is_used() {
        // The YuMi-like package: a box mesh per link (arm links as convex hulls) and a body box
        // below the shoulders (a triangle surface).
        let dir = tempfile::tempdir().unwrap();
        let urdf = crate::test_robots::write_yumi_like(dir.path());
        let robot = RobotDescription::load(&urdf, &Default::default()).unwrap();
        let world = CollisionWorld::new(&robot);
        assert!(world.warnings.is_empty(), "{:?}", world.warnings);
        let (l, r) = (robot.home_q_rad(Side::Left), robot.home_q_rad(Side::Right));
        assert!(
            !world.in_collision(&l, &r, 5.0),
            "{:?}",
            world.colliding_pairs(&l, &r, 5.0)
        );
        // Some random left-arm poses reach into the body box (the body's triangle surface).
        let limits = robot.joint_limits_rad(Side::Left);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let hit = (0..500)
            .map(|_| -> Vec<f64> {
                limits
                    .iter()
                    .map(|&(lo, hi)| rng.random_range(lo..hi))
                    .collect()
            })
            .find(|q| {
                world
                    .colliding_pairs(q, &r, 0.0)
                    .iter()
                    .any(|(a, _, k)| a == "yumi_body" && *k == PairKind::ArmBody)
            })
            .expect("an arm pose in the body");
        let arms = world.colliding_arms(&hit, &r, 0.0);
        assert!(arms.left && !arms.right);
        // A missing collision mesh is a warning, not a refused robot.
        std::fs::remove_file(dir.path().join("yumi_description/meshes/coarse/link_3.stl")).unwrap();
        let robot = RobotDescription::load(&urdf, &Default::default()).unwrap();
        let world = CollisionWorld::new(&robot);
        assert!(
            world.warnings.iter().any(|w| w.contains("link_3")),
            "{:?}",
            world.warnings
        );
    }
}
