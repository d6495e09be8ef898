//! Every solution of a pose of a 6R arm whose last three axes meet in one point (a spherical
//! wrist: Pieper's decomposition), or whose first three do (the same on the reversed chain).
//!
//! The wrist centre `c` is fixed by joints 4 to 6, so `e1 e2 e3 c = T M^-1 c =: X`: a 3R
//! positioning problem. Turning about axis 1 keeps a point's distance from a point `o` of that
//! axis and its height along it, so `|e2 e3 c - o|^2 = |X - o|^2` and `w1 . (e2 e3 c - o) =
//! w1 . (X - o)`: two equations in joints 2 and 3, each a combination of `{1, s2, c2} x {1, s3,
//! c3}` (read off exactly by interpolation, as in [`super::general`]). With half-angle tangents
//! they are two quadratics in `x2`; their Sylvester resultant is a 4 x 4 matrix quadratic in `x3`
//! whose determinant vanishes at each solution (at most 4 real), found as an 8 x 8 companion
//! eigenproblem. Joint 1 is the turn about axis 1 onto `X`; joints 4 and 5 turn axis 6 onto its
//! goal direction (the two-rotation subproblem, up to two ways, for any twist between the wrist
//! axes); joint 6 is the rest.

use super::bilinear;
use super::cap::Cap;
use super::lines::{interpolate2, node_turns, turn_about, Arm, Chain, Turn, NODES};
use crate::model::Model;
use nalgebra::{Isometry3, Matrix3, Vector3};

/// Lines closer than this (scaled lengths) meet.
const MEET: f64 = 1e-9;
/// Sine of the angle below which two wrist axes count as parallel: no spherical wrist.
const PARALLEL: f64 = 1e-6;
/// A point closer than this (scaled) to an axis leaves that joint's angle free: a continuum.
const ON_AXIS: f64 = 1e-9;

/// Every solution of one pose, unpolished.
#[derive(Debug, Clone, Default)]
pub struct WristSolutions {
    /// Joint configurations in the model's convention, angles in (-pi, pi].
    pub configurations: Vec<[f64; 6]>,
    /// Every solution is listed (given each is verified by the caller); false at a singular
    /// pose (a continuum of solutions) or where a root could not be resolved.
    pub resolved: bool,
    /// Why no configuration reaches the pose within 1 mm and 1 degree, when the wrist centre
    /// proves it (see [`SphericalWrist::out_of_reach_over_turn`]); only looked for when no solution exists.
    pub out_of_reach: Option<String>,
}

/// Pieper's solver of one model.
#[derive(Debug, Clone)]
pub struct SphericalWrist {
    arm: Arm,
    /// The wrist is at the base: the reversed chain is solved.
    reversed: bool,
    /// The wrist centre (scaled chain coordinates).
    centre: Vector3<f64>,
    /// `[equation][{1, s2, c2} x {1, s3, c3}]`: squared distance from axis 1's point, height
    /// along axis 1.
    position: [[f64; 9]; 2],
    /// Two consecutive positioning axes meet or are parallel: one joint has an equation of its
    /// own, and the positioning is closed form.
    decoupled: Option<Decoupled>,
}

/// How two consecutive axes relate when the positioning decouples.
#[derive(Debug, Clone, Copy)]
enum Pair {
    /// They meet here: turning about either keeps the distance from it.
    Meet(Vector3<f64>),
    /// Parallel: turning about either keeps the height along them.
    Parallel,
}

/// Positioning chains with a closed form. Axes 1 and 2 meet or are parallel (a shoulder like
/// most arms'): the resultant would vanish doubly at every root (one equation lacks joint 2), so
/// joint 3 comes from what joints 1 and 2 keep, joint 2 from what joint 1 keeps, joint 1 last.
/// Axes 2 and 3 meet or are parallel (an elbow in one plane, like the ABB's): what joints 2 and 3
/// keep fixes joint 1 first, then joint 3 from what joint 2 keeps, then joint 2.
#[derive(Debug, Clone, Copy)]
enum Decoupled {
    Shoulder(Pair),
    Elbow(Pair),
}

impl SphericalWrist {
    /// The solver of `model` when it is a 6R arm with three consecutive axes meeting at one end
    /// (the last three, else the first three).
    pub fn detect(model: &Model) -> Option<SphericalWrist> {
        Self::of_arm(Arm::of(model)?)
    }

