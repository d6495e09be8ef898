//! A 6R arm as its six joint axis lines at `q = 0` and its home tool pose, in product-of-
//! exponentials form (`T(q) = e1(q1) .. e6(q6) M`, `e_i` the turn about line `i`), read from the
//! model's own FK: no DH fit, any joint frames. Lengths are divided by the arm's size about joint
//! 1's origin, so the all-solutions methods see numbers near 1 whatever the units. The reversed
//! chain (`T^-1 = M^-1 e6(-q6) .. e1(-q1)`) is a 6R arm too: a method that needs special
//! structure at the wrist applies it at the base by solving the reversed chain.

use crate::model::{JointKind, KinematicsWorkspace, Model};
use nalgebra::{Isometry3, Matrix3, SMatrix, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Distance and sine of angle (lengths scaled as the chain's) below which two lines are one.
const SAME_LINE: f64 = 1e-9;

/// One joint's axis line: a point on it and its unit direction.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line {
    pub(crate) point: Vector3<f64>,
    pub(crate) axis: Vector3<f64>,
}

impl Line {
    /// The rotation of a turn `angle` about the line's direction.
    pub(crate) fn rotation(&self, angle: f64) -> Matrix3<f64> {
        let (s, c) = angle.sin_cos();
        let k = self.axis.cross_matrix();
        Matrix3::identity() + k * s + k * k * (1.0 - c)
    }

    /// Point `x` turned by `angle` about the line.
    pub(crate) fn turn(&self, angle: f64, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation(angle) * (x - self.point) + self.point
    }

    /// [`Self::rotation`] of the angle whose sine and cosine are given: the closed forms know
    /// them from the geometry that fixed the angle, and a trigonometric call costs more than
    /// the rotation itself. `c I + s [a]x + (1 - c) a a^T`, the same turn without a matrix
    /// product.
    pub(crate) fn rotation_of(&self, turn: Turn) -> Matrix3<f64> {
        let Turn { sin: s, cos: c, .. } = turn;
        let a = &self.axis;
        let t = 1.0 - c;
        let (xy, xz, yz) = (t * a.x * a.y, t * a.x * a.z, t * a.y * a.z);
        Matrix3::new(
            c + t * a.x * a.x,
            xy - s * a.z,
            xz + s * a.y,
            xy + s * a.z,
            c + t * a.y * a.y,
            yz - s * a.x,
            xz - s * a.y,
            yz + s * a.x,
            c + t * a.z * a.z,
        )
    }

    /// Direction `x` turned by `turn` about the line's direction: `c x + s a x x + (1 - c) (a .
    /// x) a`, no matrix built.
    pub(crate) fn turn_direction(&self, turn: Turn, x: &Vector3<f64>) -> Vector3<f64> {
        let a = &self.axis;
        x * turn.cos + a.cross(x) * turn.sin + a * ((1.0 - turn.cos) * a.dot(x))
    }

    /// [`Self::turn`] by a [`Turn`].
    pub(crate) fn turn_by(&self, turn: Turn, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation_of(turn) * (x - self.point) + self.point
    }
}

/// An angle with its sine and cosine, as the closed forms find them (an `atan2`'s arguments,
/// normalised): carried along so that no turn by it calls `sin_cos` again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Turn {
    pub(crate) angle: f64,
    pub(crate) sin: f64,
    pub(crate) cos: f64,
}

impl Turn {
    /// The turn by `angle`.
    pub(crate) fn of(angle: f64) -> Turn {
        let (sin, cos) = angle.sin_cos();
        Turn { angle, sin, cos }
    }

    /// The angle of the direction `(x, y)` (not both zero): `atan2(y, x)` with its sine and
    /// cosine. The closed forms' lengths are scaled near 1: no squares overflow, so no `hypot`
    /// (a tenth of a closed form's time).
    pub(crate) fn towards(y: f64, x: f64) -> Turn {
        let length = (x * x + y * y).sqrt();
        Turn {
            angle: y.atan2(x),
            sin: y / length,
            cos: x / length,
        }
    }

    /// The turn the other way.
    pub(crate) fn inverse(self) -> Turn {
        Turn {
            angle: -self.angle,
            sin: -self.sin,
            cos: self.cos,
        }
    }
}

/// [`NODES`] as turns: their sines and cosines once per process.
pub(crate) fn node_turns() -> [Turn; 3] {
    static TURNS: std::sync::LazyLock<[Turn; 3]> = std::sync::LazyLock::new(|| NODES.map(Turn::of));
    *TURNS
}

