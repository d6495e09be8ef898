//! The rotation-matrix form of FK + Jacobian behind [`Model::tool_jacobian`], with one kernel per
//! joint chosen once from the exact zeros of its fixed rotation.
//!
//! Every kernel performs the same floating-point operations, in the same order, as the general
//! 3x3 products of nalgebra (`((a0 b0 + a1 b1) + a2 b2)` per entry) minus the terms whose factor
//! is an exact zero of the fixed rotation. Dropping `x * 0` from a sum leaves every non-zero
//! result bit-identical; only the sign of an entry that is exactly zero may differ.

use super::{JointKind, Model};
use nalgebra::{Matrix3, Matrix6xX, Vector3};

/// Column-major 3x3, `m[column][row]` (the layout of `nalgebra::Matrix3`).
type Mat = [[f64; 3]; 3];
type Vec3 = [f64; 3];

/// `m v` in nalgebra's order of summation.
#[inline(always)]
fn mat_vec(m: &Mat, v: &Vec3) -> Vec3 {
    std::array::from_fn(|r| (m[0][r] * v[0] + m[1][r] * v[1]) + m[2][r] * v[2])
}

#[inline(always)]
fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    [mat_vec(a, &b[0]), mat_vec(a, &b[1]), mat_vec(a, &b[2])]
}

