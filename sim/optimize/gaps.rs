//! The capsule model's closed-form gaps as one fused candle operation: per sample and candidate,
//! the surface distance of a capsule to another capsule, a rounded obstacle or the floor, with
//! its gradient with respect to the capsule ends.
//!
//! Written as candle ops, each segment pair cost some fifty elementwise tensors of
//! `[samples, pairs]` forward and as many backward; on the CPU the batch's time went to
//! allocating, faulting in and synchronising those, not to arithmetic (batch 4096: 353 ms, 72 ms
//! fused). Fused, the candidates cost one pass each way over the capsule ends, and the rest of
//! the objective (kinematics, pose error, the choice of each pair's closest candidate, the
//! collision cost) stays differentiated by candle. The closest points are
//! `frames::closest_points_of_segments` and the floor's is `collide::capsule_floor`'s, the CPU
//! path's own; the composed-op version this replaces is kept in the tests as the oracle.
//!
//! The gradient holds the closest points fixed on their segments (at the minimum over
//! `(s, t)` the distance is stationary in `s` and `t`, or they sit on a bound): with `n` the unit
//! vector from the first axis's point to the second's, the ends move the distance by
//! `-(1 - s) n`, `-s n` (first) and `(1 - t) n`, `t n` (second). Axes that meet (closer than
//! [`MEET_M`]) have no normal and pass no gradient, as on the CPU path. A floor
//! gap moves with the height of the capsule's lower end.

use crate::frames::closest_parameters_of_segments;
use candle_core::{CpuStorage, CustomOp1, CustomOp2, Device, Layout, Shape, Tensor};
use nalgebra::Vector3;
use std::sync::Arc;

/// Axes closer than this (m) meet: segments joined through a link with `d = a = 0` do, whatever
/// the joints, up to rounding. Their normal is arbitrary, so their distance gets no gradient.
pub(super) const MEET_M: f64 = 1e-9;

/// The other segment of a pair.
#[derive(Debug, Clone, Copy)]
pub(super) enum Other {
    /// Another capsule of the robot, by index.
    Capsule(usize),
    /// A fixed segment in the world (a rounded obstacle's axis).
    Fixed(Vector3<f64>, Vector3<f64>),
    /// The floor at this height (m).
    Floor(f64),
}

/// How one gap moves with the capsule ends.
enum Slope {
    /// Segment pair: the closest points' parameters and the unit normal from the first to the
    /// second (`None` where the axes meet).
    Segments(f64, f64, Option<Vector3<f64>>),
    /// Floor: the index (0 start, 1 end) of the capsule's lower end.
    Floor(usize),
}

/// The candidates measured, in output column order: a capsule, what it is measured against and
/// the radii to take off the axis distance.
#[derive(Debug, Clone)]
pub(super) struct CapsuleGaps {
    pairs: Arc<[(usize, Other, f64)]>,
}

impl CapsuleGaps {
    pub(super) fn new(pairs: Vec<(usize, Other, f64)>) -> Self {
        Self { pairs: pairs.into() }
    }

    /// `[B, candidates]` surface gaps from the capsule ends `[B, capsules, 6]` (start, end).
    pub(super) fn apply(&self, ends: &Tensor) -> candle_core::Result<Tensor> {
        on_cpu(&[ends], |t| t[0].apply_op1(self.clone()))
    }

    /// Candidate `p`'s gap in one sample's ends, and how it moves with them.
    fn measure(&self, ends: &[f64], p: usize) -> (f64, Slope) {
        let end = |capsule: usize, k: usize| {
            let at = capsule * 6 + 3 * k;
            Vector3::new(ends[at], ends[at + 1], ends[at + 2])
        };
        let (capsule, other, radii) = self.pairs[p];
        let (p1, q1) = (end(capsule, 0), end(capsule, 1));
        let (p2, q2) = match other {
            Other::Capsule(j) => (end(j, 0), end(j, 1)),
            Other::Fixed(start, stop) => (start, stop),
            Other::Floor(height) => {
                // As `collide::capsule_floor` picks it.
                let lower = usize::from(q1.z < p1.z);
                return (p1.z.min(q1.z) - radii - height, Slope::Floor(lower));
            }
        };
        let (s, t) = closest_parameters_of_segments(p1, q1, p2, q2);
        let between = (p2 + (q2 - p2) * t) - (p1 + (q1 - p1) * s);
        let distance = between.norm();
        let normal = (distance >= MEET_M).then(|| between / distance);
        (distance - radii, Slope::Segments(s, t, normal))
    }
}

