//! Every solution of a pose of any 6R arm: the Raghavan–Roth elimination (Manocha & Canny's
//! matrix form) written on the joint axis lines, so it needs no DH fit.
//!
//! The arm is its six axis lines at `q = 0` (a point `c_i` and direction `w_i` each, read from the
//! model's own FK) and its home tool pose `M`: `T(q) = e1(q1) .. e6(q6) M` with `e_i` the turn
//! about line `i`. Rearranged, `e3 e4 e5 = e2^-1 e1^-1 T M^-1 e6^-1`; both sides map a point and
//! the direction of axis 6 alike, and `e6` fixes both. From the point `p` (taken from a point of
//! axis 3) and the direction `l` the fourteen quantities `p, l, p.p, p.l, p x l,
//! (p.p) l - 2 (p.l) p` are, on the left, combinations of `{1, s3, c3} x {1, s4, c4} x {1, s5, c5}`
//! and, on the right, of `{1, s1, c1} x {1, s2, c2}` (the quadratic terms cancel; see
//! `tests/general_ik.rs`). Their coefficients are read off exactly by interpolating each side at
//! three angles per joint, so the same code serves every arm. Eliminating the eight products of
//! joints 1 and 2 leaves six equations in joints 3 to 5; with half-angle tangents and one more
//! multiple they are a 12 x 12 matrix quadratic in `x3 = tan(theta3 / 2)` whose determinant
//! vanishes at each solution: a 24 x 24 companion eigenproblem (16 roots at most are real
//! solutions; eight are always `x3 = +-i`). Each real root gives joints 4 and 5 from the
//! matrix's null vector, joints 1 and 2 from the eliminated products, joint 6 from the pose.
//!
//! When the elimination degenerates for an arm (special geometry: the products of joints 1 and 2
//! are dependent, or the determinant vanishes identically) the reversed chain is tried, which
//! eliminates joint 1 instead of joint 6; an arm for which both degenerate gets `None`, and its
//! pose goals stay with the numeric solver.

use super::deflate::Deflation;
use super::lines::{half_angle, interpolate2, is_near_real, near_real, node_inverse, quadratic_eigenvalues, Arm, Chain, NODES};
use crate::model::Model;
use crate::scenario::Goal;
use nalgebra::{Complex, Isometry3, Matrix3, SMatrix, SVector, Translation3, UnitQuaternion, Vector3};
use std::sync::OnceLock;

/// The fourteen Raghavan–Roth quantities of a point `p` and a direction `l`.
fn fourteen(p: &Vector3<f64>, l: &Vector3<f64>) -> [f64; 14] {
    let pp = p.dot(p);
    let pl = p.dot(l);
    let cross = p.cross(l);
    let last = l * pp - p * (2.0 * pl);
    [
        p.x, p.y, p.z, l.x, l.y, l.z, pp, pl, cross.x, cross.y, cross.z, last.x, last.y, last.z,
    ]
}

/// Offsets of the half-angle tangents (rad): a solution at `offset + pi` would be at infinity, so
/// the offsets are angles no design chooses on purpose.
const OFFSETS: [f64; 3] = [0.713_281_0, -1.302_717_5, 2.218_919_3];
/// Joint 3's offsets in the order tried: the first, then others where its leading matrix is
/// near singular or a root near infinity.
const OFFSETS3: [f64; 4] = [OFFSETS[0], -0.411_734_9, 1.577_102_6, -2.650_381_7];
/// Configurations whose poses probe an elimination: for its regularity, and for the subspace
/// its deflation takes out.
const PROBES: [[f64; 6]; 2] = [[0.9, -0.4, 1.3, 2.1, -0.7, 0.5], [-2.3, 1.7, -0.6, -1.2, 2.6, -1.9]];

/// Pose error (scaled lengths and rad) beyond which a fast candidate is recomputed by the SVD.
const CANDIDATE: f64 = 1e-6;
/// Tangents beyond this (joint 3 within about 2 degrees of the offset's half turn) are retried
/// with another offset.
const LARGE_ROOT: f64 = 50.0;
/// Step of the pose (m, rad) for the roots' rates of change in an out-of-reach proof.
const POSE_STEP: f64 = 1e-6;
/// A root's match after a step must be this many times nearer than the next root.
const MATCH_MARGIN: f64 = 8.0;
/// Distance (rad) within which roots are copies of one multiple root split by rounding (a
/// four-fold root splits by about the fourth root of the machine epsilon times its scale).
const CLUSTER: f64 = 1e-3;
/// How much a multiple root's split may grow over a step and still be rounding's, as a factor
/// and a floor (rad): one that is the pose's splits by the square root of the step or more.
const SPLIT_GROWTH: f64 = 10.0;
/// How many times its first-order motion over a region a followed root may have moved at a
/// probe of the region (see [`General6R::roots_stay_off`]).
const LINEAR: f64 = 2.0;
/// The least distance (rad) a root may have moved at a probe: rounding's, at most.
const LINEAR_FLOOR: f64 = 1e-6;
const ROUNDING_SPREAD: f64 = 1e-7;
/// Imaginary part (rad) of a root's angle beyond which it is the formulation's own (joint 3's
/// tangent at +-i, to rounding: the determinant's factor that is no solution) and moves no
/// solution: a true root that far off would need a turn of its angle the tolerance cannot give.
const FAR_FROM_REAL: f64 = 8.0;
/// Imaginary part (rad) below which a root counts as real: a solution, no out-of-reach proof.
const REAL_ROOT: f64 = 1e-6;
/// How many times its first-order motion over the tolerance a root must stay off the real
/// angles: where two roots approach a fold their distance falls as the square root of the
/// pose's, which first order underestimates twice; four keeps a margin of two on that.
const FACTOR: f64 = 4.0;
/// Metres per radian weighing a rotation offset against a position one when the tolerance is
/// cut into parts (which offset is halved, never what is proven): the roots move with the
/// tool's rotation about as much as with its position times the arm's size. Measured on
/// `paper-real-world`'s workspace goal 39: 1 044 parts at 0.03 m, 56 at 0.3 m, 48 at 0.5 and
/// 1 m.
const PARTS_LEVER_M: f64 = 0.5;
/// `|w^T Q'(x0) v|` (unit null vectors) relative to `|Q'(x0)|` at or below which a root counts
/// as double: its first-order rate is not defined.
const DOUBLE_ROOT: f64 = 1e-9;
/// The poses beside the edges at which an out-of-reach proof solves the roots again: a sweep's
/// and a validation's (see [`General6R::out_of_reach_checked`]).
const SWEEP_CHECKS: Checks = Checks {
    turns: 0,
    corners: 1,
    steps: 2,
    tight: 0.5,
};
const VALIDATION_CHECKS: Checks = Checks {
    turns: 32,
    corners: 4,
    steps: 4,
    tight: 0.0,
};
/// A part's (see [`General6R::out_of_reach_in_parts`], a validation's only): its two corners
/// nearest to failing beside its twelve faces.
const PART_CHECKS: Checks = Checks {
    turns: 0,
    corners: 2,
    steps: 2,
    tight: 0.0,
};
/// Ratio of smallest to largest singular value below which a matrix counts as singular.
const SINGULAR: f64 = 1e-10;
/// Ratio of the second smallest to the largest singular value at or below which a root's
/// matrix has two null vectors (two solutions share joint 3's angle): a double root's second
/// is of the matrix's own size, two roots one to rounding (1e-7) leave it about that small.
const SHARED_NULL: f64 = 1e-5;
/// Pose error (as [`CANDIDATE`]) within which a configuration at a shared root is polished by
/// Newton steps, to within [`CANDIDATE`] or no pair: the null vectors of a matrix with two are
/// only as precise as the two roots are one (measured on a wrist spherical to 25 um: 5e-6 for
/// a pair 8e-8 apart, 1.5e-4 for one 1e-7 apart).
const SHARED_MISS: f64 = 1e-2;
/// The 2 x 2 minors, the largest first, whose combinations a shared root's pair is sought in.
const SHARED_FORMS: usize = 6;
/// Joint difference (rad) within which two configurations are one solution: what the pipeline
/// merges as copies (`IkOptions::distinct_tolerance`'s default), so two roots never stand for
/// one listed solution.
const SHARED_DISTINCT: f64 = 1e-3;

/// The first joints (0-based) of the three consecutive joints an elimination keeps, in the
/// order tried: 2 is Raghavan and Roth's own (joints 3 to 5 kept, joint 6's line carried, joints
/// 1 and 2 eliminated); 1 keeps joints 2 to 4, carries joint 5's line and eliminates 1 and 6; 0
/// keeps joints 1 to 3, carries joint 4's line and eliminates 5 and 6. The goal only ever enters
/// the eliminated side, so the kept side's table is the arm's own. Arms whose special geometry
/// (parallel or meeting axes, as in most modular arms) makes one choice degenerate often suit
/// another.
const BLOCKS: [usize; 3] = [2, 1, 0];

/// The two joints eliminated by the products for a block, in increasing order.
fn eliminated(block: usize) -> [usize; 2] {
    match block {
        2 => [0, 1],
        1 => [0, 5],
        _ => [4, 5],
    }
}

/// The poses about a goal over which [`General6R::roots_stay_off`] bounds its roots' motion: a
/// ball (`turn` more about tool z), or a box of offsets (see
/// [`General6R::out_of_reach_over_box`]).
#[derive(Debug, Clone, Copy)]
enum Region {
    Ball { radii: super::search::Radii, turn: f64 },
    Box { half: [f64; 6], local: bool },
}

impl Region {
    /// Whether its rotation offsets are about the goal's own axes (a ball's always are).
    fn local(self) -> bool {
        match self {
            Region::Ball { .. } => true,
            Region::Box { local, .. } => local,
        }
    }
}

/// Poses of a region's boundary beside its edges at which [`General6R::roots_stay_off`] solves
/// the roots again: `turns` turns of the whole rotation about axes spread over the sphere (a
/// ball's), and the corners of the region that the `corners` roots nearest to failing point
/// to by their first-order rates (the whole shift and the whole turn along which first order
/// brings each nearest the real angles, together). On 600 arms (`examples/proof_audit.rs`,
/// seed 0) three first-order proofs the exact solver refutes were refuted only where the
/// shift and the turn were both near their whole; one corner refuses all three and no other.
#[derive(Debug, Clone, Copy)]
struct Checks {
    turns: usize,
    corners: usize,
    /// Corners visited per root at most (see [`General6R::worst_corner_holds`]).
    steps: usize,
    /// The share of its allowed motion (a quarter of its distance from the real angles) a
    /// root's first-order motion must use for its corners to be searched: 0 searches them
    /// whatever it is.
    tight: f64,
}