/// A 6R chain in product-of-exponentials form, lengths divided by `scale` about `origin`.
#[derive(Debug, Clone)]
pub(crate) struct Chain {
    pub(crate) lines: [Line; 6],
    /// Home tool pose (rotation, translation).
    pub(crate) home_rotation: Matrix3<f64>,
    pub(crate) home_translation: Vector3<f64>,
}

impl Chain {
    /// Whether two consecutive joints turn about one line (within rounding of the scaled
    /// lengths): every pose's solutions then form continua.
    pub(crate) fn has_coaxial_pair(&self) -> bool {
        self.lines.windows(2).any(|pair| {
            let (first, next) = (&pair[0], &pair[1]);
            let offset = next.point - first.point;
            let off_line = (offset - first.axis * first.axis.dot(&offset)).norm();
            first.axis.cross(&next.axis).norm() <= SAME_LINE && off_line <= SAME_LINE
        })
    }

    /// Tool pose (rotation, translation) at `q`.
    pub(crate) fn forward(&self, q: &[f64; 6]) -> (Matrix3<f64>, Vector3<f64>) {
        let mut rotation = self.home_rotation;
        let mut translation = self.home_translation;
        for (line, angle) in self.lines.iter().zip(q).rev() {
            let r = line.rotation(*angle);
            rotation = r * rotation;
            translation = r * (translation - line.point) + line.point;
        }
        (rotation, translation)
    }