/// `f` on CPU copies of `inputs` (contiguous), its result moved back to their device: the fused
/// kernels have no GPU version, and their few values per sample cross cheaply.
fn on_cpu(inputs: &[&Tensor], f: impl FnOnce(&[Tensor]) -> candle_core::Result<Tensor>) -> candle_core::Result<Tensor> {
    let device = inputs[0].device().clone();
    let local: Vec<Tensor> = inputs
        .iter()
        .map(|t| t.to_device(&Device::Cpu)?.contiguous())
        .collect::<candle_core::Result<_>>()?;
    f(&local)?.to_device(&device)
}

/// The contiguous f64 values of a CPU tensor.
fn values<'a>(storage: &'a CpuStorage, layout: &Layout, what: &str) -> candle_core::Result<&'a [f64]> {
    let CpuStorage::F64(all) = storage else {
        candle_core::bail!("{what}: f64 tensors only")
    };
    let Some((from, to)) = layout.contiguous_offsets() else {
        candle_core::bail!("{what}: contiguous tensors only")
    };
    Ok(&all[from..to])
}

/// `[B, capsules, 6]` as `(B, capsules)`.
fn ends_dims(layout: &Layout) -> candle_core::Result<(usize, usize)> {
    match layout.shape().dims() {
        &[samples, capsules, 6] => Ok((samples, capsules)),
        dims => candle_core::bail!("capsule gaps: capsule ends must be [samples, capsules, 6], got {dims:?}"),
    }
}

impl CustomOp1 for CapsuleGaps {
    fn name(&self) -> &'static str {
        "capsule-gaps"
    }

    fn cpu_fwd(&self, storage: &CpuStorage, layout: &Layout) -> candle_core::Result<(CpuStorage, Shape)> {
        let ends = values(storage, layout, self.name())?;
        let (samples, capsules) = ends_dims(layout)?;
        let count = self.pairs.len();
        let mut out = Vec::with_capacity(samples * count);
        for sample in ends.chunks_exact(capsules * 6) {
            out.extend((0..count).map(|p| self.measure(sample, p).0));
        }
        Ok((CpuStorage::F64(out), Shape::from((samples, count))))
    }

    fn bwd(&self, ends: &Tensor, _res: &Tensor, grad: &Tensor) -> candle_core::Result<Option<Tensor>> {
        let op = CapsuleGapsGrad(self.clone());
        on_cpu(&[ends, grad], |t| t[0].apply_op2_no_bwd(&t[1], &op)).map(Some)
    }
}

/// The backward kernel of [`CapsuleGaps`]: `[B, capsules, 6]` from the ends and `[B, pairs]`.
struct CapsuleGapsGrad(CapsuleGaps);