/// A root of the determinant as joint 3's complex angle `(re, im)`, and whether
/// [`General6R::solve`] takes it as a solution (near the real line).
#[derive(Debug, Clone, Copy)]
struct Root {
    angle: (f64, f64),
    /// Joint 3's half-angle tangent at the offset used, `(re, im)`.
    tangent: (f64, f64),
    solution: bool,
}

/// A multiple root (or a simple one) followed by an out-of-reach proof: its size, centroid,
/// spread and distance from the real angles, and its first root's index.
struct Followed {
    count: usize,
    centre: (f64, f64),
    spread: f64,
    off_real: f64,
    first: usize,
}

/// A pose's roots (see [`General6R::angles`]) with the system and the matrix quadratic (at
/// offset `OFFSETS3[index]`) they are the roots of.
struct Angles {
    index: usize,
    roots: Vec<Root>,
    system: System,
    quadratic: Quadratic,
}

/// How a simple root `x0` of `det(C + B x + A x^2)` moves with the matrices: with `v` and `w`
/// the right and left null vectors of `Q(x0)`, `dx = -w^T dQ(x0) v / w^T Q'(x0) v` (first-order
/// perturbation of a simple eigenvalue).
struct Perturbation {
    x0: Complex<f64>,
    right: [Complex<f64>; 12],
    left: [Complex<f64>; 12],
    denominator: Complex<f64>,
}

impl Perturbation {
    /// `None` where a null vector breaks down or the root is double to rounding (no rate).
    fn of(quadratic: &Quadratic, tangent: (f64, f64)) -> Option<Perturbation> {
        let x0 = Complex::new(tangent.0, tangent.1);
        let [c, b, a] = quadratic;
        let at = ComplexLu::new(std::array::from_fn(|i| {
            std::array::from_fn(|j| x0 * (x0 * a[(i, j)] + b[(i, j)]) + c[(i, j)])
        }))?;
        let right = at.null_vector(false)?;
        let left = at.null_vector(true)?;
        let derivative = |i: usize, j: usize| x0 * (2.0 * a[(i, j)]) + b[(i, j)];
        let denominator = bilinear(&left, derivative, &right);
        let scale = (0..144).map(|k| derivative(k / 12, k % 12).norm_sqr()).sum::<f64>().sqrt();
        // False for NaN too.
        let simple = denominator.norm() > DOUBLE_ROOT * scale;
        simple.then_some(Perturbation {
            x0,
            right,
            left,
            denominator,
        })
    }

    /// The root's joint angle's rate of change (complex) as the matrix quadratic changes at
    /// `delta` per unit.
    fn angle_rate(&self, delta: &Quadratic) -> Complex<f64> {
        let [dc, db, da] = delta;
        let x0 = self.x0;
        let dx = -bilinear(&self.left, |i, j| x0 * (x0 * da[(i, j)] + db[(i, j)]) + dc[(i, j)], &self.right) / self.denominator;
        // theta = offset + 2 atan(x).
        dx * 2.0 / (x0 * x0 + 1.0)
    }
}

/// `w^T M v` (no conjugation) for `M` given entry by entry.
fn bilinear(w: &[Complex<f64>; 12], m: impl Fn(usize, usize) -> Complex<f64>, v: &[Complex<f64>; 12]) -> Complex<f64> {
    let mut sum = Complex::new(0.0, 0.0);
    for (i, wi) in w.iter().enumerate() {
        let mut row = Complex::new(0.0, 0.0);
        for (j, vj) in v.iter().enumerate() {
            row += m(i, j) * vj;
        }
        sum += wi * row;
    }
    sum
}

/// A complex 12 x 12 LU with row pivoting (`P M = L U`), which solves with the matrix and its
/// transpose: the right and left null vectors of a matrix singular to rounding from one
/// factorization.
struct ComplexLu {
    lu: [[Complex<f64>; 12]; 12],
    /// Row `i` of `P M` is row `rows[i]` of `M`.
    rows: [usize; 12],
}

impl ComplexLu {
    /// `None` for a matrix that is not finite.
    fn new(mut lu: [[Complex<f64>; 12]; 12]) -> Option<ComplexLu> {
        let scale = lu.iter().flatten().map(|z| z.norm()).fold(0.0, f64::max);
        if !(scale.is_finite() && scale > 0.0) {
            return None;
        }
        let mut rows: [usize; 12] = std::array::from_fn(|i| i);
        for k in 0..12 {
            let pivot = (k..12)
                .max_by(|&a, &b| lu[a][k].norm_sqr().total_cmp(&lu[b][k].norm_sqr()))
                .unwrap_or(k);
            lu.swap(k, pivot);
            rows.swap(k, pivot);
            // An exact zero pivot (a singular matrix, as asked) becomes a rounding-sized one:
            // inverse iteration only needs the factors near the matrix.
            if lu[k][k].norm() <= f64::EPSILON * scale {
                lu[k][k] = Complex::new(f64::EPSILON * scale, 0.0);
            }
            let (upper, lower) = lu.split_at_mut(k + 1);
            let pivot_row = &upper[k];
            for row in lower.iter_mut() {
                let factor = row[k] / pivot_row[k];
                row[k] = factor;
                for (value, above) in row[k + 1..].iter_mut().zip(&pivot_row[k + 1..]) {
                    *value -= factor * above;
                }
            }
        }
        Some(ComplexLu { lu, rows })
    }

    /// The unit null vector of the matrix (`transposed`: of its transpose) by two steps of
    /// inverse iteration from a fixed generic start; `None` when it breaks down.
    fn null_vector(&self, transposed: bool) -> Option<[Complex<f64>; 12]> {
        let mut v: [Complex<f64>; 12] = std::array::from_fn(|i| Complex::new(1.0 + 0.1 * i as f64, 0.05 * i as f64));
        for _ in 0..2 {
            v = if transposed { self.solve_transposed(&v) } else { self.solve(&v) };
            let norm = v.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return None;
            }
            for z in &mut v {
                *z /= norm;
            }
        }
        Some(v)
    }

    /// `x` with `M x = b`: `L U x = P b`.
    fn solve(&self, b: &[Complex<f64>; 12]) -> [Complex<f64>; 12] {
        let mut x: [Complex<f64>; 12] = std::array::from_fn(|i| b[self.rows[i]]);
        for i in 0..12 {
            for j in 0..i {
                let step = self.lu[i][j] * x[j];
                x[i] -= step;
            }
        }
        for i in (0..12).rev() {
            for j in i + 1..12 {
                let step = self.lu[i][j] * x[j];
                x[i] -= step;
            }
            x[i] /= self.lu[i][i];
        }
        x
    }

    /// `x` with `M^T x = b`: `U^T L^T (P x) = b`.
    fn solve_transposed(&self, b: &[Complex<f64>; 12]) -> [Complex<f64>; 12] {
        let mut z = *b;
        for i in 0..12 {
            for j in 0..i {
                let step = self.lu[j][i] * z[j];
                z[i] -= step;
            }
            z[i] /= self.lu[i][i];
        }
        for i in (0..12).rev() {
            for j in i + 1..12 {
                let step = self.lu[j][i] * z[j];
                z[i] -= step;
            }
        }
        let mut x = [Complex::new(0.0, 0.0); 12];
        for (i, &row) in self.rows.iter().enumerate() {
            x[row] = z[i];
        }
        x
    }
}

/// The elimination of one chain, with what does not depend on the pose.
#[derive(Debug, Clone)]
struct Elimination {
    chain: Chain,
    /// The first of the three kept joints (see [`BLOCKS`]).
    block: usize,
    /// Left side: `[quantity][{1, s3, c3}][{1, s4, c4} x {1, s5, c5}]`.
    left: [[[f64; 9]; 3]; 14],
    /// Per offset of [`OFFSETS3`], found at first use: the companion's `+-i` subspace to take
    /// out (`None` where the arm's has no clear one).
    deflations: [OnceLock<Option<Deflation>>; 4],
}

/// Every solution of one pose, unpolished.
#[derive(Debug, Clone, Default)]
pub struct GeneralSolutions {
    /// Joint configurations in the model's convention, angles in (-pi, pi].
    pub configurations: Vec<[f64; 6]>,
    /// Every real root was resolved into one configuration: with each configuration verified
    /// by the caller, the list is every solution of the pose. False when a root was ambiguous
    /// (two solutions share joint 3's angle, a near-double root) or the pose is degenerate for
    /// the elimination.
    pub resolved: bool,
}

/// The general solver of one 6R model.
#[derive(Debug, Clone)]
pub struct General6R {
    elimination: Elimination,
    /// The reversed chain solves it (joint order reversed in the answer).
    reversed: bool,
    arm: Arm,
}

impl General6R {
    /// The solver for `model` when it has six revolute joints and the elimination does not
    /// degenerate for its geometry (in the given or the reversed order); `None` otherwise.
    pub fn new(model: &Model) -> Option<General6R> {
        Self::of_arm(Arm::of(model)?)
    }

    /// The solver of a chain's lines (see [`super::lines`]).
    pub(crate) fn of_arm(arm: Arm) -> Option<General6R> {
        // Raghavan and Roth's choice in both orders first, then the other blocks.
        let order = BLOCKS.iter().flat_map(|block| [(false, *block), (true, *block)]);
        for (reversed, block) in order {
            let elimination = Elimination::new(arm.chain(reversed).clone(), block)?;
            if elimination.regular() {
                return Some(General6R {
                    elimination,
                    reversed,
                    arm,
                });
            }
        }
        None
    }

    /// Whether the reversed chain is solved.
    pub fn is_reversed(&self) -> bool {
        self.reversed
    }

