//! The batch an objective evaluates: designs of one degree-of-freedom count and one capsule
//! structure, each with the same goals and starts; and the standard-DH forward kinematics both
//! backends share where they need f64 frames (the linearised obstacles without a closed form).

use super::OptimizeError;
use crate::collide::{self, CapsuleModel, CapsuleOther, CollisionWorld};
use crate::design::Design;
use crate::scenario::{Scenario, Tolerance};
use nalgebra::{Isometry3, Matrix3, Rotation3, Vector3};
use rayon::prelude::*;

/// Where a capsule's segment lies on its link, as a function of the link's DH row `(d, a)`
/// (see `model::from_design`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CapsuleKind {
    /// From the link origin to `(0, 0, d)`.
    D,
    /// From `(0, 0, d)` to `(a, 0, d)`.
    A,
    /// The sphere at the link origin of a row with `d = a = 0`.
    Point,
}

impl CapsuleKind {
    /// Segment ends in the link frame for the row `(d, a)` (m).
    pub fn ends(self, d: f64, a: f64) -> (Vector3<f64>, Vector3<f64>) {
        match self {
            Self::D => (Vector3::zeros(), Vector3::new(0.0, 0.0, d)),
            Self::A => (Vector3::new(0.0, 0.0, d), Vector3::new(a, 0.0, d)),
            Self::Point => (Vector3::zeros(), Vector3::zeros()),
        }
    }
}

/// A goal as the objective sees it.
#[derive(Debug, Clone)]
pub struct Target {
    /// Goal position in the world (m).
    pub position: Vector3<f64>,
    /// Goal orientation in the world.
    pub rotation: Matrix3<f64>,
    /// How the orientation counts.
    pub tolerance: Tolerance,
}

/// The constant part of one design: twists and the fixed poses around the chain.
#[derive(Debug, Clone)]
pub struct DesignFrame {
    /// `alpha` per DH row (rad); discrete, never optimized.
    pub alpha: Vec<f64>,
    /// Pose of frame 0 in the world (the scenario's base times the design's base).
    pub world_from_base: Isometry3<f64>,
    /// The design's tool offset after the last DH row.
    pub tool: Isometry3<f64>,
}

/// The variables: joint positions per sample and the continuous DH parameters per design.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Joint positions, `samples x dof`, row-major (rad).
    pub q: Vec<f64>,
    /// DH `d` per design, `designs x dof` (m).
    pub d: Vec<f64>,
    /// DH `a` per design, `designs x dof` (m).
    pub a: Vec<f64>,
}

/// What an objective returns for a batch: the paper's terms per sample, and the gradients of
/// each sample's own loss `w_d d + w_col c_col`.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Pose distance `d` per sample (m, rotation weighted by `w_r`).
    pub distance: Vec<f64>,
    /// Collision cost `c_col` per sample.
    pub collision: Vec<f64>,
    /// d(loss of sample b) / dq of sample b, `samples x dof`.
    pub grad_q: Vec<f64>,
    /// d(loss of sample b) / d(d of its design), `samples x dof`.
    pub grad_d: Vec<f64>,
    /// d(loss of sample b) / d(a of its design), `samples x dof`.
    pub grad_a: Vec<f64>,
}

impl Evaluation {
    /// `w_d d + w_col c_col` of sample `b`.
    pub fn loss(&self, b: usize) -> f64 {
        crate::ik::LossTerms {
            distance: self.distance[b],
            collision: self.collision[b],
        }
        .weighted()
    }
}

/// One sample: a design and a goal (the start is its row of [`Params::q`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sample {
    /// Index into [`Batch::designs`].
    pub design: usize,
    /// Index into [`Batch::targets`].
    pub goal: usize,
}

/// Everything constant over an optimization.
#[derive(Clone)]
pub struct Batch {
    /// Joints per design.
    pub dof: usize,
    /// Per design.
    pub designs: Vec<DesignFrame>,
    /// Per goal of the scenario.
    pub targets: Vec<Target>,
    /// Per sample.
    pub samples: Vec<Sample>,
    /// Per capsule: its link (1..=dof) and how its ends follow the link's DH row.
    pub capsules: Vec<(usize, CapsuleKind)>,
    /// The capsule model's pairs, in the order the CPU path measures them.
    pub(crate) model: CapsuleModel,
    /// The first design's collision world: the pair lists and the obstacles without a closed form.
    pub world: std::sync::Arc<CollisionWorld>,
}