    /// The solver of a chain's lines (see [`super::lines`]).
    pub(crate) fn of_arm(arm: Arm) -> Option<SphericalWrist> {
        for reversed in [false, true] {
            let chain = arm.chain(reversed);
            let Some(centre) = meeting_point(chain) else { continue };
            let position = position_coefficients(chain, &centre);
            let [l1, l2, l3, ..] = &chain.lines;
            let decoupled = pair(l1, l2).map(Decoupled::Shoulder).or_else(|| pair(l2, l3).map(Decoupled::Elbow));
            let wrist = SphericalWrist {
                arm: arm.clone(),
                reversed,
                centre,
                position,
                decoupled,
            };
            if wrist.decoupled.is_some() || wrist.regular() {
                return Some(wrist);
            }
        }
        None
    }

    /// Whether the wrist is at the base (axes 1 to 3 meet).
    pub fn at_base(&self) -> bool {
        self.reversed
    }

    /// Whether the positioning resultant holds for this arm: not identically zero.
    fn regular(&self) -> bool {
        let chain = self.arm.chain(self.reversed);
        let q = [0.7, -0.9, 1.2, 0.4, -1.1, 0.3];
        let (rotation, translation) = chain.forward(&q);
        let [s0, s1, s2] = bilinear::resultant(&self.equations(&rotation, &translation), bilinear::OFFSETS_B[0]);
        let probe = s0 + s1 * 0.41 + s2 * (0.41 * 0.41);
        let sigma = probe.svd(false, false).singular_values;
        sigma.min() > 1e-10 * sigma.max()
    }

    /// Every configuration whose tool frame is at world pose `goal`, unpolished; where there is
    /// none, the wrist centre's ball proof (see [`Self::solve_proving`]).
    pub fn solve(&self, goal: &Isometry3<f64>) -> WristSolutions {
        self.solve_proving(goal, 0)
    }

    /// [`Self::solve`], where no solution exists and the ball does not prove it, the cap within it
    /// at up to `evaluations` distances: a goal's own proof, not poses solved in bulk (a
    /// self-motion's samples, the nearby poses).
    pub fn solve_proving(&self, goal: &Isometry3<f64>, evaluations: usize) -> WristSolutions {
        let (rotation, translation) = self.arm.goal(goal, self.reversed);
        let mut out = self.solve_chain(&rotation, &translation);
        if out.resolved && out.configurations.is_empty() {
            out.out_of_reach = self.out_of_reach(&rotation, &translation, super::search::Radii::REACHED, 0.0, evaluations);
        }
        if self.reversed {
            for q in &mut out.configurations {
                q.reverse();
            }
        }
        out
    }

    /// Why no configuration reaches `goal`, turned by up to `turn` about tool z, within the
    /// tolerance: the wrist-centre proof with the turn added to the slack, and where that fails
    /// the cap within it, at up to `evaluations` distances (about 30 ns each; none: the ball
    /// alone).
    pub fn out_of_reach_over_turn(&self, goal: &Isometry3<f64>, turn: f64, evaluations: usize) -> Option<String> {
        self.out_of_reach_within(goal, super::search::Radii::REACHED, turn, evaluations)
    }