    /// The elimination used, for reports and tests: `joints 3-5 kept` with `, reversed` when
    /// the reversed chain's joints are meant.
    pub fn variant(&self) -> String {
        let first = self.elimination.block + 1;
        let order = if self.reversed { ", reversed chain" } else { "" };
        format!("joints {first}-{} kept{order}", first + 2)
    }

    /// Why no configuration reaches world pose `goal` within `radii`, turned by up to `turn`
    /// about tool z, when the pose has no solution and none can appear within. A real root
    /// appears only where two meet on the real line (a branch pair born), so it suffices that
    /// each of the determinant's complex roots (joint 3's angle, complex) stays off the real
    /// angles by more than `FACTOR` (4) times the first-order change the tolerance can give its
    /// imaginary part (its real part may move freely: only the imaginary part reaching 0 makes
    /// it real); each simple root's rate of change with the pose is its perturbation's (see
    /// `Perturbation`), a multiple root's by finite differences, the roots matched to their
    /// nearest; the bound is then checked at probes of the tolerance (see `Checks`: a
    /// sweep's). `None` when the pose has a real root, the system degenerates at it or next to
    /// it, or a root's motion or its match is in doubt.
    pub fn out_of_reach_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> Option<String> {
        self.out_of_reach_in_ball(goal, radii, turn, SWEEP_CHECKS)
    }

    /// [`Self::out_of_reach_within`] with a validation's checks: more roots' corners, and 32
    /// turns of the whole tolerance about axes spread over the sphere (see `Checks`).
    pub fn out_of_reach_checked(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> Option<String> {
        self.out_of_reach_in_ball(goal, radii, turn, VALIDATION_CHECKS)
    }

    fn out_of_reach_in_ball(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64, checks: Checks) -> Option<String> {
        let closest = self.roots_stay_off(goal, Region::Ball { radii, turn }, false, checks).ok()?;
        let within = format!(
            "within {:.1} mm and {:.2} deg of it",
            radii.position_m * 1e3,
            (radii.orientation_rad + turn).to_degrees()
        );
        Some(self.no_root_appears(closest, &within))
    }

    /// The proof's words: how far the roots stay off the real angles over the poses `within`
    /// names.
    fn no_root_appears(&self, closest: f64, within: &str) -> String {
        format!(
            "the pose has no solution and none appears {within}: joint {}'s angle at every root of the determinant is at least {closest:.3} rad (imaginary part) off the real angles, more than four times what the tolerance can move it (first order)",
            if self.reversed { 6 - self.elimination.block } else { self.elimination.block + 1 }
        )
    }

    /// [`Self::out_of_reach_within`] over a box of poses about `goal` rather than a ball: the
    /// offsets along the position's world axes (m), then about the rotation's axes (rad; the
    /// goal's own axes with `local`, else the world's) up to `half` either side. Its roots'
    /// first-order motion is each offset's rate times its half-width, summed: where one offset
    /// moves a root most, a box thin along it proves what the ball about it cannot. On failure,
    /// the offset whose half-width added most to the failing root's motion (where known): the
    /// one to halve.
    pub(crate) fn out_of_reach_over_box(&self, goal: &Isometry3<f64>, half: &[f64; 6], local: bool) -> Result<String, Option<usize>> {
        let closest = self.roots_stay_off(goal, Region::Box { half: *half, local }, false, PART_CHECKS)?;
        let within = format!(
            "within ({:.2}, {:.2}, {:.2}) mm and ({:.2}, {:.2}, {:.2}) deg either side of it ({} axes)",
            half[0] * 1e3,
            half[1] * 1e3,
            half[2] * 1e3,
            half[3].to_degrees(),
            half[4].to_degrees(),
            half[5].to_degrees(),
            if local { "the goal's" } else { "world" }
        );
        Ok(self.no_root_appears(closest, &within))
    }

    /// Whether no solution appears within `radii` of world pose `goal` (turned by up to `turn`
    /// about tool z) beside those of the pose itself: the check of
    /// [`Self::out_of_reach_within`] on the complex roots alone, those [`Self::solve`] does not
    /// take as solutions. A proof from the pose's solutions (each certified over the tolerance)
    /// holds only with it: the tolerance may hold a branch pair born off every one of them.
    pub fn no_solution_appears_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64) -> bool {
        self.roots_stay_off(goal, Region::Ball { radii, turn }, true, SWEEP_CHECKS).is_ok()
    }

    /// The core of [`Self::out_of_reach_within`]: the smallest imaginary part of the roots that
    /// stay off the real angles, each by more than `FACTOR` times its imaginary part's
    /// first-order change over `region`; with `solutions`, the pose's solutions (near-real
    /// roots, see [`near_real`]) are let be, else one is a failure. On any failure, the box's
    /// offset that moved the failing root most, where there is one.
    fn roots_stay_off(&self, goal: &Isometry3<f64>, region: Region, solutions: bool, checks: Checks) -> Result<f64, Option<usize>> {
        let found = self.angles_of_system(goal, None, solutions).ok_or(None)?;
        let (index3, roots) = (found.index, &found.roots);
        // The pose's derivatives per metre and per radian, by one step along each axis.
        let local = region.local();
        let steps: [Isometry3<f64>; 6] = std::array::from_fn(|axis| offset_pose(goal, axis, POSE_STEP, local));
        // A tolerance on the real tool moves the chain's (a held joint's frame) by the lever
        // times its angle on top; a turn about the chain tool's own z moves only its rotation.
        let lever = self.arm.tool_lever;
        // Each offset's share of a root's first-order motion, from its rates of change.
        let shares = |rates: &[f64; 6]| -> [f64; 6] {
            match region {
                Region::Ball { radii, turn } => {
                    let position = radii.position_m + lever * radii.orientation_rad;
                    let rotation = radii.orientation_rad + turn;
                    let norm = |first: usize| rates[first..first + 3].iter().map(|r| r * r).sum::<f64>().sqrt();
                    [norm(0) * position, 0.0, 0.0, norm(3) * rotation, 0.0, 0.0]
                }
                Region::Box { half, .. } => {
                    let position = rates[..3].iter().map(|r| r * r).sum::<f64>().sqrt();
                    let turned = half[3..].iter().map(|h| h * h).sum::<f64>().sqrt();
                    let mut shares: [f64; 6] = std::array::from_fn(|k| rates[k].abs() * half[k]);
                    shares[0] += position * lever * turned;
                    shares
                }
            }
        };
        let points: Vec<(f64, f64)> = roots.iter().map(|root| root.angle).collect();
        // Roots within a rounding split of one another are one multiple root (a factor of the
        // determinant that is the geometry's): it moves as their centroid, which rounding
        // leaves precise, and must stay one after each step.
        // Clusters holding a solution are not followed.
        let clusters: Vec<Followed> = clusters(&points)
            .iter()
            .filter(|cluster| !(solutions && cluster.iter().any(|&i| roots[i].solution)))
            .map(|cluster| {
                let members: Vec<(f64, f64)> = cluster.iter().map(|&i| points[i]).collect();
                let (centre, spread) = centroid(&members);
                let off_real = members.iter().map(|m| m.1.abs()).fold(f64::INFINITY, f64::min) - spread;
                Followed {
                    count: members.len(),
                    centre,
                    spread,
                    off_real,
                    first: cluster[0],
                }
            })
            .collect();
        let mut rates = vec![[0.0; 6]; clusters.len()];
        // Each cluster's whole (complex) motion per offset, for the probes' check that the roots
        // moved as first order says.
        let mut speeds = vec![[0.0; 6]; clusters.len()];
        // Whether a root with rates `rate` (so far) stays off by enough, else the offset to halve.
        let judge = |rate: &[f64; 6], off_real: f64| -> Result<(), Option<usize>> {
            let shares = shares(rate);
            let stays_off = off_real > FACTOR * shares.iter().sum::<f64>();
            if stays_off {
                return Ok(());
            }
            let most = (0..6).max_by(|&a, &b| shares[a].total_cmp(&shares[b]));
            Err(most.filter(|_| matches!(region, Region::Box { .. })))
        };
        // Simple roots move by the perturbation of the matrix quadratic (its left and right
        // null vectors at the root), one system per offset instead of one eigenvalue problem;
        // a multiple root (a cluster) is followed by solving the stepped poses' roots.
        let perturbations: Option<Vec<Perturbation>> = clusters
            .iter()
            .map(|cluster| {
                (cluster.count == 1)
                    .then(|| Perturbation::of(&found.quadratic, roots[cluster.first].tangent))
                    .flatten()
            })
            .collect();
        // Rotations first: they move the roots most, so a failing proof ends soonest.
        for axis in [3, 4, 5, 0, 1, 2] {
            if let Some(perturbations) = &perturbations {
                let delta = self.quadratic_rate(&found, &steps[axis]).ok_or(None)?;
                for (((cluster, perturbation), rate), speed) in
                    clusters.iter().zip(perturbations).zip(rates.iter_mut()).zip(speeds.iter_mut())
                {
                    // Off the real angles is the imaginary part alone; a rate is its approach.
                    let turn = perturbation.angle_rate(&delta);
                    rate[axis] = -cluster.centre.1.signum() * turn.im;
                    speed[axis] = turn.norm();
                    if !rate[axis].is_finite() {
                        return Err(None);
                    }
                    judge(rate, cluster.off_real)?;
                }
                continue;
            }
            let (_, moved) = self.angles(&steps[axis], Some(index3), solutions).ok_or(None)?;
            for (
                &Followed {
                    count,
                    centre,
                    spread,
                    off_real,
                    ..
                },
                (rate, speed),
            ) in clusters.iter().zip(rates.iter_mut().zip(speeds.iter_mut()))
            {
                let mut near: Vec<(f64, (f64, f64))> = moved.iter().map(|m| (angle_distance(&centre, &m.angle), m.angle)).collect();
                near.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (farthest, next) = (near.get(count - 1).ok_or(None)?.0, near.get(count).map_or(f64::INFINITY, |n| n.0));
                // False for NaN too: no proof from a root that is not a number.
                let matched = farthest * MATCH_MARGIN < next;
                if !matched {
                    return Err(None);
                }
                let copies: Vec<(f64, f64)> = near[..count].iter().map(|n| n.1).collect();
                let (moved_centre, moved_spread) = centroid(&copies);
                // A multiple root that is the pose's alone splits under a step far more than
                // rounding spreads it.
                if moved_spread > SPLIT_GROWTH * spread + ROUNDING_SPREAD {
                    return Err(None);
                }
                // Off the real angles is the imaginary part alone.
                rate[axis] = (centre.1.abs() - moved_centre.1.abs()) / POSE_STEP;
                speed[axis] = angle_distance(&centre, &moved_centre) / POSE_STEP;
                judge(rate, off_real)?;
            }
        }
        let closest = clusters
            .iter()
            .map(|cluster| cluster.off_real + cluster.spread)
            .fold(f64::INFINITY, f64::min);
        let real = roots.iter().filter(|root| root.solution).count();
        // The corners the roots nearest to failing point to.
        let mut order: Vec<(f64, usize)> = rates
            .iter()
            .zip(&clusters)
            .enumerate()
            .map(|(i, (rate, cluster))| (shares(rate).iter().sum::<f64>() / cluster.off_real, i))
            .collect();
        order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let corners: Vec<([f64; 6], (f64, f64))> = order
            .iter()
            .take(checks.corners)
            .filter(|(ratio, _)| FACTOR * ratio >= checks.tight)
            .map(|&(_, i)| (rates[i], clusters[i].centre))
            .collect();
        // Two roots that may meet within the region (their whole first-order motions reach
        // across the distance between them; a root and its conjugate meet only on the real
        // angles, which its own rate bounds) may part at right angles to their approach, so
        // toward the real angles as fast as they move at all: each must stay off by four times
        // its whole motion (on a modular arm four roots 1.6 rad off the real angles, symmetric
        // about an angle, met in pairs on it and parted, one of each pair onto the real angles).
        let motions: Vec<f64> = speeds.iter().map(|speed| shares(speed).iter().sum::<f64>()).collect();
        for (i, a) in clusters.iter().enumerate() {
            let may_meet = clusters.iter().enumerate().any(|(j, b)| {
                let conjugate = (a.centre.0, -a.centre.1);
                j != i && angle_distance(&conjugate, &b.centre) > CLUSTER && angle_distance(&a.centre, &b.centre) < motions[i] + motions[j]
            });
            // False for NaN too.
            let stays_off = a.off_real > FACTOR * motions[i];
            if may_meet && !stays_off {
                return Err(None);
            }
        }
        // Where each followed root may be at a probe: within twice its whole first-order motion.
        let reach: Vec<((f64, f64), f64)> = clusters
            .iter()
            .zip(&speeds)
            .map(|(cluster, speed)| {
                (
                    cluster.centre,
                    LINEAR * shares(speed).iter().sum::<f64>() + 2.0 * cluster.spread + LINEAR_FLOOR,
                )
            })
            .collect();
        if !self.roots_stay_off_at_the_edges(goal, region, index3, closest, real, checks, &corners, &reach) {
            return Err(None);
        }
        Ok(closest)
    }