impl Batch {
    /// The batch of `designs` (one dof count, one capsule structure) on `scenario`, `samples`
    /// in the order of the rows of [`Params::q`].
    ///
    /// # Errors
    /// [`OptimizeError::Batch`] for designs of different dof counts or capsule structures,
    /// [`OptimizeError::Pipeline`] when the collision world cannot be built.
    pub fn new(designs: &[Design], scenario: &Scenario, samples: Vec<Sample>) -> Result<Self, OptimizeError> {
        let first = designs.first().ok_or_else(|| OptimizeError::Batch("no design".into()))?;
        let model = crate::model::from_design(first).placed(&scenario.world_from_base);
        let world = crate::pipeline::collision_world(&model, scenario, &[]).map_err(Box::new)?;
        let capsule_model = collide::capsule_model(&world);
        let capsules = capsule_kinds(first, &capsule_model)?;
        // Each design's structure is checked on its own (in parallel); the first misfit in
        // design order is reported, whatever the thread count.
        let checks: Vec<Result<(), OptimizeError>> = designs
            .par_iter()
            .map(|design| {
                if design.dof() != first.dof() {
                    return Err(OptimizeError::Batch(format!(
                        "design `{}` has {} joints, `{}` {}: a batch holds one dof count",
                        design.name,
                        design.dof(),
                        first.name,
                        first.dof()
                    )));
                }
                let other = crate::model::from_design(design).placed(&scenario.world_from_base);
                let other_world = crate::pipeline::collision_world(&other, scenario, &[]).map_err(Box::new)?;
                let other_model = collide::capsule_model(&other_world);
                if capsule_kinds(design, &other_model)? != capsules || !same_pairs(&other_model, &capsule_model) {
                    return Err(OptimizeError::Batch(format!(
                        "design `{}` has another capsule structure than `{}` (zero offsets or checked pairs differ)",
                        design.name, first.name
                    )));
                }
                Ok(())
            })
            .collect();
        checks.into_iter().collect::<Result<(), _>>()?;
        if let Some(bad) = samples.iter().find(|s| s.design >= designs.len() || s.goal >= scenario.goals.len()) {
            return Err(OptimizeError::Batch(format!("sample {bad:?} names no design or goal")));
        }
        Ok(Self {
            dof: first.dof(),
            designs: designs
                .iter()
                .map(|design| DesignFrame {
                    alpha: design.joints.iter().map(|j| j.alpha).collect(),
                    world_from_base: scenario.world_from_base * design.base.isometry(),
                    tool: design.tool.isometry(),
                })
                .collect(),
            targets: scenario
                .goals
                .iter()
                .map(|goal| Target {
                    position: goal.position,
                    rotation: goal.rotation.to_rotation_matrix().into_inner(),
                    tolerance: goal.tolerance,
                })
                .collect(),
            samples,
            capsules,
            model: capsule_model,
            world: std::sync::Arc::new(world),
        })
    }

    /// The DH `(d, a)` rows of design `design` in `params`.
    pub fn rows<'p>(&self, params: &'p Params, design: usize) -> (&'p [f64], &'p [f64]) {
        let range = design * self.dof..(design + 1) * self.dof;
        (&params.d[range.clone()], &params.a[range])
    }

    /// The joint positions of sample `b` in `params`.
    pub fn q<'p>(&self, params: &'p Params, b: usize) -> &'p [f64] {
        &params.q[b * self.dof..(b + 1) * self.dof]
    }
}

fn same_pairs(a: &CapsuleModel, b: &CapsuleModel) -> bool {
    a.pair_count == b.pair_count
        && a.candidates.len() == b.candidates.len()
        && a.candidates.iter().zip(&b.candidates).all(|(x, y)| {
            x.0 == y.0
                && x.1 == y.1
                && match (x.2, y.2) {
                    (CapsuleOther::Capsule(i), CapsuleOther::Capsule(j)) | (CapsuleOther::Shape(i), CapsuleOther::Shape(j)) => i == j,
                    (CapsuleOther::Rounded { .. }, CapsuleOther::Rounded { .. }) | (CapsuleOther::Floor(_), CapsuleOther::Floor(_)) => true,
                    _ => false,
                }
        })
}