    /// How far the chain's pose at `q` is from (`rotation`, `translation`): the larger of the
    /// position error (scaled) and the largest rotation-matrix entry error.
    pub(crate) fn misses(&self, q: &[f64; 6], rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> f64 {
        let (r, t) = self.forward(q);
        let position = (t - translation).norm();
        let angle = (r - rotation).amax();
        if position.is_nan() || angle.is_nan() {
            f64::INFINITY
        } else {
            position.max(angle)
        }
    }

    /// `q` after Newton steps toward the pose (`rotation`, `translation`): the Jacobian by
    /// central differences, five steps at most, each kept only where it lowers the miss; angles
    /// in (-pi, pi].
    pub(crate) fn newton(&self, mut q: [f64; 6], rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> [f64; 6] {
        const STEP: f64 = 1e-6;
        let error = |q: &[f64; 6]| -> nalgebra::Vector6<f64> {
            let (r, t) = self.forward(q);
            let turn = rotation * r.transpose();
            let about = 0.5
                * Vector3::new(
                    turn[(2, 1)] - turn[(1, 2)],
                    turn[(0, 2)] - turn[(2, 0)],
                    turn[(1, 0)] - turn[(0, 1)],
                );
            let position = translation - t;
            nalgebra::Vector6::new(position.x, position.y, position.z, about.x, about.y, about.z)
        };
        for _ in 0..5 {
            let e = error(&q);
            let mut jacobian = nalgebra::Matrix6::zeros();
            for column in 0..6 {
                let (mut ahead, mut behind) = (q, q);
                ahead[column] += STEP;
                behind[column] -= STEP;
                jacobian.set_column(column, &((error(&behind) - error(&ahead)) / (2.0 * STEP)));
            }
            let Some(step) = jacobian.lu().solve(&e) else {
                break;
            };
            let next: [f64; 6] = std::array::from_fn(|i| q[i] + step[i]);
            // A miss is never NaN (infinite instead).
            if self.misses(&next, rotation, translation) >= self.misses(&q, rotation, translation) {
                break;
            }
            q = next;
        }
        q.map(super::wrap_angle)
    }

    /// Joint `joint`'s angle (0-based) given the other five in `q` and the goal rotation.
    pub(crate) fn angle_of(&self, joint: usize, q: &[f64; 6], goal: &Matrix3<f64>) -> f64 {
        let mut before = Matrix3::identity();
        for (line, angle) in self.lines.iter().zip(q).take(joint) {
            before *= line.rotation(*angle);
        }
        let mut after = Matrix3::identity();
        for (line, angle) in self.lines.iter().zip(q).skip(joint + 1) {
            after *= line.rotation(*angle);
        }
        let turn = before.transpose() * goal * self.home_rotation.transpose() * after.transpose();
        axis_angle_of(&self.lines[joint].axis, &turn)
    }
}

/// The angle of `turn` about unit axis `w`, for a rotation that is one about `w`.
fn axis_angle_of(w: &Vector3<f64>, turn: &Matrix3<f64>) -> f64 {
    let v = across(w);
    angle_of_moved(w, &v, &(turn * v))
}

/// A unit vector at right angles to unit `w`: the one [`axis_angle_of`] turns.
pub(crate) fn across(w: &Vector3<f64>) -> Vector3<f64> {
    let helper = if w.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    w.cross(&helper).normalize()
}

/// The angle about unit `w` that takes `v` (at right angles to it) to `moved`.
pub(crate) fn angle_of_moved(w: &Vector3<f64>, v: &Vector3<f64>, moved: &Vector3<f64>) -> f64 {
    w.dot(&v.cross(moved)).atan2(v.dot(moved))
}

/// An arm's chain in both orders, with the scaling that made it.
#[derive(Debug, Clone)]
pub(crate) struct Arm {
    pub(crate) forward: Chain,
    pub(crate) reversed: Chain,
    origin: Vector3<f64>,
    scale: f64,
    /// How far the real tool is from the chain's tool frame (m): 0, except with a joint held
    /// (see [`Arm::holding_last_joint`]), where a tolerance on the real tool lets the chain's
    /// tool frame move by this much times the angle on top.
    pub(crate) tool_lever: f64,
}

impl Arm {
    /// The chains of `model` when it has six revolute joints.
    pub(crate) fn of(model: &Model) -> Option<Arm> {
        if model.dof() != 6 {
            return None;
        }
        Self::with_lines(model)
    }

    /// The chains of a five-joint `model` with a sixth, virtual joint turning the tool about its
    /// own z axis: a `z_symmetric` goal of the five joints is a pose goal of the six (the virtual
    /// angle is the free turn about tool z).
    pub(crate) fn with_virtual_tool_joint(model: &Model) -> Option<Arm> {
        if model.dof() != 5 {
            return None;
        }
        Self::with_lines(model)
    }

    /// The chains of joints 1 to 6 of a 7R `model`, joint 7 held: their tool is a virtual frame
    /// on joint 7's axis (its origin joint 7's, its z the axis), and `offset` is the real tool
    /// in that frame at `q7 = 0`. A turn of joint 7 by `t` turns the virtual frame about its own
    /// z, so the tool is at `V(q1..q6) Rz(t) offset`, and a pose `G` with joint 7 at `t` is the
    /// pose `G offset^-1 Rz(-t)` of the six.
    pub(crate) fn holding_last_joint(model: &Model) -> Option<(Arm, Isometry3<f64>)> {
        if model.dof() != 7 || model.joints.iter().any(|j| j.kind == JointKind::Prismatic) {
            return None;
        }
        let mut ws = model.workspace();
        model.forward(&[0.0; 7], &mut ws);
        let frame = &ws.link_in_world[7];
        let axis = (frame.rotation * model.joints[6].axis.into_inner()).normalize();
        // Any frame with z along the axis will do; antiparallel has no shortest arc.
        let rotation = UnitQuaternion::rotation_between(&Vector3::z(), &axis)
            .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI));
        let virtual_tool = Isometry3::from_parts(frame.translation, rotation);
        let offset = virtual_tool.inverse() * ws.tool_in_world;
        let lever = offset.translation.vector.norm();
        let mut arm = Self::from_frames(model, &ws, virtual_tool)?;
        arm.tool_lever = lever;
        Some((arm, offset))
    }

    /// The axis lines of every joint, and of a virtual one about tool z where only five exist.
    fn with_lines(model: &Model) -> Option<Arm> {
        if model.joints.iter().any(|j| j.kind == JointKind::Prismatic) {
            return None;
        }
        let mut ws = model.workspace();
        model.forward(&vec![0.0; model.dof()], &mut ws);
        let home = ws.tool_in_world;
        Self::from_frames(model, &ws, home)
    }