    /// The first-order bound's check at the region's edges: at the pose offset by the whole
    /// region along each of its six offsets (a ball's three rotations), either side, no more
    /// roots are real than at the centre (`real`, the pose's solutions), and no other is nearer
    /// the real angles than half the closest at the centre (the bound lets a root come a
    /// quarter nearer), the pairs of the pose's solutions that met and left the real line
    /// before the edge aside. A root whose
    /// motion is far from linear over the region fails it: found on a modular catalog arm
    /// whose roots barely move at the centre of a goal's tolerance and turn real at 0.9 of its
    /// radius, where two solutions appear.
    #[allow(clippy::too_many_arguments)]
    fn roots_stay_off_at_the_edges(
        &self,
        goal: &Isometry3<f64>,
        region: Region,
        index3: usize,
        closest: f64,
        real: usize,
        checks: Checks,
        corners: &[([f64; 6], (f64, f64))],
        reach: &[((f64, f64), f64)],
    ) -> bool {
        let (half, local) = match region {
            // The ball's rotation edges alone: a degree turns the tool's end by the arm's
            // size times it, ten times a millimetre's shift; on the brute force of task 00 and
            // the 200 random designs x 36 tasks every edge that failed was a rotation's, and
            // the ball's proofs are a sweep's largest share of them.
            Region::Ball { radii, turn } => {
                let rotation = radii.orientation_rad;
                ([0.0, 0.0, 0.0, rotation, rotation, rotation + turn], true)
            }
            Region::Box { half, local } => (half, local),
        };
        let edges = (0..12).filter_map(|k| {
            let (axis, sign) = (k / 2, if k % 2 == 0 { 1.0 } else { -1.0 });
            (half[axis] != 0.0).then(|| offset_pose(goal, axis, sign * half[axis], local))
        });
        // The turns between the edges' axes: `checks.turns` axes spread evenly over the sphere (a
        // Fibonacci lattice), each turned by the whole rotation the edges have along it.
        let turns = (0..checks.turns).map(|k| {
            let z = 1.0 - (2 * k + 1) as f64 / checks.turns as f64;
            let across = (1.0 - z * z).max(0.0).sqrt();
            let longitude = k as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
            let axis = Vector3::new(across * longitude.cos(), across * longitude.sin(), z);
            let turn = UnitQuaternion::from_scaled_axis(axis.component_mul(&Vector3::new(half[3], half[4], half[5])));
            if local {
                goal * turn
            } else {
                Isometry3::from_parts(goal.translation, turn * goal.rotation)
            }
        });
        edges.chain(turns).all(|edge| {
            self.angles(&edge, Some(index3), real > 0)
                .is_some_and(|(_, roots)| probe_holds(&roots, real, closest, reach))
        }) && corners
            .iter()
            .all(|(rates, start)| self.worst_corner_holds(goal, region, index3, (real, closest), reach, *rates, *start, checks.steps))
    }

    /// The check of [`Self::roots_stay_off_at_the_edges`] at the corner of `region` a root's
    /// `rates` point to, then at the corner its rates there point to, and so on
    /// (`steps` corners at most, until one repeats): a search for the pose where that
    /// root comes nearest the real angles when first order at the centre misjudges the
    /// direction (on an economic arm a root 0.011 rad off them turns real only near one corner
    /// of the tolerance, its shift and turn both whole). The root is followed from `start` to
    /// its nearest at each corner.
    #[allow(clippy::too_many_arguments)]
    fn worst_corner_holds(
        &self,
        goal: &Isometry3<f64>,
        region: Region,
        index3: usize,
        (real, closest): (usize, f64),
        reach: &[((f64, f64), f64)],
        mut rates: [f64; 6],
        mut at: (f64, f64),
        steps: usize,
    ) -> bool {
        let local = region.local();
        let lever = self.arm.tool_lever;
        let mut previous: Option<Isometry3<f64>> = None;
        for _ in 0..steps {
            let pose = corner(goal, region, lever, &rates);
            if previous.is_some_and(|p| {
                (p.translation.vector - pose.translation.vector).norm() < 1e-12 && p.rotation.angle_to(&pose.rotation) < 1e-12
            }) {
                return true;
            }
            let Some(found) = self.angles_of_system(&pose, Some(index3), real > 0) else {
                return false;
            };
            if !probe_holds(&found.roots, real, closest, reach) {
                return false;
            }
            // The followed root there, and its rates of approach there.
            let Some(root) = found
                .roots
                .iter()
                .min_by(|a, b| angle_distance(&a.angle, &at).total_cmp(&angle_distance(&b.angle, &at)))
            else {
                return false;
            };
            let Some(perturbation) = Perturbation::of(&found.quadratic, root.tangent) else {
                return true;
            };
            for (axis, rate) in rates.iter_mut().enumerate() {
                let Some(delta) = self.quadratic_rate(&found, &offset_pose(&pose, axis, POSE_STEP, local)) else {
                    return false;
                };
                *rate = -root.angle.1.signum() * perturbation.angle_rate(&delta).im;
            }
            if !rates.iter().all(|r| r.is_finite()) {
                return false;
            }
            at = root.angle;
            previous = Some(pose);
        }
        true
    }

    /// [`Self::out_of_reach_within`] part by part over `goal`'s tolerance (see
    /// `ik::parts`; at most `budget` parts, taken as used), for a pose a millimetre or two
    /// beyond a fold of the arm's solutions: its roots are nearer the real angles than four
    /// times their motion over the whole tolerance, but not over a small enough part of it.
    /// `None` where a small part's centre pose has solutions (ignoring the limits), a part stays
    /// unproven at the smallest size, or the budget runs out.
    pub fn out_of_reach_in_parts(&self, goal: &Goal, budget: &mut usize) -> Option<String> {
        let pose_of = |goal: &Goal| Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        super::parts::out_of_reach_by_parts(
            goal,
            budget,
            PARTS_LEVER_M,
            |part, extent| self.out_of_reach_over_box(&pose_of(part), &extent.half, extent.local),
            |part| !self.solve(&pose_of(part)).configurations.is_empty(),
        )
    }

    /// Every root of `goal`'s determinant but the `+-i` ones the deflation takes out, as joint
    /// 3's complex angle (re modulo a turn) and whether [`Self::solve`] takes it as a solution,
    /// at offset `OFFSETS3[index]` (else the first whose companion matrix works), and the
    /// offset's index; `None` when the system degenerates, or, without `solutions`, the pose
    /// has a real root.
    fn angles(&self, goal: &Isometry3<f64>, index: Option<usize>, solutions: bool) -> Option<(usize, Vec<Root>)> {
        self.angles_of_system(goal, index, solutions)
            .map(|found| (found.index, found.roots))
    }

    /// [`Self::angles`] with the system and the matrix quadratic they are the roots of.
    fn angles_of_system(&self, goal: &Isometry3<f64>, index: Option<usize>, solutions: bool) -> Option<Angles> {
        let (rotation, translation) = self.arm.goal(goal, self.reversed);
        let system = self.elimination.system(&rotation, &translation)?;
        let indices = match index {
            Some(index) => index..index + 1,
            None => 0..OFFSETS3.len(),
        };
        for index in indices {
            let offset = OFFSETS3[index];
            let Some((eigenvalues, quadratic)) = self.elimination.eigenvalues(&system, index) else {
                continue;
            };
            let roots: Vec<Root> = eigenvalues
                .iter()
                .map(|&(re, im)| {
                    // 2 atan(re + i im): its real part from atan2, its imaginary part from a log.
                    let real = offset + (2.0 * re).atan2(1.0 - re * re - im * im);
                    let imaginary = 0.5 * ((re * re + (1.0 + im).powi(2)) / (re * re + (1.0 - im).powi(2))).ln();
                    Root {
                        angle: (real, imaginary),
                        tangent: (re, im),
                        solution: is_near_real(re, im),
                    }
                })
                .collect();
            if roots
                .iter()
                .any(|root| !root.angle.0.is_finite() || (!solutions && root.angle.1.abs() <= REAL_ROOT))
            {
                return None;
            }
            return Some(Angles {
                index,
                roots,
                system,
                quadratic,
            });
        }
        None
    }

