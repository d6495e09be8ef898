//! Branch-aware restarts: from one solution of a 6R arm, starts on the other branches of the same
//! pose (elbow, wrist and shoulder flips), for the numeric solver to refine on the true arm.
//!
//! Random starts find the branches whose basins are large; the others (a UR5 has 8 solutions per
//! pose, 4 random starts found 3.0 of its 7.5 on average) need starts placed on them. The flips
//! are built from the solution's own joint axes, not from a fitted model, so they apply to any 6R
//! arm; they are exact where the arm has the structure they assume and good starts near it:
//!
//! - elbow: joints 2 and 3 parallel. The elbow is mirrored across the line from joint 2 to the
//!   wrist point (where axes 4 and 5 cross), which stays put; when axis 4 is parallel too, joint 4
//!   takes back the turn about the common axis so the orientation stays (exact for UR-type and
//!   spherical-wrist arms).
//! - wrist: joint 5 is mirrored about its angle where axes 4 and 6 are parallel and joints 4 and
//!   6 turn half a turn (`Rz(a) Ry(b) Rz(c) = Rz(a + pi) Ry(-b) Rz(c + pi)`): the same orientation
//!   whenever axes 4, 5 and 6 are mutually perpendicular. A wrist offset (UR's `d5`) moves the
//!   tool; joints 2 to 4 move it back by the planar solve below (exact for UR-type arms).
//! - shoulder: joint 1 turns so that the wrist point lies in the mirrored arm plane (exact when
//!   axis 2 is perpendicular to axis 1), and joints 2 and 3 bring the wrist point back, both
//!   elbows. The wrist orientation is left to the solver.

use crate::model::{JointKind, KinematicsWorkspace, Model};
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Sine of the angle below which two axes count as parallel (or lines as crossing-free); only
/// decides which construction is tried, the solver refines either way.
const PARALLEL: f64 = 1e-6;
/// Lengths below which the planar sub-problem degenerates (m).
const MIN_LENGTH_M: f64 = 1e-9;

/// Whether branch restarts apply to `model`: six revolute joints (a 6R arm has finitely many
/// solutions per pose; with fewer or more joints, or a prismatic one, the flips mean nothing).
pub(crate) fn applies(model: &Model) -> bool {
    model.dof() == 6 && model.joints.iter().all(|j| j.kind != JointKind::Prismatic)
}

/// Joint axis lines of `model` at the configuration last passed to `forward`: a point on each
/// axis and its world direction.
fn axes(model: &Model, ws: &KinematicsWorkspace) -> [(Vector3<f64>, Vector3<f64>); 6] {
    std::array::from_fn(|i| {
        let frame = &ws.link_in_world[i + 1];
        (frame.translation.vector, frame.rotation * model.joints[i].axis.into_inner())
    })
}

/// Point of line `(p, u)` closest to line `(q, v)` (unit directions); `p` when they are parallel.
fn closest_on_first(p: &Vector3<f64>, u: &Vector3<f64>, q: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    let w = p - q;
    let b = u.dot(v);
    let denominator = 1.0 - b * b;
    if denominator < PARALLEL * PARALLEL {
        return *p;
    }
    p + u * ((b * v.dot(&w) - u.dot(&w)) / denominator)
}

/// The wrist point: where axes 4 and 5 cross (the wrist centre of a spherical wrist; for a
/// UR-type arm the point that moves with joints 1 to 3 only, in the arm plane up to `d4`).
fn wrist_point(axes: &[(Vector3<f64>, Vector3<f64>); 6]) -> Vector3<f64> {
    let ((p4, w4), (p5, w5)) = (axes[3], axes[4]);
    closest_on_first(&p4, &w4, &p5, &w5)
}

/// Signed angle from `a` to `b` about unit `n`, both projected onto the plane normal to `n`.
fn angle_about(n: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    n.dot(&a.cross(b)).atan2(a.dot(b) - n.dot(a) * n.dot(b))
}

