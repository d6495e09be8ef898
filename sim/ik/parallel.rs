//! Every solution of a pose of a 6R arm with three consecutive parallel axes (joints 1 to 3 or
//! 2 to 4, or 4 to 6 and 3 to 5 on the reversed chain) where the elimination degenerates, as it
//! does for modular catalog arms off the UR layout.
//!
//! The three parallel joints (direction `u`) make a planar motion `P`: a turn about `u` and a
//! shift across it. Written `T M^-1 = D`, with the block at joints 2 to 4 `P = e1^-1 D e6^-1
//! e5^-1`, and at joints 1 to 3 `P = D e6^-1 e5^-1 e4^-1`. `P` keeps `u` and moves no point
//! along `u`; with the lone joint's turn (joint 1, resp. 6) carrying one direction onto another,
//! both conditions become two equations in the pair of joints left (5 and 6, resp. 4 and 5),
//! each a combination of `{1, sin, cos} x {1, sin, cos}` (read off exactly by interpolation):
//! their common roots (an 8 x 8 resultant, `ik::bilinear`), the lone joint from the direction it must carry,
//! then the planar three joints (two ways at most) from `P`.

use super::bilinear::common_roots;
use super::lines::{angle_about, interpolate2, Arm, Chain, NODES};
use super::solutions::Solutions;
use super::wrist::trig_roots;
use crate::model::Model;
use nalgebra::{Isometry3, Matrix3, Vector3};

/// Sine of the angle below which two axes count as parallel.
const PARALLEL: f64 = 1e-9;
/// A vector shorter than this (scaled) across an axis leaves that joint free: a continuum.
const ON_AXIS: f64 = 1e-9;
/// Pose error (scaled lengths and rad) beyond which a candidate is not a solution.
const CANDIDATE: f64 = 1e-6;

/// The solver of one arm.
#[derive(Debug, Clone)]
pub struct ParallelTriple {
    arm: Arm,
    reversed: bool,
    /// The first parallel joint (0-based): 0 or 1.
    block: usize,
}

impl ParallelTriple {
    /// The solver of `model` when it has six revolute joints, three consecutive of them
    /// parallel, and the method resolves probe poses.
    pub fn detect(model: &Model) -> Option<ParallelTriple> {
        Self::of_arm(Arm::of(model)?)
    }

    /// The solver of a chain's lines (see [`super::lines`]).
    pub(crate) fn of_arm(arm: Arm) -> Option<ParallelTriple> {
        for reversed in [false, true] {
            for block in [1, 0] {
                let lines = &arm.chain(reversed).lines;
                let u = lines[block].axis;
                let parallel = (1..3).all(|k| u.cross(&lines[block + k].axis).norm() < PARALLEL);
                if !parallel {
                    continue;
                }
                let solver = ParallelTriple {
                    arm: arm.clone(),
                    reversed,
                    block,
                };
                if solver.regular() {
                    return Some(solver);
                }
            }
        }
        None
    }

    /// Whether probe poses resolve into verified configurations, the probe's own among them.
    fn regular(&self) -> bool {
        let chain = self.arm.chain(self.reversed);
        let probes = [[0.9, -0.4, 1.3, 2.1, -0.7, 0.5], [-2.3, 1.7, -0.6, -1.2, 2.6, -1.9]];
        probes.iter().all(|probe| {
            let (rotation, translation) = chain.forward(probe);
            let found = self.solve_chain(&rotation, &translation);
            let own = |q: &[f64; 6]| q.iter().zip(probe).all(|(a, b)| super::wrap_angle(a - b).abs() < 1e-6);
            found.resolved && found.configurations.iter().any(own)
        })
    }

    /// Every configuration whose tool frame is at world pose `goal`, unpolished; `resolved` is
    /// false where a root could not be resolved or a joint is free (a continuum).
    pub fn solve(&self, goal: &Isometry3<f64>) -> Solutions {
        let (rotation, translation) = self.arm.goal(goal, self.reversed);
        let mut out = self.solve_chain(&rotation, &translation);
        if self.reversed {
            for q in &mut out.configurations {
                q.reverse();
            }
        }
        out
    }

