//! Closed-form IK for UR-type arms: every solution of a pose, and proofs that a pose is out of
//! reach.
//!
//! Detection fits the UR kinematics to any model, whatever its source: joint `i`'s world axis
//! line at `q = 0`, read from the model's own FK, fixes a DH base frame (origin where axes 1 and
//! 2 cross, z along axis 1), the link lengths `a2`, `a3`, the offsets `d4` (every offset along
//! the parallel axes 2 to 4, summed) and `d5`, the joint angle at `q = 0` of each joint and the
//! sign of each axis; `d1` and `d6` go into the base and tool transforms. A model is UR-type only
//! when the fitted parametrisation's FK agrees with the model's own at 20 seeded configurations
//! to 1e-9 m and 1e-9 rad: the fit assumes the UR structure, the check proves it.
//!
//! The fitted chain is `base * A1 .. A6 * tool`, `A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i)
//! Rot_x(alpha_i)` with `alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)`, `d = (0, 0, 0, d4, d5, 0)`,
//! `a = (0, a2, a3, 0, 0, 0)` and `theta_i = offset_i + sign_i q_i`. Frames 5 and 6 share their
//! origin, the wrist centre, which fixes joint 1 (two ways), then joint 5 from the tool axis
//! (two ways), joint 6, and the planar three-link problem of joints 2 to 4 (elbow up or down).

use crate::model::{JointKind, Model};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use std::f64::consts::{FRAC_PI_2, PI};

/// Agreement the fitted FK must reach with the model's (m and rad).
const FIT_TOLERANCE: f64 = 1e-9;
/// Configurations the fit is checked at.
const FIT_CONFIGURATIONS: usize = 20;
/// Axis directions further than this from parallel or perpendicular (sine or cosine) cannot be
/// UR-type: the fit is not even tried.
const AXIS_TOLERANCE: f64 = 1e-6;
/// Link lengths below this (m) degenerate the planar sub-problem.
const MIN_LINK_M: f64 = 1e-6;
/// Sine of joint 5 below which the wrist is singular: joints 4 and 6 turn about one line and only
/// their sum or difference is fixed, a continuum of solutions.
const WRIST_SINGULAR: f64 = 1e-7;
/// Distances (m) below which the wrist centre is on joint 1's axis or joint 4's origin on joint
/// 2's: a continuum of solutions.
const SHOULDER_SINGULAR_M: f64 = 1e-9;
/// Slack on the cosines of the closed form before a branch counts as out of reach: a pose at the
/// boundary of the workspace (arm stretched) keeps its solution despite rounding.
const COSINE_SLACK: f64 = 1e-10;

/// A UR-type 6R arm: the fitted closed-form parametrisation of a model.
#[derive(Debug, Clone)]
pub struct UrArm {
    /// World pose of the DH base frame (frame 0).
    base: Isometry3<f64>,
    base_inverse: Isometry3<f64>,
    /// The model's tool frame in DH frame 6.
    tool: Isometry3<f64>,
    tool_inverse: Isometry3<f64>,
    a2: f64,
    a3: f64,
    d4: f64,
    d5: f64,
    /// DH angle of each joint at `q = 0`.
    offset: [f64; 6],
    /// `+1` or `-1`: the model's axis along or against the DH z axis.
    sign: [f64; 6],
}

/// Every solution of one pose.
#[derive(Debug, Clone, Default)]
pub struct AnalyticSolutions {
    /// Joint configurations in the model's convention, each angle in (-pi, pi], unrefined (the
    /// closed form in f64: errors around 1e-15 m). Duplicates (at the boundary of the workspace
    /// two branches meet) are not removed.
    pub configurations: Vec<[f64; 6]>,
    /// The pose has finitely many solutions and every one is listed; false at a singular pose,
    /// where a continuum of solutions exists and one representative of it is listed.
    pub finite: bool,
    /// Why no configuration reaches the pose within the 1 mm and 1 degree tolerance, when the
    /// wrist centre proves it.
    pub out_of_reach: Option<String>,
}

/// `Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)`.
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> Isometry3<f64> {
    let (sin, cos) = theta.sin_cos();
    Isometry3::from_parts(
        Translation3::new(a * cos, a * sin, d),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta) * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha),
    )
}