/// Both solutions (elbow signs) of joints 2 and 3 that put the wrist point of `q` at `target`,
/// solved in the plane normal to axis 2 (the out-of-plane part of `target` is ignored); when
/// axis 4 is parallel to axis 2, joint 4 keeps the distal links' orientation, so they translate.
/// Empty when the plane problem degenerates.
fn planar(model: &Model, ws: &mut KinematicsWorkspace, q: &[f64], target: &Vector3<f64>) -> Vec<Vec<f64>> {
    model.forward(q, ws);
    let axes = axes(model, ws);
    let ((shoulder, n), (elbow, w3), (_, w4)) = (axes[1], axes[2], axes[3]);
    let wrist = wrist_point(&axes);
    let in_plane = |x: Vector3<f64>| {
        let v = x - shoulder;
        v - n * n.dot(&v)
    };
    let (e, w, t) = (in_plane(elbow), in_plane(wrist), in_plane(*target));
    let (upper, fore, reach) = (e.norm(), (w - e).norm(), t.norm());
    if upper < MIN_LENGTH_M || fore < MIN_LENGTH_M || reach < MIN_LENGTH_M {
        return Vec::new();
    }
    // Out of reach: the stretched or folded arm is the nearest start.
    let cosine = ((upper * upper + reach * reach - fore * fore) / (2.0 * upper * reach)).clamp(-1.0, 1.0);
    let opening = cosine.acos();
    let toward = |a: &Vector3<f64>, b: &Vector3<f64>| angle_about(&n, a, b);
    let rotate = |v: &Vector3<f64>, angle: f64| nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(n), angle) * v;
    let parallel4 = w4.cross(&n).norm() < PARALLEL;
    let mut out = Vec::with_capacity(2);
    for side in [1.0, -1.0] {
        // Joint 2 turns the elbow onto the circle's intersection, joint 3 the wrist onto the target.
        let to_target = toward(&e, &t);
        let turn2 = to_target + side * opening;
        let (elbow_moved, wrist_moved) = (rotate(&e, turn2), rotate(&w, turn2));
        let turn3 = toward(&(wrist_moved - elbow_moved), &(t - elbow_moved));
        let mut next = q.to_vec();
        next[1] += turn2;
        next[2] += turn3 * w3.dot(&n).signum();
        if parallel4 {
            next[3] -= (turn2 + turn3) * w4.dot(&n).signum();
        }
        for value in next.iter_mut() {
            *value = super::wrap_angle(*value);
        }
        out.push(next);
    }
    out
}

/// Starts on the other branches of solution `q` (see the module documentation): the elbow flip,
/// the wrist flip with both elbows, the shoulder flip with both elbows unless `shoulder_known`
/// says a solution with the flipped joint 1 angle is already known (where the shoulder flip is
/// exact its branch is then found, and its own elbow and wrist flips cover the rest).
/// `tool_position` is the goal's (m, world). Some may coincide with `q` or with each other; the
/// caller removes known ones.
pub(crate) fn flips(
    model: &Model,
    ws: &mut KinematicsWorkspace,
    q: &[f64],
    tool_position: &Vector3<f64>,
    shoulder_known: &dyn Fn(f64) -> bool,
) -> Vec<Vec<f64>> {
    let mut starts = Vec::with_capacity(5);
    model.forward(q, ws);
    let axes = axes(model, ws);
    let wrist = wrist_point(&axes);

    // Elbow: of the two planar solutions reaching the wrist point, the one further from q.
    let elbows = planar(model, ws, q, &wrist);
    if let Some(other) = elbows.into_iter().max_by(|a, b| {
        let moved = |c: &[f64]| super::wrap_angle(c[1] - q[1]).abs();
        moved(a).total_cmp(&moved(b))
    }) {
        starts.push(other);
    }

    // Wrist: the angle of joint 5 where axis 6 is parallel to axis 4 is the mirror.
    let ((_, w4), (_, w5), (_, w6)) = (axes[3], axes[4], axes[5]);
    let to_parallel = angle_about(&w5, &w6, &w4);
    let mut wrist_flipped = q.to_vec();
    wrist_flipped[3] = super::wrap_angle(q[3] + PI);
    wrist_flipped[4] = super::wrap_angle(q[4] + 2.0 * to_parallel);
    wrist_flipped[5] = super::wrap_angle(q[5] + PI);
    model.forward(&wrist_flipped, ws);
    let drift = tool_position - ws.tool_in_world.translation.vector;
    let moved = wrist_point(&self::axes(model, ws)) + drift;
    starts.extend(planar(model, ws, &wrist_flipped, &moved));

    // Shoulder: mirror axis 2's direction across the wrist point's direction about axis 1.
    let ((_, w1), (_, w2)) = (axes[0], axes[1]);
    let centre = closest_on_first(&axes[4].0, &w5, &axes[5].0, &w6);
    let turn1 = 2.0 * angle_about(&w1, &w2, &(centre - axes[0].0));
    let mut shoulder_flipped = q.to_vec();
    shoulder_flipped[0] = super::wrap_angle(q[0] + turn1);
    if !shoulder_known(shoulder_flipped[0]) {
        starts.extend(planar(model, ws, &shoulder_flipped, &wrist));
    }
    starts
}