/// Which segment of its link's DH row each capsule of the design's model is.
fn capsule_kinds(design: &Design, model: &CapsuleModel) -> Result<Vec<(usize, CapsuleKind)>, OptimizeError> {
    model
        .capsules
        .iter()
        .map(|&(link, start, end)| {
            let row = link
                .checked_sub(1)
                .and_then(|r| design.joints.get(r))
                .ok_or_else(|| OptimizeError::Batch(format!("capsule on link {link} has no DH row")))?;
            [CapsuleKind::D, CapsuleKind::A, CapsuleKind::Point]
                .into_iter()
                .find(|kind| kind.ends(row.d, row.a) == (start, end))
                .map(|kind| (link, kind))
                .ok_or_else(|| OptimizeError::Batch(format!("capsule on link {link} is not a segment of its DH row")))
        })
        .collect()
}

/// World frames of one sample: `links[k]` = (rotation, origin) of link `k` (0 the base), and
/// the tool's.
#[derive(Debug, Clone)]
pub struct Frames {
    /// Link frames, base first.
    pub links: Vec<(Matrix3<f64>, Vector3<f64>)>,
    /// Tool frame.
    pub tool: (Matrix3<f64>, Vector3<f64>),
}

/// `Rot_x(alpha)` as a matrix.
pub(super) fn rot_x(alpha: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), alpha).into_inner()
}

/// Standard-DH forward kinematics: link `k + 1 = k * Trans_z(d_k) Trans_x(a_k) Rot_x(alpha_k)
/// Rot_z(q_{k+1})`, link 1 = base * `Rot_z(q_1)`.
pub fn forward(frame: &DesignFrame, d: &[f64], a: &[f64], q: &[f64]) -> Frames {
    let mut links = Vec::with_capacity(q.len() + 1);
    let base = (
        frame.world_from_base.rotation.to_rotation_matrix().into_inner(),
        frame.world_from_base.translation.vector,
    );
    links.push(base);
    let (mut rotation, mut origin) = base;
    for (k, &qk) in q.iter().enumerate() {
        if k > 0 {
            origin += rotation.column(0) * a[k - 1] + rotation.column(2) * d[k - 1];
            rotation *= rot_x(frame.alpha[k - 1]);
        }
        rotation *= Rotation3::from_axis_angle(&Vector3::z_axis(), qk).into_inner();
        links.push((rotation, origin));
    }
    let n = q.len();
    let last = origin + rotation.column(0) * a[n - 1] + rotation.column(2) * d[n - 1];
    let last_rotation = rotation * rot_x(frame.alpha[n - 1]);
    let tool = (
        last_rotation * frame.tool.rotation.to_rotation_matrix().into_inner(),
        last + last_rotation * frame.tool.translation.vector,
    );
    Frames { links, tool }
}

/// A capsule's measured closest point and normal against an obstacle without a closed form:
/// the objective takes the distance as the plane through the witness, `d0 - n . (c - c0)`,
/// exact in value and first derivative at the point measured.
#[derive(Debug, Clone, Copy)]
pub struct Witness {
    /// Measured signed distance (m).
    pub distance: f64,
    /// Unit normal from the capsule to the obstacle.
    pub normal: Vector3<f64>,
    /// The closest point's parameter on the capsule's segment, in [0, 1].
    pub along: f64,
    /// That point of the axis in the world (m).
    pub centre: Vector3<f64>,
}

/// Witnesses of every `Shape` candidate of sample `b`, candidate order (`None` elsewhere).
pub fn shape_witnesses(batch: &Batch, params: &Params, b: usize, frames: &Frames) -> Vec<Option<Witness>> {
    let design = batch.samples[b].design;
    let (d, a) = batch.rows(params, design);
    batch
        .model
        .candidates
        .iter()
        .map(|&(_, capsule, other)| {
            let CapsuleOther::Shape(obstacle) = other else { return None };
            let (link, kind) = batch.capsules[capsule];
            let (start, end) = kind.ends(d[link - 1], a[link - 1]);
            let (rotation, origin) = frames.links[link];
            let pose = Isometry3::from_parts(
                origin.into(),
                nalgebra::UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rotation)),
            );
            let closest = collide::capsule_shape_distance(&batch.world, obstacle, &pose, start, end);
            let centre = closest.point_a - closest.normal * crate::model::PAPER_CAPSULE_RADIUS_M;
            let (start_w, end_w) = (rotation * start + origin, rotation * end + origin);
            let axis = end_w - start_w;
            let length2 = axis.norm_squared();
            let along = if length2 > 0.0 {
                ((centre - start_w).dot(&axis) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            Some(Witness {
                distance: closest.distance,
                normal: closest.normal,
                along,
                centre: start_w + axis * along,
            })
        })
        .collect()
}