/// `v` turned about z by the angle of sine `s` and cosine `c`.
fn rz(s: f64, c: f64, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// `v` turned about x by a quarter turn.
fn rx_half_pi(v: Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.x, -v.z, v.y)
}

/// `v` turned about x by a quarter turn back.
fn rx_minus_half_pi(v: Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.x, v.z, -v.y)
}

/// Closest point of line `(p, u)` to line `(q, v)` (unit directions, not parallel).
fn closest_on_first(p: &Vector3<f64>, u: &Vector3<f64>, q: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    let w = p - q;
    let b = u.dot(v);
    let denominator = 1.0 - b * b;
    let t = (b * v.dot(&w) - u.dot(&w)) / denominator;
    p + u * t
}

impl UrArm {
    /// The closed-form parametrisation of `model` when it is a UR-type 6R arm (see the module
    /// documentation); `None` for any other model, prismatic joints and other dof counts included.
    pub fn detect(model: &Model) -> Option<UrArm> {
        if model.dof() != 6 || model.joints.iter().any(|j| j.kind == JointKind::Prismatic) {
            return None;
        }
        let mut ws = model.workspace();
        model.forward(&[0.0; 6], &mut ws);
        let lines: Vec<(Vector3<f64>, Vector3<f64>)> = model
            .joints
            .iter()
            .enumerate()
            .map(|(i, joint)| {
                let frame = &ws.link_in_world[i + 1];
                (frame.translation.vector, frame.rotation * joint.axis.into_inner())
            })
            .collect();
        let w = |i: usize| lines[i].1;
        let p = |i: usize| lines[i].0;
        let perpendicular = |i: usize, j: usize| w(i).dot(&w(j)).abs() < AXIS_TOLERANCE;
        let parallel = |i: usize, j: usize| w(i).cross(&w(j)).norm() < AXIS_TOLERANCE;
        if !(perpendicular(0, 1) && parallel(1, 2) && parallel(1, 3) && perpendicular(3, 4) && perpendicular(4, 5)) {
            return None;
        }
        // DH base: z along axis 1, axis 2 along -y at theta_1 = 0 (alpha_1 = pi/2), origin where
        // axes 1 and 2 cross (d1 goes into the base).
        let z = w(0);
        let y = -(w(1) - z * z.dot(&w(1))).normalize();
        let x = y.cross(&z);
        let origin = closest_on_first(&p(0), &w(0), &p(1), &w(1));
        let rotation = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_basis_unchecked(&[x, y, z]));
        let base = Isometry3::from_parts(Translation3::from(origin), rotation);
        let local = |v: Vector3<f64>| base.rotation.inverse() * v;
        let local_point = |v: Vector3<f64>| base.inverse_transform_point(&Point3::from(v)).coords;
        // Axes 2 to 4 run along -y: where they cross the x-z plane is the planar arm.
        let (p3, p4) = (local_point(p(2)), local_point(p(3)));
        let (elbow, wrist) = ((p3.x, p3.z), (p4.x - p3.x, p4.z - p3.z));
        let a2 = elbow.0.hypot(elbow.1);
        let a3 = wrist.0.hypot(wrist.1);
        if a2 < MIN_LINK_M || a3 < MIN_LINK_M {
            return None;
        }
        let mut offset = [0.0; 6];
        let mut sign = [1.0; 6];
        offset[1] = elbow.1.atan2(elbow.0);
        offset[2] = wrist.1.atan2(wrist.0) - offset[1];
        let axis2 = local(w(1));
        sign[2] = local(w(2)).dot(&axis2).signum();
        sign[3] = local(w(3)).dot(&axis2).signum();
        // Joint 4's origin is where axis 5 crosses axis 4; its distance along the parallel axes
        // is every d offset between joints 2 and 5, summed.
        let crossing45 = local_point(closest_on_first(&p(3), &w(3), &p(4), &w(4)));
        let d4 = crossing45.dot(&axis2);
        let frame3 = dh(0.0, 0.0, 0.0, FRAC_PI_2) * dh(offset[1], 0.0, a2, 0.0) * dh(offset[2], 0.0, a3, 0.0);
        // Axis 5 in frame 3 is Rot_z(theta_4) (0, -1, 0).
        let v = frame3.rotation.inverse() * local(w(4));
        offset[3] = v.x.atan2(-v.y);
        let frame4 = frame3 * dh(offset[3], d4, 0.0, FRAC_PI_2);
        let axis5 = frame4.rotation * Vector3::z();
        let crossing56 = local_point(closest_on_first(&p(4), &w(4), &p(5), &w(5)));
        let d5 = (crossing56 - frame4.translation.vector).dot(&axis5);
        // Axis 6 in frame 4 is Rot_z(theta_5) (0, 1, 0).
        let u = frame4.rotation.inverse() * local(w(5));
        offset[4] = (-u.x).atan2(u.y);
        let frame6 = frame4 * dh(offset[4], d5, 0.0, -FRAC_PI_2);
        let tool = (base * frame6).inverse() * ws.tool_in_world;
        let arm = UrArm {
            base,
            base_inverse: base.inverse(),
            tool,
            tool_inverse: tool.inverse(),
            a2,
            a3,
            d4,
            d5,
            offset,
            sign,
        };
        let numbers = [a2, a3, d4, d5].into_iter().chain(offset);
        if numbers.into_iter().any(|n| !n.is_finite()) || !arm.fits(model) {
            return None;
        }
        Some(arm)
    }

    /// Whether the fitted FK agrees with the model's at seeded configurations.
    fn fits(&self, model: &Model) -> bool {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x5552_4b49);
        (0..FIT_CONFIGURATIONS).all(|_| {
            let q: [f64; 6] = std::array::from_fn(|_| rand::Rng::random_range(&mut rng, -PI..=PI));
            let (position, angle) = crate::frames::pose_difference(&model.tool_pose(&q), &self.forward(&q));
            position <= FIT_TOLERANCE && angle <= FIT_TOLERANCE
        })
    }

    /// World pose of the tool at `q` by the fitted parametrisation.
    pub fn forward(&self, q: &[f64; 6]) -> Isometry3<f64> {
        let theta: [f64; 6] = std::array::from_fn(|i| self.offset[i] + self.sign[i] * q[i]);
        self.base
            * dh(theta[0], 0.0, 0.0, FRAC_PI_2)
            * dh(theta[1], 0.0, self.a2, 0.0)
            * dh(theta[2], 0.0, self.a3, 0.0)
            * dh(theta[3], self.d4, 0.0, FRAC_PI_2)
            * dh(theta[4], self.d5, 0.0, -FRAC_PI_2)
            * dh(theta[5], 0.0, 0.0, 0.0)
            * self.tool
    }

    /// The fitted DH numbers `(a2, a3, d4, d5)` (m); `d1` and `d6` are in the base and tool.
    pub fn lengths(&self) -> [f64; 4] {
        [self.a2, self.a3, self.d4, self.d5]
    }

    /// Every configuration whose tool frame is at world pose `goal`.
    pub fn solve(&self, goal: &Isometry3<f64>) -> AnalyticSolutions {
        let flange = self.base_inverse * goal * self.tool_inverse;
        let centre = flange.translation.vector;
        let mut out = AnalyticSolutions {
            configurations: Vec::with_capacity(8),
            finite: true,
            out_of_reach: self.out_of_reach(goal, super::search::Radii::REACHED, 0.0),
        };
        let rotation = flange.rotation.to_rotation_matrix();
        let (x6, y6, z6) = (
            rotation.matrix().column(0).into_owned(),
            rotation.matrix().column(1).into_owned(),
            rotation.matrix().column(2).into_owned(),
        );
        let (a2, a3, d4, d5) = (self.a2, self.a3, self.d4, self.d5);
        // The wrist centre lies on the plane of the parallel axes, d4 along them: theta_1 puts
        // the plane there.
        let radius = centre.x.hypot(centre.y);
        if radius < SHOULDER_SINGULAR_M {
            // On joint 1's axis (possible only with d4 = 0): every theta_1 or none.
            out.finite = false;
        }
        let sine1 = if radius > 0.0 { d4 / radius } else { 0.0 };
        if sine1.abs() > 1.0 + COSINE_SLACK {
            return out;
        }
        // Every angle below comes with its sine and cosine from the geometry that fixed it, and
        // the frames are turned as vectors: no `sin_cos` and no quaternion per branch (they
        // were most of the closed form's time).
        let psi = centre.y.atan2(centre.x);
        let (sin_psi, cos_psi) = if radius > 0.0 {
            (centre.y / radius, centre.x / radius)
        } else {
            (0.0, 1.0)
        };
        let sin_lean = sine1.clamp(-1.0, 1.0);
        let lean = sin_lean.asin();
        let cos_lean = ((1.0 - sin_lean) * (1.0 + sin_lean)).sqrt();
        let shoulders = [
            (
                psi + lean,
                sin_psi * cos_lean + cos_psi * sin_lean,
                cos_psi * cos_lean - sin_psi * sin_lean,
            ),
            (
                psi + PI - lean,
                cos_psi * sin_lean - sin_psi * cos_lean,
                -(cos_psi * cos_lean + sin_psi * sin_lean),
            ),
        ];
        let flange_rotation = rotation.matrix();
        let flange_origin = flange.translation.vector;
        for (theta1, s1, c1) in shoulders {
            let z1 = Vector3::new(s1, -c1, 0.0);
            let c5 = z6.dot(&z1).clamp(-1.0, 1.0);
            let across5 = ((1.0 - c5) * (1.0 + c5)).sqrt();
            // A vector of the flange frame in DH frame 1 (`A1^-1`, `A1 = Rz(theta1) Rx(pi/2)`).
            let in_first = |v: Vector3<f64>| rx_minus_half_pi(rz(-s1, c1, &v));
            for wrist in [1.0, -1.0] {
                let theta5 = wrist * c5.acos();
                let s5 = wrist * across5;
                let (theta6, s6, c6) = if s5.abs() < WRIST_SINGULAR {
                    out.finite = false;
                    (0.0, 0.0, 1.0)
                } else {
                    // z1 in frame 6: (c6 s5, -s6 s5, .).
                    let flip = s5.signum();
                    let (y, x) = (-z1.dot(&y6) * flip, z1.dot(&x6) * flip);
                    let length = (x * x + y * y).sqrt();
                    (y.atan2(x), y / length, x / length)
                };
                // Frame 6 to frame 4 is `(A5 A6)^-1`, `A5 = Rz(theta5) Tz(d5) Rx(-pi/2)`, `A6 =
                // Rz(theta6)`: a vector of frame 4 in the flange's is `Rz(-theta6) Rx(pi/2)
                // Rz(-theta5)` of it.
                let to_flange = |v: Vector3<f64>| rz(-s6, c6, &rx_half_pi(rz(-s5, c5, &v)));
                let x4 = in_first(flange_rotation * to_flange(Vector3::x()));
                let origin4 = in_first(flange_origin - flange_rotation * to_flange(Vector3::new(0.0, 0.0, d5)));
                let (x, y) = (origin4.x, origin4.y);
                let sum = x4.y.atan2(x4.x);
                let squared = x * x + y * y;
                if squared.sqrt() < SHOULDER_SINGULAR_M {
                    out.finite = false;
                }
                let c3 = (squared - a2 * a2 - a3 * a3) / (2.0 * a2 * a3);
                if c3.abs() > 1.0 + COSINE_SLACK {
                    continue;
                }
                let c3 = c3.clamp(-1.0, 1.0);
                let across3 = ((1.0 - c3) * (1.0 + c3)).sqrt();
                for elbow in [1.0, -1.0] {
                    let theta3 = elbow * c3.acos();
                    let s3 = elbow * across3;
                    let theta2 = y.atan2(x) - (a3 * s3).atan2(a2 + a3 * c3);
                    let theta4 = sum - theta2 - theta3;
                    let theta = [theta1, theta2, theta3, theta4, theta5, theta6];
                    out.configurations.push(std::array::from_fn(|i| {
                        super::wrap_angle(self.sign[i] * (theta[i] - self.offset[i]))
                    }));
                }
                if s5.abs() < WRIST_SINGULAR {
                    // Both wrist signs are the same configuration family.
                    break;
                }
            }
        }
        if out.finite && out.configurations.is_empty() && out.out_of_reach.is_none() {
            out.out_of_reach = self.elbow_out_of_reach(goal, 0.0);
        }
        out
    }

    /// Joint 1's sine condition and the elbow cosine of each of the four (shoulder, wrist)
    /// branches at `goal`: a branch has a solution when its cosine is within [-1, 1]; `None` when
    /// joint 1 has none (the sine beyond 1) or the pose is singular for the closed form.
    fn branch_cosines(&self, goal: &Isometry3<f64>) -> Option<(f64, [f64; 4])> {
        let flange = self.base_inverse * goal * self.tool_inverse;
        let centre = flange.translation.vector;
        let rotation = flange.rotation.to_rotation_matrix();
        let (x6, y6, z6) = (
            rotation.matrix().column(0).into_owned(),
            rotation.matrix().column(1).into_owned(),
            rotation.matrix().column(2).into_owned(),
        );
        let radius = centre.x.hypot(centre.y);
        let sine1 = self.d4 / radius;
        if radius < SHOULDER_SINGULAR_M || sine1.abs() > 1.0 {
            return None;
        }
        let psi = centre.y.atan2(centre.x);
        let lean = sine1.asin();
        let mut cosines = [0.0; 4];
        for (b, (theta1, wrist)) in [
            (psi + lean, 1.0),
            (psi + lean, -1.0),
            (psi + PI - lean, 1.0),
            (psi + PI - lean, -1.0),
        ]
        .into_iter()
        .enumerate()
        {
            let (s1, c1) = theta1.sin_cos();
            let z1 = Vector3::new(s1, -c1, 0.0);
            let theta5: f64 = wrist * z6.dot(&z1).clamp(-1.0, 1.0).acos();
            let s5 = theta5.sin();
            if s5.abs() < WRIST_SINGULAR {
                return None;
            }
            let flip = s5.signum();
            let theta6 = (-z1.dot(&y6) * flip).atan2(z1.dot(&x6) * flip);
            let frame4 = flange * (dh(theta5, self.d5, 0.0, -FRAC_PI_2) * dh(theta6, 0.0, 0.0, 0.0)).inverse();
            let in_first = dh(theta1, 0.0, 0.0, FRAC_PI_2).inverse() * frame4;
            let (x, y) = (in_first.translation.x, in_first.translation.y);
            cosines[b] = (x * x + y * y - self.a2 * self.a2 - self.a3 * self.a3) / (2.0 * self.a2 * self.a3);
        }
        Some((sine1, cosines))
    }

    /// Why no configuration reaches `goal` (turned by up to `turn` about tool z) within the
    /// tolerance, when joint 1 has its two branches but every branch's elbow cosine lies beyond
    /// +-1 by more than the tolerance can move it: the cosines' gradients over the pose (central
    /// differences in the six world directions, and the turn about tool z), times 1 mm and
    /// 1 degree (and the turn), doubled for the curvature like the other certificates.
    pub fn elbow_out_of_reach(&self, goal: &Isometry3<f64>, turn: f64) -> Option<String> {
        self.elbow_out_of_reach_within(goal, super::search::Radii::REACHED, turn)
    }

    /// [`Self::elbow_out_of_reach`] for the poses within `radii` of `goal` (a part of the
    /// tolerance).
    fn elbow_out_of_reach_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> Option<String> {
        let (sine1, cosines) = self.branch_cosines(goal)?;
        if cosines.iter().any(|c| c.abs() <= 1.0) {
            return None;
        }
        const STEP: f64 = 1e-6;
        let shifted = |direction: usize, sign: f64| -> Option<(f64, [f64; 4])> {
            let h = sign * STEP;
            let pose = match direction {
                0..=2 => {
                    let mut t = goal.translation.vector;
                    t[direction] += h;
                    Isometry3::from_parts(Translation3::from(t), goal.rotation)
                }
                3..=5 => {
                    let axis = Vector3::ith(direction - 3, 1.0);
                    Isometry3::from_parts(goal.translation, UnitQuaternion::from_scaled_axis(axis * h) * goal.rotation)
                }
                _ => {
                    let z = goal.rotation * Vector3::z();
                    Isometry3::from_parts(goal.translation, UnitQuaternion::from_scaled_axis(z * h) * goal.rotation)
                }
            };
            self.branch_cosines(&pose)
        };
        // Per quantity (the sine, then each cosine), the squared gradient over position, over
        // rotation, and the rate along the turn.
        let mut position = [0.0; 5];
        let mut rotation = [0.0; 5];
        let mut along = [0.0; 5];
        for direction in 0..7 {
            let (plus, minus) = (shifted(direction, 1.0)?, shifted(direction, -1.0)?);
            let values = |v: (f64, [f64; 4])| [v.0, v.1[0], v.1[1], v.1[2], v.1[3]];
            let (plus, minus) = (values(plus), values(minus));
            for i in 0..5 {
                let derivative = (plus[i] - minus[i]) / (2.0 * STEP);
                match direction {
                    0..=2 => position[i] += derivative * derivative,
                    3..=5 => rotation[i] += derivative * derivative,
                    _ => along[i] = derivative.abs(),
                }
            }
        }
        let change =
            |i: usize| 2.0 * (position[i].sqrt() * radii.position_m + rotation[i].sqrt() * radii.orientation_rad + along[i] * turn);
        let branches_stay = 1.0 - sine1.abs() > change(0);
        let every_elbow_out = (0..4).all(|b| cosines[b].abs() - 1.0 > change(b + 1));
        (branches_stay && every_elbow_out).then(|| {
            let least = cosines.iter().map(|c| c.abs() - 1.0).fold(f64::INFINITY, f64::min);
            format!(
                "closed-form IK: pose out of reach: on every branch the elbow's cosine lies at least {least:.4} beyond +-1, more than the goal's tolerance can move it (first order, doubled)"
            )
        })
    }

    /// Why no configuration reaches `goal`, turned by up to `turn` about tool z, within 1 mm and
    /// 1 degree: the wrist-centre proof of [`UrArm::solve`] with the turn added to the slack.
    pub fn out_of_reach_over_turn(&self, goal: &Isometry3<f64>, turn: f64) -> Option<String> {
        self.out_of_reach_within(goal, super::search::Radii::REACHED, turn)
    }

    /// [`Self::out_of_reach_over_turn`] for the poses within `radii` of `goal` instead of the
    /// whole tolerance (a part of it: the out-of-reach proof cut into parts). The elbow's
    /// certificate is first order, doubled, as over the whole tolerance; over a part of radius
    /// `r` its neglected remainder shrinks as `r^2` and the doubling's margin as `r`, so a part
    /// holds it with more room than the whole.
    pub fn out_of_reach_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> Option<String> {
        self.out_of_reach(goal, radii, turn)
            .or_else(|| self.elbow_out_of_reach_within(goal, radii, turn))
    }

    /// Why no configuration reaches `goal` within 1 mm and 1 degree, from the wrist centre
    /// (the flange's origin, DH base frame) alone: it lies `d4` off the arm's plane, at most
    /// `|a2| + |a3| + |d5|` and at least `||a2| - |a3|| - |d5|` from axis 2 in that plane. A tool
    /// within the tolerance puts the wrist centre within `1 mm + L * 1 deg` of it (`L` its
    /// distance from the tool), so a centre further than that outside the region proves the pose
    /// out of reach. Inside that ball, the distance from the shoulder is bounded more tightly: a
    /// turn of the tool about its own point moves the centre on the sphere of radius `L` about
    /// it, over a cap within 1 degree of where the pose needs it, and the distance from the
    /// shoulder over such a cap has a closed form (the shoulder's direction seen from the tool
    /// against the cap's).
    ///
    /// With `turn` > 0 the pose may also turn that much about tool z (a sample of a
    /// `z_symmetric` goal's free turn): the centre moves by at most `r * turn` more, `r` its
    /// distance from the tool's z axis (none where the flange's axis is the tool's), or its
    /// cap widens by `turn`, whichever bounds it closer.
    fn out_of_reach(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> Option<String> {
        let tool = self.base_inverse * goal;
        let centre = (tool * self.tool_inverse).translation.vector;
        let lever = self.tool.translation.vector.norm();
        let z = tool.rotation * Vector3::z();
        let arm = centre - tool.translation.vector;
        let off_axis = (arm - z * arm.dot(&z)).norm();
        let spun = off_axis.min(lever) * turn;
        let slack = radii.position_m + lever * radii.orientation_rad + spun;
        let within = radii.words();
        let d4 = self.d4.abs();
        let radius = centre.x.hypot(centre.y);
        let distance = centre.norm();
        let (a2, a3, d5) = (self.a2.abs(), self.a3.abs(), self.d5.abs());
        let outer = (a2 + a3 + d5).hypot(d4);
        let inner = ((a2 - a3).abs() - d5).max(0.0).hypot(d4);
        if radius < d4 - slack {
            Some(format!(
                "closed-form IK: pose out of reach: its wrist centre is {radius:.3} m from joint 1's axis, and the arm's offset along its parallel axes keeps it at least {d4:.3} m away"
            ))
        } else if distance > outer + slack {
            Some(format!(
                "closed-form IK: pose out of reach: its wrist centre is {distance:.3} m from the shoulder, and the stretched arm reaches {outer:.3} m"
            ))
        } else if distance < inner - slack {
            Some(format!(
                "closed-form IK: pose out of reach: its wrist centre is {distance:.3} m from the shoulder, and the folded arm comes no closer than {inner:.3} m"
            ))
        } else {
            let point = &tool.translation.vector;
            let (wide_near, wide_far) = cap_distances(point, &centre, radii.orientation_rad + turn);
            let (near, far) = cap_distances(point, &centre, radii.orientation_rad);
            let (nearest, furthest) = (wide_near.max(near - spun), wide_far.min(far + spun));
            let (nearest, furthest) = (nearest - radii.position_m, furthest + radii.position_m);
            if nearest > outer {
                Some(format!(
                    "closed-form IK: pose out of reach: a tool within {within} of it puts its wrist centre at least {nearest:.4} m from the shoulder, and the stretched arm reaches {outer:.4} m"
                ))
            } else if furthest < inner {
                Some(format!(
                    "closed-form IK: pose out of reach: a tool within {within} of it puts its wrist centre at most {furthest:.4} m from the shoulder, and the folded arm comes no closer than {inner:.4} m"
                ))
            } else {
                None
            }
        }
    }
}