    /// The lines of joints 1 to 6 in `ws` (FK at `q = 0`), the virtual joint about `home`'s z
    /// where only five exist, with `home` as the tool.
    fn from_frames(model: &Model, ws: &KinematicsWorkspace, home: Isometry3<f64>) -> Option<Arm> {
        let raw: [Line; 6] = std::array::from_fn(|i| match model.joints.get(i) {
            Some(joint) => {
                let frame = &ws.link_in_world[i + 1];
                Line {
                    point: frame.translation.vector,
                    axis: (frame.rotation * joint.axis.into_inner()).normalize(),
                }
            }
            None => Line {
                point: home.translation.vector,
                axis: home.rotation * Vector3::z(),
            },
        });
        let origin = raw[0].point;
        let scale = raw
            .iter()
            .map(|l| (l.point - origin).norm())
            .chain([(home.translation.vector - origin).norm()])
            .fold(0.0, f64::max);
        let scale = if scale.is_finite() && scale > 1e-9 { scale } else { 1.0 };
        let lines = raw.map(|l| Line {
            point: (l.point - origin) / scale,
            axis: l.axis,
        });
        if lines.iter().any(|l| !(l.point.iter().chain(l.axis.iter()).all(|x| x.is_finite()))) {
            return None;
        }
        let home_rotation = home.rotation.to_rotation_matrix().into_inner();
        let home_translation = (home.translation.vector - origin) / scale;
        let forward = Chain {
            lines,
            home_rotation,
            home_translation,
        };
        // The lines carried into the home tool frame, their directions flipped so the angles
        // keep their sign.
        let inverse_rotation = home_rotation.transpose();
        let reversed = Chain {
            lines: std::array::from_fn(|k| {
                let line = &lines[5 - k];
                Line {
                    point: inverse_rotation * (line.point - home_translation),
                    axis: -(inverse_rotation * line.axis),
                }
            }),
            home_rotation: inverse_rotation,
            home_translation: -(inverse_rotation * home_translation),
        };
        Some(Arm {
            forward,
            reversed,
            origin,
            scale,
            tool_lever: 0.0,
        })
    }

    /// The length the chain's coordinates are divided by (m).
    pub(crate) fn scale(&self) -> f64 {
        self.scale
    }

    /// The chain in the given order.
    pub(crate) fn chain(&self, reversed: bool) -> &Chain {
        if reversed {
            &self.reversed
        } else {
            &self.forward
        }
    }

    /// World pose `goal` as the pose (rotation, translation) the chain in the given order must
    /// reach.
    pub(crate) fn goal(&self, goal: &Isometry3<f64>, reversed: bool) -> (Matrix3<f64>, Vector3<f64>) {
        let rotation = goal.rotation.to_rotation_matrix().into_inner();
        let translation = (goal.translation.vector - self.origin) / self.scale;
        if reversed {
            let inverse = rotation.transpose();
            (inverse, -(inverse * translation))
        } else {
            (rotation, translation)
        }
    }
}

/// The angle of the turn about unit `axis` that takes `from` to `to` (their parts across the
/// axis); `None` when either part is shorter than `shortest` (on the axis: any angle).
pub(crate) fn angle_about(axis: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>, shortest: f64) -> Option<f64> {
    turn_about(axis, from, to, shortest).map(|turn| turn.angle)
}

/// [`angle_about`] as a [`Turn`]: the angle with its sine and cosine.
pub(crate) fn turn_about(axis: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>, shortest: f64) -> Option<Turn> {
    let u = from - axis * axis.dot(from);
    let v = to - axis * axis.dot(to);
    if u.norm() < shortest || v.norm() < shortest {
        return None;
    }
    Some(Turn::towards(axis.dot(&u.cross(&v)), u.dot(&v)))
}

/// Interpolation nodes: three angles fix a combination of `{1, sin, cos}` exactly.
pub(crate) const NODES: [f64; 3] = [0.0, 2.0 * PI / 3.0, 4.0 * PI / 3.0];

/// The inverse of the `{1, sin, cos}` values at [`NODES`]: coefficients from node values.
pub(crate) fn node_inverse() -> Matrix3<f64> {
    // Once per process: the closed forms ask for it a few times per pose.
    static INVERSE: std::sync::LazyLock<Matrix3<f64>> = std::sync::LazyLock::new(node_inverse_now);
    *INVERSE
}

fn node_inverse_now() -> Matrix3<f64> {
    let v = Matrix3::from_fn(|i, f| match f {
        0 => 1.0,
        1 => NODES[i].sin(),
        _ => NODES[i].cos(),
    });
    // The nodes are distinct angles: the matrix is regular.
    v.try_inverse().unwrap_or_else(Matrix3::identity)
}

/// Half-angle form of `{1, sin theta, cos theta}` for `theta = offset + t`, times `1 + x^2`
/// with `x = tan(t / 2)`: row `f`, column the power of `x`.
pub(crate) fn half_angle(offset: f64) -> Matrix3<f64> {
    let (s, c) = offset.sin_cos();
    // cos t (1 + x^2) = 1 - x^2, sin t (1 + x^2) = 2x.
    Matrix3::new(1.0, 0.0, 1.0, s, 2.0 * c, -s, c, -2.0 * s, -c)
}