#[inline(always)]
fn add(a: &Vec3, b: &Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
fn scale(a: &Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn mat(m: &Matrix3<f64>) -> Mat {
    std::array::from_fn(|c| std::array::from_fn(|r| m[(r, c)]))
}

/// The orders of [`Fixed::Permutation`], matching the kernels of [`Fixed::apply`].
const PERMUTATIONS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];

/// Columns `A`, `B`, `C` of `p` scaled by `factor`.
#[inline(always)]
fn permuted<const A: usize, const B: usize, const C: usize>(p: &Mat, factor: &[f64; 3]) -> Mat {
    [scale(&p[A], factor[0]), scale(&p[B], factor[1]), scale(&p[C], factor[2])]
}

/// `parent * F` for the fixed rotation `F` of a joint, by its pattern of exact zeros.
#[derive(Debug, Clone, Copy)]
enum Fixed {
    /// `F` is exactly the identity (the first DH joint, URDF joints without rpy).
    Identity,
    /// A rotation about x (DH alpha): column 0 is `(xx, 0, 0)`, columns 1 and 2 have a zero x.
    AboutX {
        xx: f64,
        yy: f64,
        zy: f64,
        yz: f64,
        zz: f64,
    },
    /// One non-zero entry per column (URDF rpy in multiples of pi/2): column `c` is column
    /// `PERMUTATIONS[order][c]` of the parent times `factor[c]`.
    Permutation {
        order: usize,
        factor: [f64; 3],
    },
    General(Mat),
}

impl Fixed {
    fn new(f: &Mat) -> Self {
        let nonzero = |c: usize| (0..3).filter(|&r| f[c][r] != 0.0).collect::<Vec<_>>();
        let columns = [nonzero(0), nonzero(1), nonzero(2)];
        if (0..3).all(|c| columns[c] == [c] && f[c][c] == 1.0) {
            Fixed::Identity
        } else if columns[0] == [0] && columns[1].iter().chain(&columns[2]).all(|&r| r != 0) {
            Fixed::AboutX {
                xx: f[0][0],
                yy: f[1][1],
                zy: f[1][2],
                yz: f[2][1],
                zz: f[2][2],
            }
        } else if let Some(order) = PERMUTATIONS.iter().position(|p| (0..3).all(|c| columns[c] == [p[c]])) {
            Fixed::Permutation {
                order,
                factor: std::array::from_fn(|c| f[c][PERMUTATIONS[order][c]]),
            }
        } else {
            Fixed::General(*f)
        }
    }

    #[inline(always)]
    fn apply(&self, p: &Mat) -> Mat {
        match self {
            Fixed::Identity => *p,
            Fixed::AboutX { xx, yy, zy, yz, zz } => [
                scale(&p[0], *xx),
                add(&scale(&p[1], *yy), &scale(&p[2], *zy)),
                add(&scale(&p[1], *yz), &scale(&p[2], *zz)),
            ],
            // Indexing the parent's columns by a runtime number would move the whole chain's
            // rotation from registers to the stack (measured 92 -> 155 ns), so each order is
            // its own kernel.
            Fixed::Permutation { order, factor } => match order {
                0 => permuted::<0, 1, 2>(p, factor),
                1 => permuted::<0, 2, 1>(p, factor),
                2 => permuted::<1, 0, 2>(p, factor),
                3 => permuted::<1, 2, 0>(p, factor),
                4 => permuted::<2, 0, 1>(p, factor),
                _ => permuted::<2, 1, 0>(p, factor),
            },
            Fixed::General(f) => mat_mul(p, f),
        }
    }
}

/// `R v` for a constant `v`, by which of its entries are exact zeros (DH offsets are `(a, 0, d)`,
/// often with `a` or `d` zero too).
#[derive(Debug, Clone, Copy)]
struct Offset {
    v: Vec3,
    nonzero: [bool; 3],
}

impl Offset {
    fn new(v: &Vec3) -> Self {
        Offset {
            v: *v,
            nonzero: v.map(|x| x != 0.0),
        }
    }

    /// `position + R v`, one kernel per pattern of zeros.
    #[inline(always)]
    fn moved(&self, position: &Vec3, r: &Mat) -> Vec3 {
        let v = &self.v;
        let product = match self.nonzero {
            [false, false, false] => return *position,
            [true, false, false] => scale(&r[0], v[0]),
            [false, true, false] => scale(&r[1], v[1]),
            [false, false, true] => scale(&r[2], v[2]),
            [true, true, false] => add(&scale(&r[0], v[0]), &scale(&r[1], v[1])),
            [true, false, true] => add(&scale(&r[0], v[0]), &scale(&r[2], v[2])),
            [false, true, true] => add(&scale(&r[1], v[1]), &scale(&r[2], v[2])),
            [true, true, true] => mat_vec(r, v),
        };
        add(position, &product)
    }
}

/// What the joint variable does after the fixed rotation.
#[derive(Debug, Clone, Copy)]
enum Motion {
    /// Revolute about the joint frame's z (every DH joint): `G Rot_z(q)` mixes two columns.
    AboutZ(Fixed),
    /// Revolute about another axis, by Rodrigues: `F Rot(axis, q) = F + sin F K + (1 - cos) F K^2`
    /// with `K` the cross-product matrix of the axis.
    Revolute {
        fixed: Mat,
        fixed_k: Mat,
        fixed_k2: Mat,
        axis_in_parent: Vec3,
    },
    Prismatic {
        fixed: Fixed,
        axis: Vec3,
        axis_in_parent: Vec3,
    },
}

#[derive(Debug, Clone, Copy)]
struct Step {
    offset: Offset,
    motion: Motion,
}

/// Per-joint kernels of one model and the scratch of one evaluation.
#[derive(Debug, Clone)]
pub(super) struct FastChain {
    steps: Vec<Step>,
    base_rotation: Mat,
    base_offset: Vec3,
    tool_rotation: Fixed,
    tool_offset: Offset,
    /// `(sin, cos)` of every joint variable, taken before the chain.
    sin_cos: Vec<(f64, f64)>,
    /// World position and axis of every joint.
    joint_position: Vec<Vec3>,
    joint_axis: Vec<Vec3>,
}

impl FastChain {
    pub(super) fn new(model: &Model) -> Self {
        let steps = model
            .joints
            .iter()
            .map(|joint| {
                let fixed = mat(joint.parent_from_joint.rotation.to_rotation_matrix().matrix());
                let axis = joint.axis.into_inner();
                let axis_in_parent = mat_vec(&fixed, &axis.into());
                let motion = match joint.kind {
                    JointKind::Prismatic => Motion::Prismatic {
                        fixed: Fixed::new(&fixed),
                        axis: axis.into(),
                        axis_in_parent,
                    },
                    _ if axis == Vector3::z() => Motion::AboutZ(Fixed::new(&fixed)),
                    _ => {
                        let f = Matrix3::from(fixed);
                        let k = axis.cross_matrix();
                        Motion::Revolute {
                            fixed,
                            fixed_k: mat(&(f * k)),
                            fixed_k2: mat(&(f * k * k)),
                            axis_in_parent,
                        }
                    }
                };
                Step {
                    offset: Offset::new(&joint.parent_from_joint.translation.vector.into()),
                    motion,
                }
            })
            .collect();
        FastChain {
            steps,
            base_rotation: mat(model.world_from_base.rotation.to_rotation_matrix().matrix()),
            base_offset: model.world_from_base.translation.vector.into(),
            tool_rotation: Fixed::new(&mat(model.last_from_tool.rotation.to_rotation_matrix().matrix())),
            tool_offset: Offset::new(&model.last_from_tool.translation.vector.into()),
            sin_cos: vec![(0.0, 0.0); model.dof()],
            joint_position: vec![[0.0; 3]; model.dof()],
            joint_axis: vec![[0.0; 3]; model.dof()],
        }
    }

    /// Tool position and rotation at `q`, and the Jacobian into `jacobian`.
    ///
    /// # Panics
    /// When `q` or `jacobian` does not have one entry or column per joint of the chain.
    pub(super) fn evaluate(&mut self, q: &[f64], jacobian: &mut Matrix6xX<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        let dof = self.steps.len();
        assert!(q.len() == dof && jacobian.ncols() == dof, "workspace made for another model");
        super::trig::sin_cos_all(q, &mut self.sin_cos);
        let mut rotation = self.base_rotation;
        let mut position = self.base_offset;
        for ((((step, &qi), &(sin, cos)), joint_position), joint_axis) in self
            .steps
            .iter()
            .zip(q)
            .zip(&self.sin_cos)
            .zip(&mut self.joint_position)
            .zip(&mut self.joint_axis)
        {
            position = step.offset.moved(&position, &rotation);
            let parent = rotation;
            match &step.motion {
                Motion::AboutZ(fixed) => {
                    let g = fixed.apply(&parent);
                    let (x, y) = (g[0], g[1]);
                    rotation = [
                        add(&scale(&x, cos), &scale(&y, sin)),
                        std::array::from_fn(|r| y[r] * cos - x[r] * sin),
                        g[2],
                    ];
                    *joint_axis = g[2];
                }
                Motion::Revolute {
                    fixed,
                    fixed_k,
                    fixed_k2,
                    axis_in_parent,
                } => {
                    let versine = 1.0 - cos;
                    let local: Mat =
                        std::array::from_fn(|c| std::array::from_fn(|r| (fixed[c][r] + fixed_k[c][r] * sin) + fixed_k2[c][r] * versine));
                    rotation = mat_mul(&parent, &local);
                    *joint_axis = mat_vec(&parent, axis_in_parent);
                }
                Motion::Prismatic {
                    fixed,
                    axis,
                    axis_in_parent,
                } => {
                    rotation = fixed.apply(&parent);
                    position = add(&position, &mat_vec(&rotation, &scale(axis, qi)));
                    *joint_axis = mat_vec(&parent, axis_in_parent);
                }
            }
            *joint_position = position;
        }
        let tool_position = self.tool_offset.moved(&position, &rotation);
        let tool_rotation = self.tool_rotation.apply(&rotation);
        let columns = jacobian.as_mut_slice().chunks_exact_mut(6);
        for (((column, step), axis), joint_position) in columns.zip(&self.steps).zip(&self.joint_axis).zip(&self.joint_position) {
            let [ax, ay, az] = *axis;
            if let Motion::Prismatic { .. } = step.motion {
                column.copy_from_slice(&[ax, ay, az, 0.0, 0.0, 0.0]);
            } else {
                let [bx, by, bz] = [
                    tool_position[0] - joint_position[0],
                    tool_position[1] - joint_position[1],
                    tool_position[2] - joint_position[2],
                ];
                column.copy_from_slice(&[ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx, ax, ay, az]);
            }
        }
        (tool_position.into(), Matrix3::from(tool_rotation))
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::{JointKind, Model};
    use crate::design;
    use crate::model::from_design;
    use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};
    use rand::{Rng, SeedableRng};
    use std::path::Path;

    /// A rotation given by exact quaternion components, so that its matrix has exact zeros.
    fn exact(w: f64, i: f64, j: f64, k: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::new_unchecked(Quaternion::new(w, i, j, k))
    }

    /// Models covering every kernel: DH joints (identity and alpha-only fixed rotations), 7 dof,
    /// and a chain of permutation, general and half-turn fixed rotations with revolute joints
    /// about z and about other axes and prismatic joints.
    pub(crate) fn kernel_models() -> Vec<Model> {
        let dh = r#"{"mode": "free", "base": {"position": [0.1, 0.2, 0.3], "rpy": [0.1, -0.2, 0.3]},
            "tool": {"position": [0.0, 0.05, 0.1], "rpy": [0.4, 0.0, -0.3]}, "joints": [
            {"d": 0.3, "a": 0.1, "alpha": 1.2}, {"d": -0.2, "a": 0.4, "alpha": -0.4},
            {"d": 0.0, "a": 0.0, "alpha": 0.7}, {"d": 0.15, "a": -0.3, "alpha": 0.0}]}"#;
        let load = |text: &str| from_design(&design::parse(text, Path::new("t.json")).expect("valid"));
        let redundant = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("designs/free-redundant-7dof.json"))
            .expect("shipped design");
        let mut mixed = load(&redundant);
        let general = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
        let half = std::f64::consts::FRAC_1_SQRT_2;
        let rotations = [
            exact(0.5, 0.5, 0.5, 0.5),
            general,
            exact(0.0, 1.0, 0.0, 0.0),
            general,
            exact(0.5, -0.5, 0.5, -0.5),
            exact(half, 0.0, 0.0, half),
            exact(0.0, 0.0, 0.0, 1.0),
        ];
        let axes = [
            Vector3::z(),
            Vector3::new(0.3, -0.5, 0.8),
            Vector3::x(),
            Vector3::new(0.0, 0.6, -0.8),
            Vector3::y(),
            Vector3::z(),
            Vector3::z(),
        ];
        let kinds = [0, 0, 1, 1, 0, 0, 0].map(|p| if p == 1 { JointKind::Prismatic } else { JointKind::Revolute });
        for (((joint, rotation), axis), kind) in mixed.joints.iter_mut().zip(rotations).zip(axes).zip(kinds) {
            joint.parent_from_joint.rotation = rotation;
            joint.axis = Unit::new_normalize(axis);
            joint.kind = kind;
            if kind == JointKind::Prismatic {
                joint.limits = Some([-0.2, 0.3]);
            }
        }
        vec![load(dh), load(&redundant), mixed]
    }

    /// Random configurations, and ones at quadrant boundaries where entries become exact zeros.
    pub(crate) fn configurations(model: &Model) -> Vec<Vec<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut all: Vec<Vec<f64>> = (0..200).map(|_| model.random_configuration(&mut rng)).collect();
        for _ in 0..50 {
            let quarter = std::f64::consts::FRAC_PI_2;
            all.push((0..model.dof()).map(|_| f64::from(rng.random_range(-4..=4)) * quarter).collect());
        }
        all.push(vec![0.0; model.dof()]);
        all
    }

    /// The matrix form as it was before the per-joint kernels (full nalgebra products).
    fn reference(model: &Model, q: &[f64]) -> (Isometry3<f64>, nalgebra::Matrix6xX<f64>) {
        let m = |r: &UnitQuaternion<f64>| *r.to_rotation_matrix().matrix();
        let mut rotation = m(&model.world_from_base.rotation);
        let mut position = model.world_from_base.translation.vector;
        let (mut points, mut axes) = (vec![], vec![]);
        for (joint, &qi) in model.joints.iter().zip(q) {
            let fixed = m(&joint.parent_from_joint.rotation);
            let axis = joint.axis.into_inner();
            position += rotation * joint.parent_from_joint.translation.vector;
            let parent = rotation;
            let revolute = joint.kind != JointKind::Prismatic;
            if revolute && axis == Vector3::z() {
                let (sin, cos) = super::super::trig::sin_cos(qi);
                let g = parent * fixed;
                let (x, y) = (g.column(0).into_owned(), g.column(1).into_owned());
                rotation = g;
                rotation.set_column(0, &(x * cos + y * sin));
                rotation.set_column(1, &(y * cos - x * sin));
                axes.push(g.column(2).into_owned());
            } else if revolute {
                let (sin, cos) = super::super::trig::sin_cos(qi);
                let k = axis.cross_matrix();
                rotation = parent * (fixed + (fixed * k) * sin + (fixed * k * k) * (1.0 - cos));
                axes.push(parent * (fixed * axis));
            } else {
                rotation = parent * fixed;
                position += rotation * (axis * qi);
                axes.push(parent * (fixed * axis));
            }
            points.push(position);
        }
        let tool = position + rotation * model.last_from_tool.translation.vector;
        let mut jacobian = nalgebra::Matrix6xX::zeros(model.dof());
        for (i, joint) in model.joints.iter().enumerate() {
            let mut column = jacobian.column_mut(i);
            if joint.kind == JointKind::Prismatic {
                column.fixed_rows_mut::<3>(0).copy_from(&axes[i]);
            } else {
                column.fixed_rows_mut::<3>(0).copy_from(&axes[i].cross(&(tool - points[i])));
                column.fixed_rows_mut::<3>(3).copy_from(&axes[i]);
            }
        }
        let rotation: Matrix3<f64> = rotation * m(&model.last_from_tool.rotation);
        let pose = Isometry3::from_parts(
            Translation3::from(tool),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation)),
        );
        (pose, jacobian)
    }

    /// Bit patterns equal: on these chains not even the sign of a zero changes, though dropping
    /// `x * 0` terms could flip it in principle.
    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits()
    }

    #[test]
    fn kernels_reproduce_the_full_products_bit_for_bit() {
        for model in kernel_models() {
            let mut ws = model.workspace();
            for q in configurations(&model) {
                model.tool_jacobian(&q, &mut ws);
                let (pose, jacobian) = reference(&model, &q);
                let ours = ws
                    .tool_in_world
                    .translation
                    .vector
                    .iter()
                    .chain(ws.tool_in_world.rotation.coords.iter());
                let theirs = pose.translation.vector.iter().chain(pose.rotation.coords.iter());
                assert!(ours.zip(theirs).all(|(a, b)| same(*a, *b)), "{} {q:?}", model.name);
                assert!(
                    ws.jacobian.iter().zip(jacobian.iter()).all(|(a, b)| same(*a, *b)),
                    "{} {q:?}",
                    model.name
                );
            }
        }
    }

    #[test]
    fn every_kernel_is_exercised() {
        let chains: Vec<_> = kernel_models().iter().map(super::FastChain::new).collect();
        let kinds = format!("{chains:?}");
        for kernel in ["Identity", "AboutX", "Permutation", "General", "Revolute {", "Prismatic"] {
            assert!(kinds.contains(kernel), "{kernel} not covered");
        }
    }
}
