//! The hand-written backend: the same objective as [`super::tensor`] in plain f64, one sample at a
//! time, with gradients from the geometric Jacobian (an independent oracle for the tensors, and
//! the speed reference of `benches/optimize.rs`).
//!
//! Each distance's gradient is `n . (v_b - v_a)`, `v` the velocity of the closest point of each
//! axis as a variable moves, `n` the unit normal from `a` to `b`: the closest points may be held
//! fixed on their bodies while they move (the envelope theorem), so only rigid motion counts: a
//! joint turns the point about its axis, a row's `d` and `a` move every later link along the
//! row's z and x axes, and the point's own row stretches its segment.

use super::problem::{forward, shape_witnesses, Batch, CapsuleKind, Evaluation, Frames, Params};
use super::{Objective, OptimizeError};
use crate::collide::{capsule_floor, capsules, CapsuleOther};
use crate::ik::{COLLISION_THRESHOLD_M, COLLISION_WEIGHT, DISTANCE_WEIGHT, ROTATION_WEIGHT};
use crate::model::PAPER_CAPSULE_RADIUS_M;
use crate::scenario::Tolerance;
use nalgebra::Vector3;

/// The f64 backend; stateless.
#[derive(Debug, Clone, Copy, Default)]
pub struct Analytic;

impl Objective for Analytic {
    fn evaluate(&mut self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
        let n = batch.dof;
        let count = batch.samples.len();
        let mut out = Evaluation {
            distance: vec![0.0; count],
            collision: vec![0.0; count],
            grad_q: vec![0.0; count * n],
            grad_d: vec![0.0; count * n],
            grad_a: vec![0.0; count * n],
        };
        for b in 0..count {
            let range = b * n..(b + 1) * n;
            let mut gradient = Gradient {
                q: &mut out.grad_q[range.clone()],
                d: &mut out.grad_d[range.clone()],
                a: &mut out.grad_a[range],
            };
            let (distance, collision) = sample(batch, params, b, &mut gradient);
            out.distance[b] = distance;
            out.collision[b] = collision;
        }
        Ok(out)
    }
}

/// The gradient rows of one sample.
struct Gradient<'a> {
    q: &'a mut [f64],
    d: &'a mut [f64],
    a: &'a mut [f64],
}

impl Gradient<'_> {
    /// Adds `weight . v` for every variable, `v` the velocity of the world point `point` fixed
    /// on link `link` after rows `1..rows` (each moves it rigidly), plus `own`: its own row
    /// stretching it (a capsule's segment kind and the point's parameter along it).
    fn add_point(
        &mut self,
        frames: &Frames,
        link: usize,
        rows: usize,
        point: &Vector3<f64>,
        own: Option<(CapsuleKind, f64)>,
        weight: &Vector3<f64>,
    ) {
        for j in 1..=link {
            let (rotation, origin) = &frames.links[j];
            self.q[j - 1] += weight.dot(&rotation.column(2).cross(&(point - origin)));
        }
        for m in 1..=rows {
            let rotation = &frames.links[m].0;
            self.d[m - 1] += weight.dot(&rotation.column(2));
            self.a[m - 1] += weight.dot(&rotation.column(0));
        }
        if let Some((kind, along)) = own {
            let rotation = &frames.links[link].0;
            match kind {
                CapsuleKind::D => self.d[link - 1] += along * weight.dot(&rotation.column(2)),
                CapsuleKind::A => {
                    self.d[link - 1] += weight.dot(&rotation.column(2));
                    self.a[link - 1] += along * weight.dot(&rotation.column(0));
                }
                CapsuleKind::Point => {}
            }
        }
    }
}