    fn solve_chain(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Solutions {
        let chain = self.arm.chain(self.reversed);
        let mut out = Solutions {
            resolved: true,
            ..Solutions::default()
        };
        let d = Motion {
            rotation: rotation * chain.home_rotation.transpose(),
            home: chain.home_translation,
            translation: *translation,
        };
        let block = self.block;
        let [pa, pb] = if block == 1 { [4, 5] } else { [3, 4] };
        let mut values = [[[0.0; 2]; 3]; 3];
        for (ia, row) in values.iter_mut().enumerate() {
            for (ib, value) in row.iter_mut().enumerate() {
                *value = self.conditions(chain, &d, NODES[ia], NODES[ib]);
            }
        }
        let equations = interpolate2(&values);
        let Some((pairs, resolved)) = common_roots(&equations) else {
            out.resolved = false;
            return out;
        };
        out.resolved &= resolved;
        for (ta, tb) in pairs {
            let mut q = [0.0; 6];
            q[pa] = ta;
            q[pb] = tb;
            let Some(lone) = self.lone_angle(chain, &d, ta, tb) else {
                out.resolved = false;
                continue;
            };
            let lone_joint = if block == 1 { 0 } else { 5 };
            q[lone_joint] = lone;
            match self.planar(chain, &d, rotation, q) {
                Some(found) => {
                    for q in found {
                        if chain.misses(&q, rotation, translation) < CANDIDATE {
                            out.configurations.push(q.map(super::wrap_angle));
                        } else {
                            out.resolved = false;
                        }
                    }
                }
                None => out.resolved = false,
            }
        }
        out
    }

    /// The two conditions on the pair at angles `ta`, `tb`: the lone joint can carry `u` where
    /// it must go (equal components along its axis), and `P` moves no point along `u`.
    fn conditions(&self, chain: &Chain, d: &Motion, ta: f64, tb: f64) -> [f64; 2] {
        let lines = &chain.lines;
        let u = lines[self.block].axis;
        let c = lines[self.block].point;
        if self.block == 1 {
            // v = R_D R6^T R5^T u must be R1 u; y = D e6^-1 e5^-1 c.
            let (l5, l6, l1) = (&lines[4], &lines[5], &lines[0]);
            let v = d.rotation * (l6.rotation(-tb) * (l5.rotation(-ta) * u));
            let y = d.apply(&l6.turn(-tb, &l5.turn(-ta, &c)));
            [l1.axis.dot(&v) - l1.axis.dot(&u), v.dot(&(y - l1.point)) + u.dot(&(l1.point - c))]
        } else {
            // a = R5^T R4^T u must be R6 R_D^T u; z = e5^-1 e4^-1 c.
            let (l4, l5, l6) = (&lines[3], &lines[4], &lines[5]);
            let a = l5.rotation(-tb) * (l4.rotation(-ta) * u);
            let back = d.rotation.transpose() * u;
            let z = l5.turn(-tb, &l4.turn(-ta, &c));
            [
                l6.axis.dot(&a) - l6.axis.dot(&back),
                a.dot(&(z - l6.point)) + back.dot(&(l6.point - d.home)) + u.dot(&(d.translation - c)),
            ]
        }
    }

    /// The lone joint's angle: the turn carrying `u` where the pair puts it.
    fn lone_angle(&self, chain: &Chain, d: &Motion, ta: f64, tb: f64) -> Option<f64> {
        let lines = &chain.lines;
        let u = lines[self.block].axis;
        if self.block == 1 {
            let v = d.rotation * (lines[5].rotation(-tb) * (lines[4].rotation(-ta) * u));
            angle_about(&lines[0].axis, &u, &v, ON_AXIS)
        } else {
            let a = lines[4].rotation(-tb) * (lines[3].rotation(-ta) * u);
            angle_about(&lines[5].axis, &(d.rotation.transpose() * u), &a, ON_AXIS)
        }
    }

    /// The planar joints for the other three in `q` (up to two ways); `None` where one is free.
    fn planar(&self, chain: &Chain, d: &Motion, rotation: &Matrix3<f64>, q: [f64; 6]) -> Option<Vec<[f64; 6]>> {
        let lines = &chain.lines;
        let k = self.block;
        let (first, second, third) = (&lines[k], &lines[k + 1], &lines[k + 2]);
        // Where the planar motion must put a point of the third parallel axis: the whole chain
        // with the planar joints at zero carries it to `P`'s image through the other joints.
        let target = self.planar_target(chain, d, &q, &third.point);
        let u = first.axis;
        let across = |x: Vector3<f64>| x - u * u.dot(&x);
        let wanted = across(target - first.point).norm_squared();
        let roots = trig_roots(|t| across(second.turn_by(t, &third.point) - first.point).norm_squared(), wanted)?;
        let mut out = Vec::with_capacity(2);
        for t2 in roots {
            let moved = second.turn_by(t2, &third.point);
            let t2 = t2.angle;
            let t1 = angle_about(&u, &(moved - first.point), &(target - first.point), ON_AXIS)?;
            let mut full = q;
            full[k] = t1;
            full[k + 1] = t2;
            full[k + 2] = chain.angle_of(k + 2, &full, rotation);
            out.push(full);
        }
        Some(out)
    }

    /// `P(x)`: for block 2-4 `e1^-1 D e6^-1 e5^-1 x`, for block 1-3 `D e6^-1 e5^-1 e4^-1 x`.
    fn planar_target(&self, chain: &Chain, d: &Motion, q: &[f64; 6], x: &Vector3<f64>) -> Vector3<f64> {
        let lines = &chain.lines;
        let mut point = *x;
        for joint in self.block + 3..6 {
            point = lines[joint].turn(-q[joint], &point);
        }
        point = d.apply(&point);
        for joint in (0..self.block).rev() {
            point = lines[joint].turn(-q[joint], &point);
        }
        point
    }
}

/// `D = T M^-1` as a map of points: `x -> rotation (x - home) + translation`.
struct Motion {
    rotation: Matrix3<f64>,
    home: Vector3<f64>,
    translation: Vector3<f64>,
}

impl Motion {
    fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * (x - self.home) + self.translation
    }
}