    /// The rate of change of `found`'s matrix quadratic toward `stepped`, a pose [`POSE_STEP`]
    /// from `found`'s (see [`Elimination::system_near`]).
    fn quadratic_rate(&self, found: &Angles, stepped: &Isometry3<f64>) -> Option<Quadratic> {
        let (rotation, translation) = self.arm.goal(stepped, self.reversed);
        let near = self
            .elimination
            .system_near(&rotation, &translation, &found.system, OFFSETS3[found.index])?;
        Some(std::array::from_fn(|k| (near[k] - found.quadratic[k]) / POSE_STEP))
    }

    /// Every configuration whose tool frame is at world pose `goal`, unpolished.
    pub fn solve(&self, goal: &Isometry3<f64>) -> GeneralSolutions {
        let (rotation, translation) = self.arm.goal(goal, self.reversed);
        let mut out = self.elimination.solve(&rotation, &translation);
        if self.reversed {
            for q in &mut out.configurations {
                q.reverse();
            }
        }
        out
    }
}

impl Elimination {
    /// The left side's coefficients of `chain`: interpolated at 27 nodes and checked at a point
    /// off them (`None` when the check fails: the lines are not a 6R chain, e.g. NaN).
    fn new(chain: Chain, block: usize) -> Option<Elimination> {
        let nodes = node_inverse();
        let mut values = [[[[0.0; 14]; 3]; 3]; 3];
        for (i3, plane) in values.iter_mut().enumerate() {
            for (i4, row) in plane.iter_mut().enumerate() {
                for (i5, value) in row.iter_mut().enumerate() {
                    *value = chain.left(block, [NODES[i3], NODES[i4], NODES[i5]]);
                }
            }
        }
        let mut left = [[[0.0; 9]; 3]; 14];
        for (k, quantity) in left.iter_mut().enumerate() {
            for (f3, by3) in quantity.iter_mut().enumerate() {
                for f4 in 0..3 {
                    for f5 in 0..3 {
                        let mut sum = 0.0;
                        for i3 in 0..3 {
                            for i4 in 0..3 {
                                for i5 in 0..3 {
                                    sum += nodes[(f3, i3)] * nodes[(f4, i4)] * nodes[(f5, i5)] * values[i3][i4][i5][k];
                                }
                            }
                        }
                        by3[f4 * 3 + f5] = sum;
                    }
                }
            }
        }
        let elimination = Elimination {
            chain,
            block,
            left,
            deflations: Default::default(),
        };
        let probe = [0.37, -1.91, 2.47];
        let exact = elimination.chain.left(block, probe);
        let fitted = elimination.left_at(probe[0], probe[1], probe[2]);
        let agrees = exact.iter().zip(&fitted).all(|(a, b)| (a - b).abs() <= 1e-9 * (1.0 + a.abs()));
        agrees.then_some(elimination)
    }

    /// Whether the elimination holds for this chain at generic poses: the eliminated products
    /// independent, the determinant not identically zero, no two roots one to rounding (a
    /// spherical wrist's flip shares joints 1 to 3: an elimination keeping joints 4 to 6 splits
    /// the pair), and each root resolved into one configuration that reaches the pose, the
    /// probe's own among them. Special geometry can
    /// pass the first two and still fail the last (the null vector leaves a kept joint free, as
    /// where the carried line meets the last kept axis); the probes catch it.
    fn regular(&self) -> bool {
        PROBES.iter().all(|probe| {
            let (rotation, translation) = self.chain.forward(probe);
            let Some(system) = self.system(&rotation, &translation) else {
                return false;
            };
            let sigma = system.at(0.29).svd(false, false).singular_values;
            if sigma.min() <= SINGULAR * sigma.max() {
                return false;
            }
            let (found, shared) = self.solve_sharing(&rotation, &translation);
            let reaches = |q: &[f64; 6]| self.chain.misses(q, &rotation, &translation) < CANDIDATE;
            let own = |q: &[f64; 6]| q.iter().zip(probe).all(|(a, b)| super::wrap_angle(a - b).abs() < 1e-6);
            !shared && found.resolved && found.configurations.iter().all(reaches) && found.configurations.iter().any(own)
        })
    }

    /// The left side's fitted quantities at joint angles 3, 4, 5.
    fn left_at(&self, t3: f64, t4: f64, t5: f64) -> [f64; 14] {
        let b3 = [1.0, t3.sin(), t3.cos()];
        let b4 = [1.0, t4.sin(), t4.cos()];
        let b5 = [1.0, t5.sin(), t5.cos()];
        std::array::from_fn(|k| {
            let mut sum = 0.0;
            for (f3, v3) in b3.iter().enumerate() {
                for (f4, v4) in b4.iter().enumerate() {
                    for (f5, v5) in b5.iter().enumerate() {
                        sum += self.left[k][f3][f4 * 3 + f5] * v3 * v4 * v5;
                    }
                }
            }
            sum
        })
    }