    /// [`Self::out_of_reach_over_turn`] for the poses within `radii` of `goal` instead of the
    /// whole tolerance (a part of it: the out-of-reach proof cut into parts).
    pub fn out_of_reach_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64, evaluations: usize) -> Option<String> {
        let (rotation, translation) = self.arm.goal(goal, self.reversed);
        self.out_of_reach(&rotation, &translation, radii, turn, evaluations)
    }

    /// Why no configuration reaches the pose within the tolerance, from the wrist centre alone:
    /// a tool within 1 mm and 1 degree puts the wrist centre within `1 mm + L * 1 deg` of where
    /// the pose needs it (`L` its distance from the tool). Turning about axis 1 keeps a point's
    /// distance from that axis and its height along it, so the wrist centre's closest approach
    /// is the closest approach of `(r, h)(q2, q3)` to the target's; a branch and bound over
    /// joints 2 and 3 bounds it from below (Lipschitz constants from the axis distances) and
    /// proves it larger than the slack, or gives up (`None`).
    ///
    /// With `turn` > 0 the pose may also turn that much about tool z: the centre moves by at
    /// most `r * turn` more, `r` its distance from the tool's z axis (`L` on the reversed
    /// chain).
    ///
    /// A wrist at the base is the same on the reversed chain: its centre (where axes 1 to 3
    /// meet) is fixed in the world, and must be where joints 6 to 4 put it in the tool frame;
    /// the tolerance moves that target by the same `1 mm + L * 1 deg`.
    ///
    /// Where the ball fails, the cap within it ([`Cap`]) within `evaluations`.
    fn out_of_reach(
        &self,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
        radii: super::search::Radii,
        turn: f64,
        evaluations: usize,
    ) -> Option<String> {
        let chain = self.arm.chain(self.reversed);
        let scale = self.arm.scale();
        let target = self.target(chain, rotation, translation);
        // The centre's distance from the tool: fixed in the tool frame, or (at the base) the
        // target itself, which the reversed chain gives in tool coordinates.
        let lever = if self.reversed {
            target.norm()
        } else {
            (self.centre - chain.home_translation).norm()
        } * scale;
        // Where the turn about tool z moves the centre from: at most its distance from that
        // axis times the turn (a held joint's chain has the joint's axis as its tool's z).
        let off_axis = if self.reversed {
            lever
        } else {
            let local = chain.home_rotation.transpose() * (self.centre - chain.home_translation);
            local.x.hypot(local.y) * scale
        };
        let spun = off_axis.min(lever) * turn;
        // The real tool may sit off the chain's tool (a held joint): the angle acts over both.
        let slack = (radii.position_m + (lever + self.arm.tool_lever) * radii.orientation_rad + spun) / scale;
        let within = radii.words();
        let [l1, l2, l3, ..] = &chain.lines;
        let cylindrical = |p: &Vector3<f64>| {
            let v = p - l1.point;
            let h = l1.axis.dot(&v);
            ((v - l1.axis * h).norm(), h)
        };
        let (target_r, target_h) = cylindrical(&target);
        let gap = |t2: f64, t3: f64| {
            let (r, h) = cylindrical(&l2.turn(t2, &l3.turn(t3, &self.centre)));
            (r - target_r).hypot(h - target_h)
        };
        let rates = super::cap::turn_rates(l2, l3, &self.centre);
        let centre = if self.reversed {
            "the point where axes 1 to 3 meet (a wrist at the base) is never closer than"
        } else {
            "its wrist centre comes no closer than"
        };
        if let Some(closest) = lower_bound_above(&gap, rates, slack) {
            return Some(format!(
                "all-solutions IK (spherical wrist): pose out of reach: {centre} {:.1} mm to where the pose needs it, and a tool within {within} would put it within {:.1} mm",
                closest * scale * 1e3,
                slack * scale * 1e3
            ));
        }
        if evaluations == 0 {
            return None;
        }
        // The ball holds every place a tolerated tool can need the centre, but those lie on a
        // sphere about the tool's origin (the tool frame's origin on the reversed chain): within
        // the position's share of the slack of a cap of it.
        let origin = if self.reversed { Vector3::zeros() } else { *translation };
        let arm = target - origin;
        // The turn widens the cap, or, for a centre near the tool's z axis, adds its motion to
        // the position's share.
        let near_axis = 2.0 * off_axis <= lever;
        let (widened, spun) = if near_axis { (0.0, spun) } else { (turn, 0.0) };
        let position = (radii.position_m + self.arm.tool_lever * radii.orientation_rad + spun) / scale;
        let cap = Cap {
            centre: origin,
            axis: arm.try_normalize(0.0)?,
            radius: arm.norm(),
            angle: radii.orientation_rad + widened,
        };
        let closest = cap.lower_bound_above([l1, l2, l3], &self.centre, position, evaluations)?;
        Some(format!(
            "all-solutions IK (spherical wrist): pose out of reach: {centre} {:.1} mm to where a tool within {within} would need it ({:.0} mm from the tool, turned up to {:.2} deg), more than the {:.1} mm the tool's position allows",
            closest * scale * 1e3,
            cap.radius * scale * 1e3,
            cap.angle.to_degrees(),
            position * scale * 1e3
        ))
    }

    /// The two positioning equations in joints 2 and 3 at a pose (`[{1, s2, c2} x {1, s3,
    /// c3}]`): the wrist centre's squared distance from axis 1's point and height along it, less
    /// the target's.
    fn equations(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> [[f64; 9]; 2] {
        let chain = self.arm.chain(self.reversed);
        let target = self.target(chain, rotation, translation);
        let axis1 = &chain.lines[0];
        let relative = target - axis1.point;
        let goals = [relative.norm_squared(), axis1.axis.dot(&relative)];
        let mut out = self.position;
        for (equation, goal) in out.iter_mut().zip(goals) {
            equation[0] -= goal;
        }
        out
    }

    /// Where the wrist centre must be: `T M^-1 c`.
    fn target(&self, chain: &Chain, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Vector3<f64> {
        rotation * (chain.home_rotation.transpose() * (self.centre - chain.home_translation)) + translation
    }

    /// Joints 1 to 3 putting the wrist centre on `target` when the positioning decouples;
    /// `None` where a joint is free (a continuum).
    fn decoupled_positions(&self, chain: &Chain, target: &Vector3<f64>, decoupled: Decoupled) -> Option<Vec<[Turn; 3]>> {
        let [l1, l2, l3, ..] = &chain.lines;
        let c = &self.centre;
        let mut out = Vec::with_capacity(4);
        match decoupled {
            Decoupled::Shoulder(relation) => {
                for t3 in trig_roots(|t| relation.kept(l1, &l3.turn_by(t, c)), relation.kept(l1, target))? {
                    let moved = l3.turn_by(t3, c);
                    for t2 in trig_roots(|t| relation.other(l1, &l2.turn_by(t, &moved)), relation.other(l1, target))? {
                        let point = l2.turn_by(t2, &moved);
                        let t1 = turn_about(&l1.axis, &(point - l1.point), &(target - l1.point), ON_AXIS)?;
                        out.push([t1, t2, t3]);
                    }
                }
            }
            Decoupled::Elbow(relation) => {
                // Joint 1 turned back, the target is where joints 2 and 3 must put the centre.
                for t1 in trig_roots(|t| relation.kept(l2, &l1.turn_by(t.inverse(), target)), relation.kept(l2, c))? {
                    let goal = l1.turn_by(t1.inverse(), target);
                    for t3 in trig_roots(|t| relation.other(l2, &l3.turn_by(t, c)), relation.other(l2, &goal))? {
                        let point = l3.turn_by(t3, c);
                        let t2 = turn_about(&l2.axis, &(point - l2.point), &(goal - l2.point), ON_AXIS)?;
                        out.push([t1, t2, t3]);
                    }
                }
            }
        }
        Some(out)
    }

    fn solve_chain(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> WristSolutions {
        let chain = self.arm.chain(self.reversed);
        let target = self.target(chain, rotation, translation);
        let found = match self.decoupled {
            Some(decoupled) => self
                .decoupled_positions(chain, &target, decoupled)
                .map(|positions| (positions, true)),
            None => self.resultant_positions(chain, &target, rotation, translation),
        };
        // None: a continuum, or no offset regular: nothing listed, and not resolved.
        let Some((positions, resolved)) = found else {
            return WristSolutions::default();
        };
        let out = WristSolutions {
            resolved,
            ..WristSolutions::default()
        };
        self.finish(chain, rotation, positions, out)
    }

    /// Joints 1 to 3 from the resultant's common roots in joints 2 and 3, and whether each gave
    /// them (not where the wrist centre lies on axis 1, joint 1 free); `None` where no offset is
    /// regular.
    fn resultant_positions(
        &self,
        chain: &Chain,
        target: &Vector3<f64>,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
    ) -> Option<(Vec<[Turn; 3]>, bool)> {
        let (roots, mut resolved) = bilinear::common_roots(&self.equations(rotation, translation))?;
        let [l1, l2, l3, ..] = &chain.lines;
        let mut positions: Vec<[Turn; 3]> = Vec::with_capacity(8);
        for (t2, t3) in roots {
            let (t2, t3) = (Turn::of(t2), Turn::of(t3));
            let point = l2.turn_by(t2, &l3.turn_by(t3, &self.centre));
            let Some(t1) = turn_about(&l1.axis, &(point - l1.point), &(*target - l1.point), ON_AXIS) else {
                // The wrist centre on axis 1: joint 1 is free.
                resolved = false;
                continue;
            };
            positions.push([t1, t2, t3]);
        }
        Some((positions, resolved))
    }

    /// The wrist joints for each position of joints 1 to 3.
    fn finish(&self, chain: &Chain, rotation: &Matrix3<f64>, positions: Vec<[Turn; 3]>, mut out: WristSolutions) -> WristSolutions {
        let [l1, l2, l3, l4, l5, l6] = &chain.lines;
        let (w4, w5, w6) = (l4.axis, l5.axis, l6.axis);
        // Only directions are turned below: axis 6 to its goal direction, and a direction
        // across it whose image fixes joint 6 (see `lines::axis_angle_of`), each taken back
        // through joints 3 to 1 (then 4 and 5) by vector turns, never a matrix product.
        let home = rotation * chain.home_rotation.transpose();
        let across6 = super::lines::across(&w6);
        let (axis_goal, across_goal) = (home * w6, home * across6);
        let back = |x: &Vector3<f64>, [t1, t2, t3]: &[Turn; 3]| {
            l3.turn_direction(t3.inverse(), &l2.turn_direction(t2.inverse(), &l1.turn_direction(t1.inverse(), x)))
        };
        let cosine = w4.dot(&w5);
        let normal = w4.cross(&w5);
        let denominator = 1.0 - cosine * cosine;
        for position in positions {
            let [t1, t2, t3] = position;
            let goal = back(&axis_goal, &position);
            let alpha = (goal.dot(&w4) - cosine * w6.dot(&w5)) / denominator;
            let beta = (w6.dot(&w5) - cosine * goal.dot(&w4)) / denominator;
            let squared = (1.0 - alpha * alpha - beta * beta - 2.0 * alpha * beta * cosine) / normal.norm_squared();
            if squared < -1e-12 {
                continue;
            }
            let gamma = squared.max(0.0).sqrt();
            let signs: &[f64] = if gamma == 0.0 { &[1.0] } else { &[1.0, -1.0] };
            let across_back = back(&across_goal, &position);
            for sign in signs {
                let z = w4 * alpha + w5 * beta + normal * (sign * gamma);
                let (Some(t5), Some(t4)) = (turn_about(&w5, &w6, &z, ON_AXIS), turn_about(&w4, &z, &goal, ON_AXIS)) else {
                    // Axis 6 along axis 4: joints 4 and 6 turn about one line.
                    out.resolved = false;
                    continue;
                };
                let moved = l5.turn_direction(t5.inverse(), &l4.turn_direction(t4.inverse(), &across_back));
                let t6 = super::lines::angle_of_moved(&w6, &across6, &moved);
                out.configurations
                    .push([t1.angle, t2.angle, t3.angle, t4.angle, t5.angle, t6].map(super::wrapped));
            }
        }
        out
    }
}

/// How two consecutive axes relate, when they meet or are parallel.
fn pair(a: &super::lines::Line, b: &super::lines::Line) -> Option<Pair> {
    if a.axis.cross(&b.axis).norm() < PARALLEL {
        Some(Pair::Parallel)
    } else {
        crossing(a.point, a.axis, b.point, b.axis).map(Pair::Meet)
    }
}

impl Pair {
    /// What turning about either of two axes so related keeps (`a` the first): the squared
    /// distance from the meeting point, or the height along the axes.
    fn kept(self, a: &super::lines::Line, p: &Vector3<f64>) -> f64 {
        match self {
            Pair::Meet(m) => (p - m).norm_squared(),
            Pair::Parallel => a.axis.dot(&(p - a.point)),
        }
    }

    /// What turning about `a` alone keeps besides: the height along `a` from the meeting point,
    /// or the squared distance from `a`.
    fn other(self, a: &super::lines::Line, p: &Vector3<f64>) -> f64 {
        match self {
            Pair::Meet(m) => a.axis.dot(&(p - m)),
            Pair::Parallel => {
                let v = p - a.point;
                (v - a.axis * a.axis.dot(&v)).norm_squared()
            }
        }
    }
}

/// The angles where `f` (a combination of `{1, sin, cos}`) equals `value`, as turns (with their
/// sines and cosines); `None` when `f` is constant and equal to it (every angle).
pub(crate) fn trig_roots(f: impl Fn(Turn) -> f64, value: f64) -> Option<TrigRoots> {
    let samples = node_turns().map(&f);
    let inverse = super::lines::node_inverse();
    let [a, b, c] = [0, 1, 2].map(|row| (0..3).map(|k| inverse[(row, k)] * samples[k]).sum::<f64>());
    // b sin t + c cos t = r cos(t - phi) = value - a. Scaled lengths: no `hypot` needed.
    let r = (b * b + c * c).sqrt();
    let size = a.abs().max(value.abs()).max(r).max(1e-300);
    let rest = value - a;
    if r <= 1e-12 * size {
        return if rest.abs() <= 1e-12 * size { None } else { Some(TrigRoots::NONE) };
    }
    let ratio = rest / r;
    if ratio.abs() > 1.0 + 1e-12 {
        return Some(TrigRoots::NONE);
    }
    let phi = b.atan2(c);
    let (sin_phi, cos_phi) = (b / r, c / r);
    let cos_spread = ratio.clamp(-1.0, 1.0);
    let spread = cos_spread.acos();
    if spread == 0.0 {
        let turn = Turn {
            angle: phi,
            sin: sin_phi,
            cos: cos_phi,
        };
        return Some(TrigRoots { turns: [turn; 2], len: 1 });
    }
    let sin_spread = (1.0 - cos_spread * cos_spread).sqrt();
    Some(TrigRoots {
        turns: [
            Turn {
                angle: phi + spread,
                sin: sin_phi * cos_spread + cos_phi * sin_spread,
                cos: cos_phi * cos_spread - sin_phi * sin_spread,
            },
            Turn {
                angle: phi - spread,
                sin: sin_phi * cos_spread - cos_phi * sin_spread,
                cos: cos_phi * cos_spread + sin_phi * sin_spread,
            },
        ],
        len: 2,
    })
}

/// [`trig_roots`]'s turns, none to two, without an allocation: the closed forms call it a few
/// times per pose.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrigRoots {
    turns: [Turn; 2],
    len: usize,
}

impl TrigRoots {
    const NONE: TrigRoots = TrigRoots {
        turns: [Turn {
            angle: 0.0,
            sin: 0.0,
            cos: 1.0,
        }; 2],
        len: 0,
    };
}

impl IntoIterator for TrigRoots {
    type Item = Turn;
    type IntoIter = std::iter::Take<std::array::IntoIter<Turn, 2>>;

    fn into_iter(self) -> Self::IntoIter {
        self.turns.into_iter().take(self.len)
    }
}

/// Boxes the branch and bound may evaluate before it gives up.
const MAX_BOXES: usize = 200_000;

/// A lower bound on `f` over the torus of two angles, when it is above `floor`: branch and
/// bound with `f`'s Lipschitz constants per angle; `None` when some box's centre is within
/// `floor` (the bound fails) or the box budget runs out.
fn lower_bound_above(f: &dyn Fn(f64, f64) -> f64, lipschitz: [f64; 2], floor: f64) -> Option<f64> {
    let mut boxes = super::cap::torus_boxes(32);
    let mut bound = f64::INFINITY;
    let mut evaluated = 0;
    while let Some((a, b, h)) = boxes.pop() {
        evaluated += 1;
        if evaluated > MAX_BOXES {
            return None;
        }
        let value = f(a, b);
        if value <= floor {
            return None;
        }
        let low = value - (lipschitz[0] + lipschitz[1]) * h;
        if low > floor {
            bound = bound.min(low);
            continue;
        }
        let quarter = h / 2.0;
        for (da, db) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
            boxes.push((a + da * quarter, b + db * quarter, quarter));
        }
    }
    Some(bound)
}