/// The parameter of `point` along `start`..`end` (0 for a point segment).
fn along(point: &Vector3<f64>, start: &Vector3<f64>, end: &Vector3<f64>) -> f64 {
    let axis = end - start;
    let length2 = axis.norm_squared();
    if length2 > 0.0 {
        ((point - start).dot(&axis) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// One measured capsule pair: distance, the closest axis points and the normal from `a` to `b`.
struct Contact {
    distance: f64,
    centre_a: Vector3<f64>,
    centre_b: Vector3<f64>,
    normal: Vector3<f64>,
}

/// `(d, c_col)` of sample `b`, adding the gradient of `w_d d + w_col c_col` to `gradient`.
fn sample(batch: &Batch, params: &Params, b: usize, gradient: &mut Gradient) -> (f64, f64) {
    let n = batch.dof;
    let design = batch.samples[b].design;
    let target = &batch.targets[batch.samples[b].goal];
    let (d, a) = batch.rows(params, design);
    let frames = forward(&batch.designs[design], d, a, batch.q(params, b));
    let (tool_rotation, tool_origin) = frames.tool;

    // Pose distance.
    let error = tool_origin - target.position;
    let position = super::beyond_dead_zone(error.norm());
    if position > 0.0 {
        gradient.add_point(&frames, n, n, &tool_origin, None, &(error * (DISTANCE_WEIGHT / position)));
    }
    let (rotation, turn) = match target.tolerance {
        Tolerance::Pose => {
            let m = target.rotation.transpose() * tool_rotation;
            let v = Vector3::new(m[(2, 1)] - m[(1, 2)], m[(0, 2)] - m[(2, 0)], m[(1, 0)] - m[(0, 1)]);
            let angle = super::beyond_dead_zone((v.norm() / 2.0).atan2((m.trace() - 1.0) / 2.0));
            let length = v.norm();
            // d angle = axis . omega, the axis of R R_g^T in the world.
            let axis = if angle > 0.0 && length > 0.0 {
                target.rotation * v / length
            } else {
                Vector3::zeros()
            };
            (angle, axis)
        }
        Tolerance::ZSymmetric => {
            let (tool_z, goal_z) = (tool_rotation.column(2).into_owned(), target.rotation.column(2).into_owned());
            ((1.0 - goal_z.dot(&tool_z)) / 2.0, -0.5 * tool_z.cross(&goal_z))
        }
        Tolerance::Position => (0.0, Vector3::zeros()),
    };
    for j in 1..=n {
        gradient.q[j - 1] += DISTANCE_WEIGHT * ROTATION_WEIGHT * turn.dot(&frames.links[j].0.column(2));
    }

    // Collision cost: the closest candidate of each checked pair.
    let radius = PAPER_CAPSULE_RADIUS_M;
    let world_ends = |capsule: usize| {
        let (link, kind) = batch.capsules[capsule];
        let (start, end) = kind.ends(d[link - 1], a[link - 1]);
        let (rotation, origin) = &frames.links[link];
        (rotation * start + origin, rotation * end + origin)
    };
    let witnesses = shape_witnesses(batch, params, b, &frames);
    let mut best: Vec<Option<(usize, Contact)>> = (0..batch.model.pair_count).map(|_| None).collect();
    for (index, &(pair, capsule, other)) in batch.model.candidates.iter().enumerate() {
        let (start, end) = world_ends(capsule);
        let contact = match other {
            CapsuleOther::Capsule(j) => {
                let (other_start, other_end) = world_ends(j);
                segment_contact(capsules(start, end, radius, other_start, other_end, radius), radius, radius)
            }
            CapsuleOther::Rounded {
                start: s,
                end: e,
                radius: r,
            } => segment_contact(capsules(start, end, radius, s, e, r), radius, r),
            CapsuleOther::Floor(height) => {
                let closest = capsule_floor(start, end, radius, height);
                Contact {
                    distance: closest.distance,
                    centre_a: closest.point_a + Vector3::z() * radius,
                    centre_b: closest.point_b,
                    normal: closest.normal,
                }
            }
            CapsuleOther::Shape(_) => {
                let witness = witnesses[index].expect("a witness per shape candidate");
                Contact {
                    distance: witness.distance,
                    centre_a: witness.centre,
                    centre_b: witness.centre,
                    normal: witness.normal,
                }
            }
        };
        let slot = &mut best[pair];
        if slot.as_ref().is_none_or(|(_, kept)| contact.distance < kept.distance) {
            *slot = Some((index, contact));
        }
    }
    let scale = 1.0 / (1.0 - (-1.0f64).exp());
    let mut collision = 0.0;
    for (index, contact) in best.into_iter().flatten() {
        if contact.distance > COLLISION_THRESHOLD_M {
            continue;
        }
        let exp = (-contact.distance / COLLISION_THRESHOLD_M).exp();
        collision += scale * (exp - (-1.0f64).exp());
        let slope = COLLISION_WEIGHT * scale * -exp / COLLISION_THRESHOLD_M;
        let (_, capsule, other) = batch.model.candidates[index];
        // d distance = n . (v_b - v_a).
        let (link, kind) = batch.capsules[capsule];
        let (start, end) = world_ends(capsule);
        let own = Some((kind, along(&contact.centre_a, &start, &end)));
        gradient.add_point(&frames, link, link - 1, &contact.centre_a, own, &(-slope * contact.normal));
        if let CapsuleOther::Capsule(j) = other {
            let (link_b, kind_b) = batch.capsules[j];
            let (start_b, end_b) = world_ends(j);
            let own_b = Some((kind_b, along(&contact.centre_b, &start_b, &end_b)));
            gradient.add_point(&frames, link_b, link_b - 1, &contact.centre_b, own_b, &(slope * contact.normal));
        }
    }
    (position + ROTATION_WEIGHT * rotation, collision)
}

/// The closest axis points of two capsules from their surface witnesses. Where the axes meet
/// (segments joined through a link with `d = a = 0` do, whatever the joints) the normal is
/// arbitrary and the distance has no gradient: closer than [`super::gaps::MEET_M`] the normal
/// is zero, as in the tensors.
fn segment_contact(closest: crate::collide::Closest, radius_a: f64, radius_b: f64) -> Contact {
    let centre_a = closest.point_a - closest.normal * radius_a;
    let centre_b = closest.point_b + closest.normal * radius_b;
    let length = (centre_b - centre_a).norm();
    Contact {
        distance: closest.distance,
        centre_a,
        centre_b,
        normal: if length < super::gaps::MEET_M {
            Vector3::zeros()
        } else {
            closest.normal
        },
    }
}