    /// The 12 x 12 matrix quadratic of a pose; `None` when the products of joints 1 and 2 are
    /// dependent at this pose.
    fn system(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Option<System> {
        let (right, q, r) = self.products(rotation, translation);
        let r_inverse = independent(&r)?;
        let complement = complement_of(&q);
        Some(System {
            equations: self.equations(&complement, &right),
            products_inverse: r_inverse * q.transpose(),
            right,
            complement,
        })
    }

    /// The matrix quadratic at tangent offset `offset3` of a pose next to `base`'s, its complement `base`'s projected off the new
    /// products: where `base`'s is chosen afresh a nearby pose may pick other rows, and the
    /// matrices would not change smoothly with the pose. `None` where the products are
    /// dependent.
    fn system_near(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>, base: &System, offset3: f64) -> Option<Quadratic> {
        let (right, q, r) = self.products(rotation, translation);
        independent(&r)?;
        let complement: [[f64; 14]; 6] = base.complement.map(|row| {
            let row = SVector::<f64, 14>::from(row);
            let projected = row - q * (q.transpose() * row);
            projected.into()
        });
        Some(quadratic_of(&self.equations(&complement, &right), offset3))
    }

    /// The right side's coefficients at a pose, the constant first, and a QR of its eight
    /// products of joints 1 and 2 (a QR, not an SVD: a fifth of the cost) as `(Q, R)`.
    fn products(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> ([[f64; 9]; 14], SMatrix<f64, 14, 8>, Matrix8) {
        let chain = &self.chain;
        let relative = rotation * chain.home_rotation.transpose();
        let mut values = [[[0.0; 14]; 3]; 3];
        for (i1, row) in values.iter_mut().enumerate() {
            for (i2, value) in row.iter_mut().enumerate() {
                *value = chain.right(self.block, [NODES[i1], NODES[i2]], &relative, translation);
            }
        }
        // right[k][f1 * 3 + f2]
        let right = interpolate2(&values);
        let products = SMatrix::<f64, 14, 8>::from_fn(|k, j| right[k][j + 1]);
        let qr = products.qr();
        (right, qr.q(), qr.r())
    }

    /// Six equations in joints 3 to 5: the rows of the left side along `complement` (which no
    /// product of joints 1 and 2 reaches), the right side's constant moved over.
    fn equations(&self, complement: &[[f64; 14]; 6], right: &[[f64; 9]; 14]) -> [[[f64; 9]; 3]; 6] {
        let mut equations = [[[0.0; 9]; 3]; 6];
        for (i, equation) in equations.iter_mut().enumerate() {
            for k in 0..14 {
                let weight = complement[i][k];
                for (by3, left) in equation.iter_mut().zip(&self.left[k]) {
                    for (value, coefficient) in by3.iter_mut().zip(left) {
                        *value += weight * coefficient;
                    }
                }
                equation[0][0] -= weight * right[k][0];
            }
        }
        equations
    }

    /// Every configuration of the chain at pose (`rotation`, `translation`).
    fn solve(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> GeneralSolutions {
        self.solve_sharing(rotation, translation).0
    }

    /// [`Self::solve`], and whether two roots were one to rounding (two solutions sharing joint
    /// 3's angle, or a double root): an elimination whose roots pair up so at generic poses is
    /// a poor choice where another exists ([`Self::regular`]).
    fn solve_sharing(&self, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> (GeneralSolutions, bool) {
        let mut out = GeneralSolutions::default();
        let Some(system) = self.system(rotation, translation) else {
            return (out, false);
        };
        let Some((offset3, roots, [c, b, a])) = self.roots(&system) else {
            return (out, false);
        };
        out.resolved = true;
        let partners = repeated_partners(&roots);
        let mut shared = partners.iter().any(|p| *p != Partner::Alone);
        // Second roots of pairs resolved with their first.
        let mut paired = vec![false; roots.len()];
        // The root each configuration came from.
        let mut sources: Vec<f64> = Vec::with_capacity(roots.len());
        let quadratic = [&c, &b, &a];
        for (i, &x3) in roots.iter().enumerate() {
            match partners[i] {
                Partner::Alone => {}
                Partner::Second if paired[i] => continue,
                Partner::Second => {}
                Partner::First(j) => {
                    // Two roots one to rounding: two solutions that share joint 3's angle (a
                    // wrist that is spherical to within the rounding of the arm's file flips
                    // about it) or a double root (a fold), told apart by the matrix's null space.
                    let between = 0.5 * (x3 + roots[j]);
                    if let Some(pair) = self.sharing_pair(&system, quadratic, offset3, between, rotation, translation) {
                        out.configurations.extend(pair);
                        sources.extend([between, between]);
                        paired[j] = true;
                        continue;
                    }
                    out.resolved = false;
                }
                Partner::Many => out.resolved = false,
            }
            let t3 = offset3 + 2.0 * x3.atan();
            let matrix = c + b * x3 + a * (x3 * x3);
            // The null vector by inverse iteration (one LU); where its configuration misses the
            // pose (an ill-conditioned root), by the SVD.
            let fast = null_vector(&matrix).and_then(|null| self.configuration(&system, &null, t3, rotation));
            let found = fast
                .filter(|q| self.chain.misses(q, rotation, translation) < CANDIDATE)
                .or_else(|| {
                    let svd = matrix.svd(false, true);
                    let (smallest, _) = svd.singular_values.argmin();
                    let v_t = svd.v_t?;
                    let null: [f64; 12] = std::array::from_fn(|i| v_t[(smallest, i)]);
                    // Ill-conditioned: two roots nearly one (a wrist spherical to within
                    // microns), whose null vectors mix.
                    self.configuration(&system, &null, t3, rotation)
                        .map(|q| self.chain.newton(q, rotation, translation))
                });
            match found {
                Some(q) => {
                    out.configurations.push(q);
                    sources.push(x3);
                }
                None => out.resolved = false,
            }
        }
        // Two roots that gave one solution: nearer than rounding's split, their matrix may still
        // hold the pair; else the other stays unlisted.
        let configurations = &mut out.configurations;
        for i in 0..configurations.len() {
            for j in i + 1..configurations.len() {
                if !one_configuration(&configurations[i], &configurations[j]) {
                    continue;
                }
                shared = true;
                let between = 0.5 * (sources[i] + sources[j]);
                match self.sharing_pair(&system, quadratic, offset3, between, rotation, translation) {
                    Some([first, second]) => {
                        configurations[i] = first;
                        configurations[j] = second;
                    }
                    None => out.resolved = false,
                }
            }
        }
        // A pair that came out as a configuration already listed.
        let repeated = configurations
            .iter()
            .enumerate()
            .any(|(i, a)| configurations[i + 1..].iter().any(|b| one_configuration(a, b)));
        if repeated {
            out.resolved = false;
        }
        (out, shared)
    }

    /// The two configurations at a root `x3` of the determinant shared by two solutions: its
    /// matrix has two null vectors, and the two combinations of them that are monomial vectors
    /// of joints 4 and 5 (where the 2 x 2 minors that vanish on one vanish: a quadratic in the
    /// combination each, the largest [`SHARED_FORMS`] tried) give them, each Newton-polished,
    /// verified against the pose and the two distinct. `None` where the null space is one
    /// vector (a double root: the pose is on a fold) or no two verify.
    fn sharing_pair(
        &self,
        system: &System,
        [c, b, a]: [&Matrix12; 3],
        offset3: f64,
        x3: f64,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
    ) -> Option<[[f64; 6]; 2]> {
        let matrix = c + b * x3 + a * (x3 * x3);
        let svd = matrix.svd(false, true);
        let v_t = svd.v_t?;
        let values = &svd.singular_values;
        let mut order: [usize; 12] = std::array::from_fn(|i| i);
        order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
        // False for NaN too.
        let two_null = values[order[1]] <= SHARED_NULL * values[order[11]];
        if !two_null {
            return None;
        }
        let null = |k: usize| -> [f64; 12] { std::array::from_fn(|i| v_t[(order[k], i)]) };
        let (p, r) = (null(0), null(1));
        let mut forms: Vec<([f64; 3], f64)> = monomial_minors(&p, &r)
            .into_iter()
            .map(|form| (form, form.iter().map(|f| f.abs()).sum::<f64>()))
            .collect();
        forms.sort_by(|x, y| y.1.total_cmp(&x.1));
        let t3 = offset3 + 2.0 * x3.atan();
        let mut found: Vec<[f64; 6]> = Vec::with_capacity(2);
        // The largest minors first: one that vanishes on the whole null space (the pair shares
        // more than joint 3's angle) or whose roots are complex to rounding gives nothing.
        for ([quadratic, linear, constant], _) in forms.into_iter().take(SHARED_FORMS) {
            // The combination `cos p + sin r` as a ratio, about the larger end coefficient.
            let flipped = quadratic.abs() < constant.abs();
            let (lead, last) = if flipped { (constant, quadratic) } else { (quadratic, constant) };
            let discriminant = linear * linear - 4.0 * lead * last;
            if !(lead != 0.0 && discriminant >= 0.0) {
                continue;
            }
            let root = discriminant.sqrt();
            for sign in [-1.0, 1.0] {
                let ratio = (-linear + sign * root) / (2.0 * lead);
                let (weight_p, weight_r) = if flipped { (1.0, ratio) } else { (ratio, 1.0) };
                let combined: [f64; 12] = std::array::from_fn(|i| weight_p * p[i] + weight_r * r[i]);
                let Some(q) = self.configuration(system, &combined, t3, rotation) else {
                    continue;
                };
                // A miss is never NaN (infinite instead).
                if self.chain.misses(&q, rotation, translation) >= SHARED_MISS {
                    continue;
                }
                let q = self.chain.newton(q, rotation, translation);
                let new = !found.iter().any(|f| one_configuration(f, &q));
                if self.chain.misses(&q, rotation, translation) < CANDIDATE && new {
                    found.push(q);
                }
                if let [a, b] = found[..] {
                    return Some([a, b]);
                }
            }
        }
        None
    }

    /// The offset of joint 3's tangent used and the near-real roots of `system`'s determinant;
    /// `None` when the leading matrix is singular, or its eigenvalues do not converge, at every
    /// offset tried.
    fn roots(&self, system: &System) -> Option<(f64, Vec<f64>, Quadratic)> {
        for (index, &offset3) in OFFSETS3.iter().enumerate() {
            let Some((eigenvalues, quadratic)) = self.eigenvalues(system, index) else {
                continue;
            };
            let roots = near_real(&eigenvalues);
            // A root near infinity (joint 3 near the offset's half turn) is imprecise: another
            // offset moves it.
            if roots.iter().any(|x| x.abs() > LARGE_ROOT) && index + 1 < OFFSETS3.len() {
                continue;
            }
            return Some((offset3, roots, quadratic));
        }
        None
    }

    /// The eigenvalues of `system`'s companion matrix at offset `OFFSETS3[index]`, without the
    /// `+-i` ones where the arm's deflation holds at this pose (all 24 where not), and the
    /// matrix quadratic.
    fn eigenvalues(&self, system: &System, index: usize) -> Option<(Vec<(f64, f64)>, Quadratic)> {
        let [c, b, a] = system.quadratic(OFFSETS3[index]);
        let deflated = self.deflation(index).and_then(|deflation| deflation.eigenvalues(&c, &b, &a));
        let eigenvalues = match deflated {
            Some(eigenvalues) => eigenvalues,
            None => quadratic_eigenvalues(&c, &b, &a)?,
        };
        Some((eigenvalues, [c, b, a]))
    }

    /// The deflation at offset `OFFSETS3[index]`, found from the first probe's pose.
    fn deflation(&self, index: usize) -> Option<&Deflation> {
        self.deflations[index]
            .get_or_init(|| {
                let (rotation, translation) = self.chain.forward(&PROBES[0]);
                let [c, b, a] = self.system(&rotation, &translation)?.quadratic(OFFSETS3[index]);
                Deflation::of(&c, &b, &a)
            })
            .as_ref()
    }

    /// The configuration of a root: joints 4 and 5 from the null vector, 1 and 2 from the
    /// eliminated products, 6 from the pose.
    fn configuration(&self, system: &System, null: &[f64; 12], t3: f64, rotation: &Matrix3<f64>) -> Option<[f64; 6]> {
        let (t4, t5) = angles_of_null_vector(null);
        let (ta, tb) = system.first_two(&self.left_at(t3, t4, t5))?;
        let block = self.block;
        let [a, b] = eliminated(block);
        let mut q = [0.0; 6];
        q[block..block + 3].copy_from_slice(&[t3, t4, t5]);
        q[a] = ta;
        q[b] = tb;
        q[block + 3] = self.chain.angle_of(block + 3, &q, rotation);
        Some(q.map(super::wrap_angle))
    }
}

/// Whether the roots at a probe of a region keep what its centre's proof needs: no more real
/// than the centre's `real`; each followed root of `reach` (centre, how far it may move) with
/// one within its reach (a root that moved further than first order allows, twice over, moves
/// far from linearly and its bound says nothing: on a modular arm roots 1.6 rad off the real
/// angles turn real inside a tolerance and leave them again at its boundary); and no other
/// nearer the real angles than half the centre's `closest`, the pairs of the pose's solutions
/// that met and left the real line before the probe aside.
fn probe_holds(roots: &[Root], real: usize, closest: f64, reach: &[((f64, f64), f64)]) -> bool {
    let at_probe = roots.iter().filter(|root| root.solution).count();
    if at_probe > real {
        return false;
    }
    let linear = reach
        .iter()
        .all(|(centre, within)| roots.iter().any(|root| angle_distance(centre, &root.angle) <= *within));
    if !linear {
        return false;
    }
    let mut off: Vec<f64> = roots
        .iter()
        .filter(|root| !root.solution)
        .map(|root| root.angle.1.abs())
        .filter(|im| *im <= FAR_FROM_REAL)
        .collect();
    off.sort_by(f64::total_cmp);
    off.get(real - at_probe).is_none_or(|nearest| *nearest >= 0.5 * closest)
}

/// The corner of `region` about `goal` that a root's first-order `rates` (of approach to the real
/// angles, per offset) point to: a ball's whole shift and whole turn along the rates' position
/// and rotation parts, a box's half-width along each offset with its rate's sign.
fn corner(goal: &Isometry3<f64>, region: Region, lever: f64, rates: &[f64; 6]) -> Isometry3<f64> {
    let (shift, turn, local) = match region {
        Region::Ball { radii, turn } => {
            let along = |first: usize, length: f64| {
                let direction = Vector3::new(rates[first], rates[first + 1], rates[first + 2]);
                let norm = direction.norm();
                if norm > 0.0 && norm.is_finite() {
                    direction * (length / norm)
                } else {
                    Vector3::zeros()
                }
            };
            (
                along(0, radii.position_m + lever * radii.orientation_rad),
                along(3, radii.orientation_rad + turn),
                true,
            )
        }
        Region::Box { half, local } => {
            let offset: [f64; 6] = std::array::from_fn(|k| half[k].copysign(rates[k]));
            (
                Vector3::new(offset[0], offset[1], offset[2]),
                Vector3::new(offset[3], offset[4], offset[5]),
                local,
            )
        }
    };
    let turn = UnitQuaternion::from_scaled_axis(turn);
    let translation = Translation3::from(goal.translation.vector + shift);
    if local {
        Isometry3::from_parts(translation, goal.rotation * turn)
    } else {
        Isometry3::from_parts(translation, turn * goal.rotation)
    }
}

/// The 12 x 12 matrix's coefficients of `x3^0, x3^1, x3^2` for joint 3's tangent offset, from six
/// equations `[equation][{1, s3, c3}][{1, s4, c4} x {1, s5, c5}]`.
fn quadratic_of(equations: &[[[f64; 9]; 3]; 6], offset3: f64) -> Quadratic {
    let (h3, h4, h5) = (half_angle(offset3), half_angle(OFFSETS[1]), half_angle(OFFSETS[2]));
    let mut out = [Matrix12::zeros(); 3];
    // The change of basis one joint at a time (it is a product of three): 5, then 4, then 3.
    for (i, equation) in equations.iter().enumerate() {
        let mut by5 = [[[0.0; 3]; 3]; 3];
        for (f3, by3) in equation.iter().enumerate() {
            for f4 in 0..3 {
                for p5 in 0..3 {
                    by5[f3][f4][p5] = (0..3).map(|f5| by3[f4 * 3 + f5] * h5[(f5, p5)]).sum();
                }
            }
        }
        let mut by4 = [[[0.0; 3]; 3]; 3];
        for f3 in 0..3 {
            for p4 in 0..3 {
                for p5 in 0..3 {
                    by4[f3][p4][p5] = (0..3).map(|f4| by5[f3][f4][p5] * h4[(f4, p4)]).sum();
                }
            }
        }
        for (p3, matrix) in out.iter_mut().enumerate() {
            for p4 in 0..3 {
                for p5 in 0..3 {
                    let v: f64 = (0..3).map(|f3| by4[f3][p4][p5] * h3[(f3, p3)]).sum();
                    matrix[(i, p4 * 3 + p5)] = v;
                    matrix[(6 + i, (p4 + 1) * 3 + p5)] = v;
                }
            }
        }
    }
    out
}

/// The inverse of the products' `R`, where they are independent: the condition number, bounded
/// from above by Frobenius norms, below `1 / SINGULAR`.
fn independent(r: &Matrix8) -> Option<Matrix8> {
    let r_inverse = r.try_inverse()?;
    let condition = r.norm() * r_inverse.norm();
    (condition.is_finite() && condition * SINGULAR <= 1.0).then_some(r_inverse)
}

/// `goal` offset by `amount` along offset `axis` of [`Region`]'s: a shift along world axis
/// `axis` (m), or from 3 a turn (rad) about the goal's own axis `axis - 3` with `local`, else
/// the world's.
fn offset_pose(goal: &Isometry3<f64>, axis: usize, amount: f64, local: bool) -> Isometry3<f64> {
    let mut offset = Vector3::zeros();
    offset[axis % 3] = amount;
    let turn = UnitQuaternion::from_scaled_axis(offset);
    match axis {
        0..3 => Isometry3::from_parts(Translation3::from(goal.translation.vector + offset), goal.rotation),
        _ if local => goal * turn,
        _ => Isometry3::from_parts(goal.translation, turn * goal.rotation),
    }
}

/// The roots of `roots` (complex angles) not [`FAR_FROM_REAL`] grouped where they lie within
/// [`CLUSTER`] of one another (single linkage), by index.
fn clusters(roots: &[(f64, f64)]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (index, root) in roots.iter().enumerate() {
        if root.1.abs() > FAR_FROM_REAL {
            continue;
        }
        let joined: Vec<usize> = (0..groups.len())
            .filter(|&g| groups[g].iter().any(|&other| angle_distance(root, &roots[other]) <= CLUSTER))
            .collect();
        let mut group = vec![index];
        for &g in joined.iter().rev() {
            group.extend(groups.remove(g));
        }
        group.sort_unstable();
        groups.push(group);
    }
    groups.sort();
    groups
}

/// The centroid of complex angles (real parts unwrapped about the first) and their largest
/// distance from it.
fn centroid(angles: &[(f64, f64)]) -> ((f64, f64), f64) {
    let first = angles[0];
    let count = angles.len() as f64;
    let re = angles.iter().map(|a| first.0 + super::wrap_angle(a.0 - first.0)).sum::<f64>() / count;
    let im = angles.iter().map(|a| a.1).sum::<f64>() / count;
    let centre = (re, im);
    let spread = angles.iter().map(|a| angle_distance(&centre, a)).fold(0.0, f64::max);
    (centre, spread)
}

/// The distance between two complex angles, their real parts compared modulo a turn.
fn angle_distance(a: &(f64, f64), b: &(f64, f64)) -> f64 {
    super::wrap_angle(a.0 - b.0).hypot(a.1 - b.1)
}

/// Whether two roots are one within rounding: two solutions sharing joint 3's angle (the null
/// vector would mix them) or a double root.
fn nearly_repeated(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-7 * (1.0 + a.abs().max(b.abs()))
}

/// Whether two configurations (angles in (-pi, pi]) are one solution: no joint apart by more
/// than [`SHARED_DISTINCT`], the way round. Every solve compares its configurations pairwise:
/// no `fmod`, and the first joint apart ends it.
fn one_configuration(a: &[f64; 6], b: &[f64; 6]) -> bool {
    a.iter().zip(b).all(|(x, y)| {
        let apart = (x - y).abs();
        apart <= SHARED_DISTINCT || apart >= std::f64::consts::TAU - SHARED_DISTINCT
    })
}

/// A root's place among the roots one to rounding ([`nearly_repeated`]) of it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Partner {
    /// No other root is one with it.
    Alone,
    /// The first of a pair; the index of the second.
    First(usize),
    /// The second of a pair.
    Second,
    /// One of three or more.
    Many,
}

/// Each root's [`Partner`].
fn repeated_partners(roots: &[f64]) -> Vec<Partner> {
    // Per root: how many others are one with it, and the last of them.
    let near: Vec<(usize, usize)> = roots
        .iter()
        .enumerate()
        .map(|(i, &a)| {
            roots
                .iter()
                .enumerate()
                .filter(|&(j, &b)| j != i && nearly_repeated(a, b))
                .fold((0, i), |(count, _), (j, _)| (count + 1, j))
        })
        .collect();
    near.iter()
        .enumerate()
        .map(|(i, &(count, j))| match count {
            0 => Partner::Alone,
            1 if near[j].0 == 1 && j > i => Partner::First(j),
            1 if near[j].0 == 1 => Partner::Second,
            _ => Partner::Many,
        })
        .collect()
}

/// The quadratic forms `[cos^2, cos sin, sin^2]` that the 2 x 2 minors of the monomial grid
/// (`x4^a x5^b` at `a * 3 + b`) take on the combinations `cos p + sin r`: all vanish on a
/// monomial vector.
fn monomial_minors(p: &[f64; 12], r: &[f64; 12]) -> Vec<[f64; 3]> {
    let mut forms = Vec::with_capacity(18);
    for a0 in 0..4 {
        for a1 in a0 + 1..4 {
            for b0 in 0..3 {
                for b1 in b0 + 1..3 {
                    // v[a0 b0] v[a1 b1] - v[a0 b1] v[a1 b0]
                    let (i, j, k, l) = (a0 * 3 + b0, a1 * 3 + b1, a0 * 3 + b1, a1 * 3 + b0);
                    forms.push([
                        p[i] * p[j] - p[k] * p[l],
                        p[i] * r[j] + r[i] * p[j] - p[k] * r[l] - r[k] * p[l],
                        r[i] * r[j] - r[k] * r[l],
                    ]);
                }
            }
        }
    }
    forms
}

/// The null vector of a matrix singular to rounding, by two steps of inverse iteration (one LU);
/// `None` when the LU breaks down.
fn null_vector(matrix: &Matrix12) -> Option<[f64; 12]> {
    let lu = matrix.lu();
    // Any fixed start with a part along the null vector; generic entries make that sure.
    let mut v = SVector::<f64, 12>::from_fn(|i, _| 1.0 + 0.1 * i as f64);
    for _ in 0..2 {
        v = lu.solve(&v)?;
        let norm = v.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        v /= norm;
    }
    Some(std::array::from_fn(|i| v[i]))
}

/// Angles of joints 4 and 5 from the monomial vector `x4^a x5^b` (index `a * 3 + b`).
fn angles_of_null_vector(null: &[f64; 12]) -> (f64, f64) {
    let at = |a: usize, b: usize| null[a * 3 + b];
    let (mut num4, mut den4, mut num5, mut den5) = (0.0, 0.0, 0.0, 0.0);
    for a in 0..4 {
        for b in 0..3 {
            if a < 3 {
                num4 += at(a + 1, b) * at(a, b);
                den4 += at(a, b) * at(a, b);
            }
            if b < 2 {
                num5 += at(a, b + 1) * at(a, b);
                den5 += at(a, b) * at(a, b);
            }
        }
    }
    let x4 = num4 / den4;
    let x5 = num5 / den5;
    (OFFSETS[1] + 2.0 * x4.atan(), OFFSETS[2] + 2.0 * x5.atan())
}

/// An orthonormal basis (six rows) of the complement of the eight orthonormal columns of `u`.
fn complement_of(u: &SMatrix<f64, 14, 8>) -> [[f64; 14]; 6] {
    let mut basis: Vec<SVector<f64, 14>> = (0..8).map(|j| u.column(j).into_owned()).collect();
    let mut out = [[0.0; 14]; 6];
    let mut found = 0;
    // Standard vectors, most outside the span first.
    let mut order: Vec<(usize, f64)> = (0..14).map(|k| (k, 1.0 - u.row(k).norm_squared())).collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (k, _) in order {
        if found == 6 {
            break;
        }
        let mut v = SVector::<f64, 14>::zeros();
        v[k] = 1.0;
        for _ in 0..2 {
            for b in &basis {
                let along = b.dot(&v);
                v -= b * along;
            }
        }
        let norm = v.norm();
        if norm > 0.1 {
            v /= norm;
            out[found] = std::array::from_fn(|i| v[i]);
            basis.push(v);
            found += 1;
        }
    }
    out
}

/// The eliminated system of one pose.
struct System {
    /// `[equation][{1, s3, c3}][{1, s4, c4} x {1, s5, c5}]`.
    equations: [[[f64; 9]; 3]; 6],
    /// The pseudo-inverse of the right side's eight products of joints 1 and 2 (full rank).
    products_inverse: SMatrix<f64, 8, 14>,
    /// The right side's coefficients, the constant first.
    right: [[f64; 9]; 14],
    /// The six rows (orthonormal where chosen afresh) the equations take of the fourteen.
    complement: [[f64; 14]; 6],
}

type Matrix12 = SMatrix<f64, 12, 12>;
type Matrix8 = SMatrix<f64, 8, 8>;
/// A matrix quadratic's coefficients of `x^0, x^1, x^2`.
type Quadratic = [Matrix12; 3];

impl System {
    /// The 12 x 12 matrix's coefficients of `x3^0, x3^1, x3^2` for joint 3's tangent offset.
    fn quadratic(&self, offset3: f64) -> Quadratic {
        quadratic_of(&self.equations, offset3)
    }

    /// The matrix at `x3` for the first offset.
    fn at(&self, x3: f64) -> Matrix12 {
        self.at_offset(OFFSETS[0], x3)
    }

    fn at_offset(&self, offset3: f64, x3: f64) -> Matrix12 {
        let [c, b, a] = self.quadratic(offset3);
        c + b * x3 + a * (x3 * x3)
    }

    /// Joints 1 and 2 from the left side's values at joints 3 to 5: the products solved for.
    fn first_two(&self, left: &[f64; 14]) -> Option<(f64, f64)> {
        let rhs = SVector::<f64, 14>::from_fn(|k, _| left[k] - self.right[k][0]);
        let y = self.products_inverse * rhs;
        if !y.iter().all(|v| v.is_finite()) {
            return None;
        }
        // Columns: f1 * 3 + f2 - 1 with f in {1, sin, cos}.
        let (s2, c2) = (y[0], y[1]);
        let (s1, c1) = (y[2], y[5]);
        Some((s1.atan2(c1), s2.atan2(c2)))
    }
}

impl Chain {
    /// The fourteen quantities of the kept joints' turns (`e3 e4 e5` for block 2) at `angles`
    /// applied to the carried line (joint 6's for block 2), about a point of the first kept
    /// joint's line.
    fn left(&self, block: usize, angles: [f64; 3]) -> [f64; 14] {
        let carried = &self.lines[block + 3];
        let (mut point, mut direction) = (carried.point, carried.axis);
        for (line, angle) in self.lines[block..block + 3].iter().zip(angles).rev() {
            point = line.turn(angle, &point);
            direction = line.rotation(angle) * direction;
        }
        fourteen(&(point - self.lines[block].point), &direction)
    }

    /// The fourteen quantities of the other side applied to the carried line, with the
    /// eliminated joints at `angles`: `e2^-1 e1^-1 D` for block 2, `e1^-1 D e6^-1` for 1 and
    /// `D e6^-1 e5^-1` for 0, where `D = T M^-1` maps `x` to `relative (x - M) + translation`.
    fn right(&self, block: usize, angles: [f64; 2], relative: &Matrix3<f64>, translation: &Vector3<f64>) -> [f64; 14] {
        let [a, _] = eliminated(block);
        let angle = |joint: usize| if joint == a { angles[0] } else { angles[1] };
        let carried = &self.lines[block + 3];
        let (mut point, mut direction) = (carried.point, carried.axis);
        for joint in block + 4..6 {
            let line = &self.lines[joint];
            point = line.turn(-angle(joint), &point);
            direction = line.rotation(-angle(joint)) * direction;
        }
        point = relative * (point - self.home_translation) + translation;
        direction = relative * direction;
        for joint in 0..block {
            let line = &self.lines[joint];
            point = line.turn(-angle(joint), &point);
            direction = line.rotation(-angle(joint)) * direction;
        }
        fourteen(&(point - self.lines[block].point), &direction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The deflated eigenvalues are the whole companion's less eight or more at `+-i`, matched
    /// one to one, on random poses at every offset, for shipped arms whose eliminations keep joints 3
    /// to 5 (a general arm), 2 to 4 (a UR type) and, reversed, 1 to 3 (a spherical wrist).
    #[test]
    fn the_deflation_takes_out_the_eight_roots_at_plus_minus_i_and_no_other() {
        let mut blocks = Vec::new();
        for design in ["free-offset-6dof", "ur5e", "economic-spherical-wrist"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("designs/{design}.json"));
            let model = crate::pipeline::load_model(&path, &Default::default()).expect("shipped design loads");
            let solver = General6R::new(&model).expect("the elimination holds");
            blocks.push((solver.elimination.block, solver.reversed));
            deflation_agrees(&solver.elimination);
        }
        assert_eq!(blocks, [(2, false), (1, false), (0, true)]);
    }

    fn deflation_agrees(elimination: &Elimination) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20 {
            let q: [f64; 6] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
            let (rotation, translation) = elimination.chain.forward(&q);
            let system = elimination.system(&rotation, &translation).expect("a regular pose");
            for (index, &offset) in OFFSETS3.iter().enumerate() {
                let deflation = elimination.deflation(index).expect("the arm's subspace at every offset");
                let [c, b, a] = system.quadratic(offset);
                let deflated = deflation.eigenvalues(&c, &b, &a).expect("the subspace holds at every pose");
                let mut whole = quadratic_eigenvalues(&c, &b, &a).expect("a regular companion");
                assert!(deflated.len() <= 16 && whole.len() == 24);
                // A multiple root at `+-i` with fewer eigenvectors than copies (a UR type's) is
                // split by rounding by a root of the machine epsilon, in either matrix.
                let at_i = |re: f64, im: f64| re.abs() < 1e-4 && (im.abs() - 1.0).abs() < 1e-4;
                for (re, im) in &deflated {
                    let scale = if at_i(*re, *im) { 1e3 } else { 1.0 + re.hypot(*im) };
                    let (nearest, distance) = whole
                        .iter()
                        .enumerate()
                        .map(|(i, w)| (i, (w.0 - re).hypot(w.1 - im)))
                        .min_by(|x, y| x.1.total_cmp(&y.1))
                        .expect("eigenvalues left");
                    assert!(distance <= 1e-7 * scale, "({re}, {im}) is {distance} from the companion's");
                    whole.swap_remove(nearest);
                }
                assert!(whole.iter().all(|&(re, im)| at_i(re, im)), "left: {whole:?}");
            }
        }
    }

    /// A matrix quadratic without the factor keeps its whole companion.
    /// The perturbation's rates of the roots' angles against central differences of the
    /// roots solved again at poses a small step either side (the eigenvalue iteration, an
    /// independent route), on shipped arms (a general one, a UR type, a spherical wrist,
    /// reversed) and random poses, every offset of the pose, each simple root well apart from
    /// the others.
    #[test]
    fn the_roots_move_as_their_perturbation_says() {
        let mut checked = 0;
        for design in ["free-offset-6dof", "ur5e", "economic-spherical-wrist", "paper-real-world"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("designs/{design}.json"));
            let model = crate::pipeline::load_model(&path, &Default::default()).expect("shipped design loads");
            let Some(solver) = General6R::new(&model) else {
                continue;
            };
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
            for _ in 0..10 {
                let tool = model.tool_pose(&model.random_configuration(&mut rng));
                // Off the workspace a little, so that some roots are complex and near real.
                let goal = Isometry3::from_parts(Translation3::from(tool.translation.vector * 1.05), tool.rotation);
                let Some(found) = solver.angles_of_system(&goal, None, true) else {
                    continue;
                };
                let points: Vec<(f64, f64)> = found.roots.iter().map(|r| r.angle).collect();
                for axis in 0..6 {
                    let step = 1e-5;
                    let delta = solver
                        .quadratic_rate(&found, &offset_pose(&goal, axis, POSE_STEP, true))
                        .expect("a regular pose");
                    let either = [step, -step].map(|amount| {
                        solver
                            .angles(&offset_pose(&goal, axis, amount, true), Some(found.index), true)
                            .expect("roots next to the pose")
                            .1
                    });
                    for (i, root) in found.roots.iter().enumerate() {
                        let apart = points
                            .iter()
                            .enumerate()
                            .filter(|(j, _)| *j != i)
                            .map(|(_, p)| angle_distance(p, &root.angle))
                            .fold(f64::INFINITY, f64::min);
                        if root.angle.1.abs() > FAR_FROM_REAL || apart < 0.05 {
                            continue;
                        }
                        let Some(perturbation) = Perturbation::of(&found.quadratic, root.tangent) else {
                            continue;
                        };
                        let rate = perturbation.angle_rate(&delta);
                        let nearest = |roots: &[Root]| {
                            roots
                                .iter()
                                .map(|r| r.angle)
                                .min_by(|a, b| angle_distance(a, &root.angle).total_cmp(&angle_distance(b, &root.angle)))
                                .expect("roots")
                        };
                        let (plus, minus) = (nearest(&either[0]), nearest(&either[1]));
                        let central = (
                            super::super::wrap_angle(plus.0 - minus.0) / (2.0 * step),
                            (plus.1 - minus.1) / (2.0 * step),
                        );
                        let error = (rate.re - central.0).hypot(rate.im - central.1);
                        assert!(
                            error <= 1e-4 * (1.0 + rate.norm()),
                            "{design} axis {axis} root {:?}: perturbation {rate}, differences {central:?}",
                            root.angle
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 500, "{checked} rates checked");
    }

    #[test]
    fn a_quadratic_without_the_factor_has_no_deflation() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let [c, b, a]: Quadratic = std::array::from_fn(|_| Matrix12::from_fn(|_, _| rng.random_range(-1.0..1.0)));
        assert!(Deflation::of(&c, &b, &a).is_none());
    }
}