/// The coefficients over `{1, sin a, cos a} x {1, sin b, cos b}` (index `fa * 3 + fb`) of `N`
/// quantities, from their values on the [`NODES`] grid (`values[ia][ib]`): exact when each is
/// such a combination.
pub(crate) fn interpolate2<const N: usize>(values: &[[[f64; N]; 3]; 3]) -> [[f64; 9]; N] {
    let nodes = node_inverse();
    let mut out = [[0.0; 9]; N];
    for (k, quantity) in out.iter_mut().enumerate() {
        for fa in 0..3 {
            for fb in 0..3 {
                let mut sum = 0.0;
                for (ia, row) in values.iter().enumerate() {
                    for (ib, value) in row.iter().enumerate() {
                        sum += nodes[(fa, ia)] * nodes[(fb, ib)] * value[k];
                    }
                }
                quantity[fa * 3 + fb] = sum;
            }
        }
    }
    out
}

/// Largest imaginary part (relative) of an eigenvalue still taken as a real root: a double root
/// (a pose on a workspace boundary) splits into a pair about `sqrt(eps)` off the real line.
const NEAR_REAL: f64 = 1e-4;

/// The near-real roots of `det(c + b x + a x^2)`, ascending: the eigenvalues of its `2 N x 2 N`
/// companion matrix ([`super::eigen`]). `None` when `a` is singular or ill-conditioned (the
/// caller retries with another tangent offset), or when the QR iteration has not converged
/// within `80 N` steps per eigenvalue block (an unbounded iteration can cycle forever on some
/// finite matrices: found on a modular catalog arm).
pub(crate) fn quadratic_roots<const N: usize>(c: &SMatrix<f64, N, N>, b: &SMatrix<f64, N, N>, a: &SMatrix<f64, N, N>) -> Option<Vec<f64>> {
    Some(near_real(&quadratic_eigenvalues(c, b, a)?))
}

/// Whether eigenvalue `re + i im` is within [`NEAR_REAL`] of the real line: a root taken as real.
pub(crate) fn is_near_real(re: f64, im: f64) -> bool {
    re.is_finite() && im.abs() <= NEAR_REAL * (1.0 + re.abs())
}

/// The real parts of the eigenvalues within [`NEAR_REAL`] of the real line, ascending.
pub(crate) fn near_real(eigenvalues: &[(f64, f64)]) -> Vec<f64> {
    let mut roots: Vec<f64> = eigenvalues
        .iter()
        .filter(|&&(re, im)| is_near_real(re, im))
        .map(|&(re, _)| re)
        .collect();
    // Ascending: the solutions' order (and what reports list first) is the roots', not the
    // eigenvalue iteration's.
    roots.sort_by(f64::total_cmp);
    roots
}

/// Every eigenvalue `(re, im)` of the companion matrix of `c + b x + a x^2` (see
/// [`quadratic_roots`], whose conditions it shares).
pub(crate) fn quadratic_eigenvalues<const N: usize>(
    c: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, N>,
    a: &SMatrix<f64, N, N>,
) -> Option<Vec<(f64, f64)>> {
    let inverse = leading_inverse(a)?;
    let (ac, ab) = (inverse * c, inverse * b);
    // Row-major: the identity above right, then -A^-1 C and -A^-1 B.
    let size = 2 * N;
    let mut companion = vec![0.0; size * size];
    for i in 0..N {
        companion[i * size + N + i] = 1.0;
        for j in 0..N {
            companion[(N + i) * size + j] = -ac[(i, j)];
            companion[(N + i) * size + N + j] = -ab[(i, j)];
        }
    }
    if !companion.iter().all(|x| x.is_finite()) {
        return None;
    }
    super::eigen::Hessenberg::new(size, companion).eigenvalues(80 * N)
}

/// The inverse of a matrix quadratic's leading coefficient; `None` when it is singular or its
/// condition number reaches `1e8` (taken from the inverse: cheaper than an SVD).
pub(crate) fn leading_inverse<const N: usize>(a: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    let inverse = a.try_inverse()?;
    let condition = inverse.norm() * a.norm();
    if condition.is_nan() || condition >= 1e8 {
        return None;
    }
    Some(inverse)
}