/// Where the chain's last three axes meet, when they do and no two are parallel.
fn meeting_point(chain: &Chain) -> Option<Vector3<f64>> {
    let [.., l4, l5, l6] = &chain.lines;
    let a = crossing(l4.point, l4.axis, l5.point, l5.axis)?;
    let b = crossing(l5.point, l5.axis, l6.point, l6.axis)?;
    ((a - b).norm() < MEET).then(|| (a + b) / 2.0)
}

/// The point where two non-parallel lines meet, when they do.
fn crossing(p: Vector3<f64>, u: Vector3<f64>, q: Vector3<f64>, v: Vector3<f64>) -> Option<Vector3<f64>> {
    let n = u.cross(&v);
    if n.norm() < PARALLEL {
        return None;
    }
    let w = p - q;
    let b = u.dot(&v);
    let denominator = 1.0 - b * b;
    let s = (b * v.dot(&w) - u.dot(&w)) / denominator;
    let t = (v.dot(&w) - b * u.dot(&w)) / denominator;
    let (on_first, on_second) = (p + u * s, q + v * t);
    ((on_first - on_second).norm() < MEET).then(|| (on_first + on_second) / 2.0)
}

/// The two positioning equations' coefficients, interpolated at three angles per joint.
fn position_coefficients(chain: &Chain, centre: &Vector3<f64>) -> [[f64; 9]; 2] {
    let [l1, l2, l3, ..] = &chain.lines;
    let mut values = [[[0.0; 2]; 3]; 3];
    for (i2, row) in values.iter_mut().enumerate() {
        for (i3, value) in row.iter_mut().enumerate() {
            let point = l2.turn(NODES[i2], &l3.turn(NODES[i3], centre)) - l1.point;
            *value = [point.norm_squared(), l1.axis.dot(&point)];
        }
    }
    interpolate2(&values)
}