impl CustomOp2 for CapsuleGapsGrad {
    fn name(&self) -> &'static str {
        "capsule-gaps-grad"
    }

    fn cpu_fwd(&self, s1: &CpuStorage, l1: &Layout, s2: &CpuStorage, l2: &Layout) -> candle_core::Result<(CpuStorage, Shape)> {
        let ends = values(s1, l1, self.name())?;
        let grad = values(s2, l2, self.name())?;
        let (samples, capsules) = ends_dims(l1)?;
        let count = self.0.pairs.len();
        if grad.len() != samples * count {
            candle_core::bail!("capsule gaps: {} gradients for {samples} x {count} pairs", grad.len())
        }
        let mut out = vec![0.0; ends.len()];
        let width = capsules * 6;
        for ((sample, row), into) in ends
            .chunks_exact(width)
            .zip(grad.chunks_exact(count))
            .zip(out.chunks_exact_mut(width))
        {
            for (p, &g) in row.iter().enumerate() {
                if g == 0.0 {
                    continue;
                }
                let (capsule, other, _) = self.0.pairs[p];
                let (s, t, normal) = match self.0.measure(sample, p).1 {
                    Slope::Floor(lower) => {
                        into[capsule * 6 + 3 * lower + 2] += g;
                        continue;
                    }
                    Slope::Segments(_, _, None) => continue,
                    Slope::Segments(s, t, Some(normal)) => (s, t, normal),
                };
                let mut add = |capsule: usize, k: usize, weight: f64| {
                    let at = capsule * 6 + 3 * k;
                    for (slot, n) in into[at..at + 3].iter_mut().zip(normal.iter()) {
                        *slot += weight * n;
                    }
                };
                add(capsule, 0, -g * (1.0 - s));
                add(capsule, 1, -g * s);
                if let Other::Capsule(j) = other {
                    add(j, 0, g * (1.0 - t));
                    add(j, 1, g * t);
                }
            }
        }
        Ok((CpuStorage::F64(out), l1.shape().clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::POINT_SEGMENT_M2;
    use candle_core::Var;
    use rand::{Rng, SeedableRng};

    fn dot(a: &Tensor, b: &Tensor) -> candle_core::Result<Tensor> {
        (a * b)?.sum(a.rank() - 1)
    }

    /// The closest points of segment pairs `[p1, q1]`, `[p2, q2]` (`[B, C, 3]` each) written as
    /// candle ops, branch by branch as masks (the version the fused operation replaced).
    fn closest_points(p1: &Tensor, q1: &Tensor, p2: &Tensor, q2: &Tensor) -> candle_core::Result<(Tensor, Tensor)> {
        let (d1, d2, r) = ((q1 - p1)?, (q2 - p2)?, (p1 - p2)?);
        let (a, e, f) = (dot(&d1, &d1)?, dot(&d2, &d2)?, dot(&d2, &r)?);
        let c = dot(&d1, &r)?;
        let b = dot(&d1, &d2)?;
        let (zero, one) = (a.zeros_like()?, a.ones_like()?);
        let a_point = a.le(POINT_SEGMENT_M2)?;
        let e_point = e.le(POINT_SEGMENT_M2)?;
        // Safe denominators: a branch not taken must not make a NaN that its zero gradient multiplies.
        let safe_a = a_point.where_cond(&one, &a)?;
        let safe_e = e_point.where_cond(&one, &e)?;
        let denominator = ((&a * &e)? - b.sqr()?)?;
        let skew = denominator.gt(0.0)?;
        let safe_denominator = skew.where_cond(&denominator, &one)?;
        let s_general = skew.where_cond(&((((&b * &f)? - (&c * &e)?)? / safe_denominator)?.clamp(0.0, 1.0)?), &zero)?;
        let t_general = (((&b * &s_general)? + &f)? / &safe_e)?;
        let s_before = (c.neg()? / &safe_a)?.clamp(0.0, 1.0)?;
        let s_after = ((&b - &c)? / &safe_a)?.clamp(0.0, 1.0)?;
        let before = t_general.lt(0.0)?;
        let after = t_general.gt(1.0)?;
        let s_both = before.where_cond(&s_before, &after.where_cond(&s_after, &s_general)?)?;
        let t_both = before.where_cond(&zero, &after.where_cond(&one, &t_general)?)?;
        let t_on_second = (&f / &safe_e)?.clamp(0.0, 1.0)?;
        let s = a_point.where_cond(&zero, &e_point.where_cond(&s_before, &s_both)?)?;
        let t = a_point.where_cond(&e_point.where_cond(&zero, &t_on_second)?, &e_point.where_cond(&zero, &t_both)?)?;
        let centre_a = (p1 + d1.broadcast_mul(&s.unsqueeze(2)?)?)?;
        let centre_b = (p2 + d2.broadcast_mul(&t.unsqueeze(2)?)?)?;
        Ok((centre_a, centre_b))
    }

    /// Segment ends in awkward places: random, parallel, crossing, points, touching.
    fn ends(rng: &mut rand_chacha::ChaCha8Rng, samples: usize) -> Vec<f64> {
        let mut out = Vec::new();
        for b in 0..samples {
            let mut v = || {
                Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            };
            let (p1, q1, p2, mut q2) = (v(), v(), v(), v());
            match b % 5 {
                1 => q2 = p2 + (q1 - p1) * 0.7,
                2 => q2 = p2,
                3 => q2 = p2 + (q1 - p1).cross(&Vector3::z()),
                _ => {}
            }
            let third = if b % 5 == 4 { (p1, p1) } else { (v(), v()) };
            for p in [p1, q1, p2, q2, third.0, third.1] {
                out.extend(p.iter());
            }
        }
        out
    }

    #[test]
    fn fused_gaps_equal_the_composed_ops_in_value_and_gradient() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let samples = 500;
        let fixed = (Vector3::new(0.1, 0.2, 0.3), Vector3::new(-0.4, 0.5, 0.2));
        let pairs = vec![
            (0, Other::Capsule(1), 0.1),
            (1, Other::Capsule(2), 0.1),
            (0, Other::Capsule(2), 0.1),
            (2, Other::Fixed(fixed.0, fixed.1), 0.07),
            (0, Other::Floor(-0.3), 0.05),
        ];
        let ends = Var::from_tensor(&Tensor::from_vec(ends(&mut rng, samples), (samples, 3, 6), &Device::Cpu).unwrap()).unwrap();
        let weights = Tensor::from_vec((0..samples * 5).map(|i| 1.0 + (i % 7) as f64).collect(), (samples, 5), &Device::Cpu).unwrap();
        let fused = CapsuleGaps::new(pairs.clone()).apply(ends.as_tensor()).unwrap();
        let fused_grad = (&fused * &weights).unwrap().sum_all().unwrap().backward().unwrap();
        let fused_grad: Vec<f64> = fused_grad.get(ends.as_tensor()).unwrap().flatten_all().unwrap().to_vec1().unwrap();

        let capsule = |c: usize, k: usize| ends.as_tensor().narrow(1, c, 1).unwrap().narrow(2, 3 * k, 3).unwrap();
        let mut columns = Vec::new();
        for &(c, other, radii) in &pairs {
            let (p2, q2) = match other {
                Other::Floor(height) => {
                    let z = |k: usize| capsule(c, k).narrow(2, 2, 1).unwrap().squeeze(2).unwrap();
                    columns.push(((z(0).minimum(&z(1)).unwrap() - radii).unwrap() - height).unwrap());
                    continue;
                }
                Other::Capsule(j) => (capsule(j, 0), capsule(j, 1)),
                Other::Fixed(a, b) => {
                    let at = |v: Vector3<f64>| {
                        Tensor::from_vec(vec![v.x, v.y, v.z], (1, 1, 3), &Device::Cpu)
                            .unwrap()
                            .broadcast_as((samples, 1, 3))
                            .unwrap()
                    };
                    (at(a), at(b))
                }
            };
            let (a, b) = closest_points(&capsule(c, 0), &capsule(c, 1), &p2, &q2).unwrap();
            let between = ((b - a).unwrap().sqr().unwrap().sum(2).unwrap() + 1e-30).unwrap().sqrt().unwrap();
            let meet = between.detach().lt(MEET_M).unwrap();
            columns.push((meet.where_cond(&between.detach(), &between).unwrap() - radii).unwrap());
        }
        let composed = Tensor::cat(&columns, 1).unwrap();
        let composed_grad = (&composed * &weights).unwrap().sum_all().unwrap().backward().unwrap();
        let composed_grad: Vec<f64> = composed_grad
            .get(ends.as_tensor())
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();

        let fused: Vec<f64> = fused.flatten_all().unwrap().to_vec1().unwrap();
        let composed: Vec<f64> = composed.flatten_all().unwrap().to_vec1().unwrap();
        for (i, (f, c)) in fused.iter().zip(&composed).enumerate() {
            assert!((f - c).abs() <= 1e-12, "distance {i}: fused {f} composed {c}");
        }
        // The floor's capsule 0 has random ends, never at one height: no tie for candle to split.
        for (i, (f, c)) in fused_grad.iter().zip(&composed_grad).enumerate() {
            // Parallel axes that overlap have a line of closest pairs: the distance has a kink
            // there (tilting either axis moves the minimum to an end), and each version returns
            // a different one-sided slope.
            if (i / 18) % 5 == 1 {
                continue;
            }
            assert!(
                (f - c).abs() <= 1e-9 * c.abs().max(1.0),
                "gradient {i} (sample {}): fused {f} composed {c}",
                i / 18
            );
        }
    }
}