/// The least and greatest distance from the origin of the points `point + R (centre - point)`
/// over every rotation `R` by at most `angle`: the sphere of radius `|centre - point|` about
/// `point`, within `angle` of `centre` as seen from `point` (a cap).
fn cap_distances(point: &Vector3<f64>, centre: &Vector3<f64>, angle: f64) -> (f64, f64) {
    let arm = centre - point;
    let lever = arm.norm();
    let away = point.norm();
    if lever == 0.0 || away == 0.0 {
        return (centre.norm(), centre.norm());
    }
    // The angle between the origin's direction from `point` (reversed: `point` itself) and the
    // cap's; |x|^2 = |p|^2 + L^2 + 2 L (p . w) with w within `angle` of the cap's direction.
    let between = (point.dot(&arm) / (away * lever)).clamp(-1.0, 1.0).acos();
    let dot_high = away * (between - angle).max(0.0).cos();
    let dot_low = away * (between + angle).min(std::f64::consts::PI).cos();
    let squared = |dot: f64| (away * away + lever * lever + 2.0 * lever * dot).max(0.0).sqrt();
    (squared(dot_low), squared(dot_high))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit};
    use rand::{Rng, SeedableRng};

    /// The closed-form range against dense points of the cap.
    #[test]
    fn cap_distances_bound_dense_points_of_the_cap() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..100 {
            let point = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let centre = point + Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3));
            let angle = rng.random_range(0.0..0.2);
            let (near, far) = cap_distances(&point, &centre, angle);
            let arm = centre - point;
            let side = Unit::new_normalize(arm.cross(&Vector3::new(0.3, -0.7, 0.2)));
            let (mut least, mut most) = (f64::INFINITY, 0.0f64);
            for i in 0..=40 {
                let tilted = Rotation3::from_axis_angle(&side, angle * i as f64 / 40.0) * arm;
                for k in 0..180 {
                    let x = point + Rotation3::from_axis_angle(&Unit::new_normalize(arm), k as f64 * PI / 90.0) * tilted;
                    least = least.min(x.norm());
                    most = most.max(x.norm());
                }
            }
            assert!(
                near <= least + 1e-12 && far >= most - 1e-12,
                "[{near}, {far}] misses [{least}, {most}]"
            );
            assert!(
                least - near < 2e-3 && far - most < 2e-3,
                "[{near}, {far}] loose around [{least}, {most}]"
            );
        }
    }
}
