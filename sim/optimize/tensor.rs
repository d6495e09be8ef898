//! The paper's objective as candle-core tensors, batched over samples (designs x goals x
//! starts), differentiated by candle's backward pass: DH forward kinematics, the pose distance
//! per tolerance mode, the capsule model's collision cost, in f64.
//!
//! The closed-form gaps (capsule to capsule, rounded obstacle or floor) are one fused operation
//! with its own backward kernel (`sim/optimize/gaps.rs`), the CPU path's closest points; boxes,
//! cylinders and meshes enter as the plane through parry's witness (see
//! [`super::problem::Witness`]). No matrix product or parallel reduction is used (products are
//! broadcast multiplies summed over a dimension of 3, in order), so the numbers do not depend on
//! the thread count.

use super::gaps::{CapsuleGaps, Other};
use super::problem::{forward, rot_x, shape_witnesses, Batch, CapsuleKind, Evaluation, Params};
use super::{Objective, OptimizeError};
use crate::collide::CapsuleOther;
use crate::ik::{COLLISION_THRESHOLD_M, COLLISION_WEIGHT, DISTANCE_WEIGHT, ROTATION_WEIGHT};
use crate::model::PAPER_CAPSULE_RADIUS_M;
use crate::scenario::Tolerance;
use candle_core::{CpuStorage, CustomOp2, DType, Device, Layout, Shape, Tensor, Var};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

/// Added under every square root so that a zero gradient through it stays 0, not NaN; it moves
/// a value by at most 1e-15 m.
pub(super) const SQRT_FLOOR: f64 = 1e-30;
/// Distance (m) of a pair without candidates: far beyond the collision threshold.
const FAR_M: f64 = 1e3;

/// Samples per graph on the CPU (see [`Tensors::with_chunk`]): batch 4096 of a design with 117
/// capsule candidates took 43 ms in chunks of 1024, 44 ms of 512, 47 ms of 256, 53 ms of 128
/// (`cargo bench --bench optimize`). At 512 a `[samples, candidates]` tensor of that size stays
/// under candle's threshold for its thread pool (64K elements), whose spinning barriers cost more
/// than they gave on two cores.
const CPU_CHUNK: usize = 512;

/// The candle backend, on a device (CPU by default; a CUDA GPU with the `cuda` feature).
#[derive(Debug, Clone)]
pub struct Tensors {
    device: Device,
    chunk: usize,
}

impl Default for Tensors {
    fn default() -> Self {
        Self::on(Device::Cpu)
    }
}

impl Tensors {
    /// The backend on `device`: on the CPU a batch is evaluated 512 samples per graph (chunks in
    /// parallel), on a GPU whole. [`super::Fused`] is the fast path on either.
    pub fn on(device: Device) -> Self {
        let chunk = if device.is_cpu() { CPU_CHUNK } else { usize::MAX };
        Self { device, chunk }
    }

    /// The same backend evaluating at most `samples` samples per graph (at least 1). Every
    /// sample's terms and gradients depend on that sample alone, so the answer is the same for
    /// any chunk; on the CPU a small one keeps each operation's tensors in cache instead of
    /// allocating and faulting in fresh pages for a whole batch at every operation.
    pub fn with_chunk(self, samples: usize) -> Self {
        Self {
            chunk: samples.max(1),
            ..self
        }
    }

    /// The backend on CUDA GPU `ordinal`.
    ///
    /// # Errors
    /// [`OptimizeError::Tensor`] when there is no such GPU or the crate was built without the
    /// `cuda` feature.
    pub fn cuda(ordinal: usize) -> Result<Self, OptimizeError> {
        Ok(Self::on(Device::new_cuda(ordinal)?))
    }
}

impl Objective for Tensors {
    fn evaluate(&mut self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
        if batch.samples.len() <= self.chunk {
            return self.evaluate_graph(batch, params);
        }
        let n = batch.dof;
        // Chunks are independent graphs: evaluated in parallel, joined in sample order, so the
        // answer is the same on any number of threads.
        let parts: Vec<Result<Evaluation, OptimizeError>> = batch
            .samples
            .par_chunks(self.chunk)
            .enumerate()
            .map_init(
                || batch.clone(),
                |part, (k, samples)| {
                    part.samples.clear();
                    part.samples.extend_from_slice(samples);
                    let first = k * self.chunk;
                    let rows = Params {
                        q: params.q[first * n..(first + samples.len()) * n].to_vec(),
                        d: params.d.clone(),
                        a: params.a.clone(),
                    };
                    self.evaluate_graph(part, &rows)
                },
            )
            .collect();
        let mut out = Evaluation {
            distance: Vec::with_capacity(batch.samples.len()),
            collision: Vec::with_capacity(batch.samples.len()),
            grad_q: Vec::with_capacity(batch.samples.len() * n),
            grad_d: Vec::with_capacity(batch.samples.len() * n),
            grad_a: Vec::with_capacity(batch.samples.len() * n),
        };
        for e in parts {
            let e = e?;
            out.distance.extend(e.distance);
            out.collision.extend(e.collision);
            out.grad_q.extend(e.grad_q);
            out.grad_d.extend(e.grad_d);
            out.grad_a.extend(e.grad_a);
        }
        Ok(out)
    }
}

impl Tensors {
    /// One graph for the whole of `batch`.
    fn evaluate_graph(&self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
        let graph = Graph::build(batch, params, &self.device)?;
        let total = graph.loss.sum_all()?;
        let grads = total.backward()?;
        let count = batch.samples.len();
        let n = batch.dof;
        let flat = |var: &Var| -> Result<Vec<f64>, OptimizeError> {
            Ok(match grads.get(var.as_tensor()) {
                Some(g) => g.flatten_all()?.to_vec1()?,
                None => vec![0.0; count * n],
            })
        };
        Ok(Evaluation {
            distance: graph.distance.to_vec1()?,
            collision: graph.collision.to_vec1()?,
            grad_q: flat(&graph.q)?,
            grad_d: flat(&graph.d)?,
            grad_a: flat(&graph.a)?,
        })
    }
}

/// The evaluated graph of one batch.
pub struct Graph {
    /// Joint positions, `[samples, dof]`.
    pub q: Var,
    /// DH `d` of each sample's design, `[samples, dof]`.
    pub d: Var,
    /// DH `a` of each sample's design, `[samples, dof]`.
    pub a: Var,
    /// Tool rotation `[samples, 3, 3]` and position `[samples, 3]` in the world.
    pub tool: (Tensor, Tensor),
    /// `d` per sample.
    pub distance: Tensor,
    /// `c_col` per sample.
    pub collision: Tensor,
    /// `w_d d + w_col c_col` per sample.
    pub loss: Tensor,
}

/// `a b` for `[B, 3, 3]` stacks: a broadcast product summed over the inner index.
fn mat_mul(a: &Tensor, b: &Tensor) -> candle_core::Result<Tensor> {
    a.unsqueeze(3)?.broadcast_mul(&b.unsqueeze(1)?)?.sum(2)
}

/// `m v` for `[B, 3, 3]` and `[B, 3]`.
fn mat_vec(m: &Tensor, v: &Tensor) -> candle_core::Result<Tensor> {
    m.broadcast_mul(&v.unsqueeze(1)?)?.sum(2)
}

/// Column `c` of `[B, 3, 3]`, `[B, 3]`.
fn column(m: &Tensor, c: usize) -> candle_core::Result<Tensor> {
    m.narrow(2, c, 1)?.squeeze(2)
}

/// `x` where it exceeds the pose distance's dead zone ([`super::POSE_DEAD_ZONE`]), else 0 with
/// no gradient.
fn beyond_dead_zone(x: &Tensor) -> candle_core::Result<Tensor> {
    let outside = x.gt(super::POSE_DEAD_ZONE)?.to_dtype(x.dtype())?;
    x * outside
}

/// `sqrt(sum(v^2) + SQRT_FLOOR)` over the last dimension.
fn norm(v: &Tensor) -> candle_core::Result<Tensor> {
    (v.sqr()?.sum(v.rank() - 1)? + SQRT_FLOOR)?.sqrt()
}

/// Dot product over the last dimension.
fn dot(a: &Tensor, b: &Tensor) -> candle_core::Result<Tensor> {
    (a * b)?.sum(a.rank() - 1)
}

/// `[B, 3, 3]` from per-sample matrices.
fn matrices(device: &Device, m: &[Matrix3<f64>]) -> candle_core::Result<Tensor> {
    let flat: Vec<f64> = m.iter().flat_map(|m| (0..9).map(move |i| m[(i / 3, i % 3)])).collect();
    Tensor::from_vec(flat, (m.len(), 3, 3), device)
}

/// `[B, 3]` from per-sample vectors.
fn vectors(device: &Device, v: &[Vector3<f64>]) -> candle_core::Result<Tensor> {
    let flat: Vec<f64> = v.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    Tensor::from_vec(flat, (v.len(), 3), device)
}

/// `atan2(y, x)` elementwise with its gradient (candle has no inverse trigonometry).
struct Atan2;

impl CustomOp2 for Atan2 {
    fn name(&self) -> &'static str {
        "atan2"
    }

    fn cpu_fwd(&self, s1: &CpuStorage, l1: &Layout, s2: &CpuStorage, l2: &Layout) -> candle_core::Result<(CpuStorage, Shape)> {
        let (CpuStorage::F64(y), CpuStorage::F64(x)) = (s1, s2) else {
            candle_core::bail!("atan2: f64 tensors only")
        };
        let (Some((y0, y1)), Some((x0, x1))) = (l1.contiguous_offsets(), l2.contiguous_offsets()) else {
            candle_core::bail!("atan2: contiguous tensors only")
        };
        let out = y[y0..y1].iter().zip(&x[x0..x1]).map(|(y, x)| y.atan2(*x)).collect();
        Ok((CpuStorage::F64(out), l1.shape().clone()))
    }

    fn bwd(&self, y: &Tensor, x: &Tensor, _res: &Tensor, grad: &Tensor) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        let r2 = (x.sqr()? + y.sqr()?)?;
        Ok((Some((grad * x)?.div(&r2)?), Some((grad * y)?.neg()?.div(&r2)?)))
    }
}

/// `atan2(y, x)`; on a GPU the few values go through the CPU (the op has no kernel there).
fn atan2(y: &Tensor, x: &Tensor) -> candle_core::Result<Tensor> {
    let device = y.device().clone();
    if device.is_cpu() {
        return y.contiguous()?.apply_op2(&x.contiguous()?, Atan2);
    }
    let (y, x) = (y.to_device(&Device::Cpu)?, x.to_device(&Device::Cpu)?);
    y.contiguous()?.apply_op2(&x.contiguous()?, Atan2)?.to_device(&device)
}

/// Which candidates of the batch are measured how, and where each lands in the distance row.
struct Groups {
    /// Closed-form candidates (capsules, rounded obstacles, the floor): capsule, the other, the
    /// radii to take off the axis distance.
    closed: Vec<(usize, Other, f64)>,
    /// Shape pairs: capsule, candidate index.
    shapes: Vec<(usize, usize)>,
    /// Column of each candidate in `closed ++ shapes`.
    column: Vec<usize>,
}

impl Groups {
    fn of(batch: &Batch) -> Self {
        let r = PAPER_CAPSULE_RADIUS_M;
        let mut closed = vec![];
        let mut shapes = vec![];
        let mut kinds = Vec::new();
        for (index, &(_, capsule, other)) in batch.model.candidates.iter().enumerate() {
            let (other, radii) = match other {
                CapsuleOther::Capsule(j) => (Other::Capsule(j), r + r),
                CapsuleOther::Rounded { start, end, radius } => (Other::Fixed(start, end), r + radius),
                CapsuleOther::Floor(height) => (Other::Floor(height), r),
                CapsuleOther::Shape(_) => {
                    kinds.push((1, shapes.len()));
                    shapes.push((capsule, index));
                    continue;
                }
            };
            kinds.push((0, closed.len()));
            closed.push((capsule, other, radii));
        }
        let offsets = [0, closed.len()];
        let column = kinds.iter().map(|&(kind, i)| offsets[kind] + i).collect();
        Groups { closed, shapes, column }
    }
}

impl Graph {
    /// Builds the forward graph of `batch` at `params` on `device`.
    ///
    /// # Errors
    /// [`OptimizeError::Tensor`] for a failing tensor operation (e.g. out of GPU memory).
    pub fn build(batch: &Batch, params: &Params, device: &Device) -> Result<Self, OptimizeError> {
        let n = batch.dof;
        let count = batch.samples.len();
        let per_sample = |values: &[f64]| -> Vec<f64> {
            batch
                .samples
                .iter()
                .flat_map(|s| values[s.design * n..(s.design + 1) * n].iter().copied())
                .collect()
        };
        let q = Var::from_tensor(&Tensor::from_vec(params.q.clone(), (count, n), device)?)?;
        let d = Var::from_tensor(&Tensor::from_vec(per_sample(&params.d), (count, n), device)?)?;
        let a = Var::from_tensor(&Tensor::from_vec(per_sample(&params.a), (count, n), device)?)?;
        let frames: Vec<_> = batch.samples.iter().map(|s| &batch.designs[s.design]).collect();
        let alpha_cos = |k: usize| Tensor::from_vec(frames.iter().map(|f| f.alpha[k].cos()).collect::<Vec<_>>(), (count, 1), device);
        let alpha_sin = |k: usize| Tensor::from_vec(frames.iter().map(|f| f.alpha[k].sin()).collect::<Vec<_>>(), (count, 1), device);

        // Forward kinematics, link frames 1..=n, as rotation columns: a joint turns x and y
        // about z, a twist turns y and z about x (a few [B, 3] operations each, where a 3 x 3
        // product per joint made and differentiated [B, 3, 3, 3] tensors).
        let base = matrices(
            device,
            &frames
                .iter()
                .map(|f| f.world_from_base.rotation.to_rotation_matrix().into_inner())
                .collect::<Vec<_>>(),
        )?;
        let mut frame = Frame {
            x: column(&base, 0)?,
            y: column(&base, 1)?,
            z: column(&base, 2)?,
            origin: vectors(
                device,
                &frames.iter().map(|f| f.world_from_base.translation.vector).collect::<Vec<_>>(),
            )?,
        };
        let mut links = vec![frame.clone()];
        let row = |t: &Var, k: usize| t.as_tensor().narrow(1, k, 1);
        for k in 0..n {
            if k > 0 {
                frame = frame
                    .along(&row(&d, k - 1)?, &row(&a, k - 1)?)?
                    .twist(&alpha_cos(k - 1)?, &alpha_sin(k - 1)?)?;
            }
            let qk = q.as_tensor().narrow(1, k, 1)?;
            frame = frame.turn(&qk.cos()?, &qk.sin()?)?;
            links.push(frame.clone());
        }
        let last = frame.along(&row(&d, n - 1)?, &row(&a, n - 1)?)?.origin;
        let rotation = Tensor::stack(&[&frame.x, &frame.y, &frame.z], 2)?;
        let last_from_tool: Vec<_> = frames
            .iter()
            .map(|f| rot_x(f.alpha[n - 1]) * f.tool.rotation.to_rotation_matrix().into_inner())
            .collect();
        let tool_offset: Vec<_> = frames.iter().map(|f| rot_x(f.alpha[n - 1]) * f.tool.translation.vector).collect();
        let tool_rotation = mat_mul(&rotation, &matrices(device, &last_from_tool)?)?;
        let tool_position = (last + mat_vec(&rotation, &vectors(device, &tool_offset)?)?)?;

        // Pose distance per tolerance mode.
        let targets: Vec<_> = batch.samples.iter().map(|s| &batch.targets[s.goal]).collect();
        let goal_position = vectors(device, &targets.iter().map(|t| t.position).collect::<Vec<_>>())?;
        let goal_rotation = matrices(device, &targets.iter().map(|t| t.rotation).collect::<Vec<_>>())?;
        let goal_transposed = matrices(device, &targets.iter().map(|t| t.rotation.transpose()).collect::<Vec<_>>())?;
        let position = beyond_dead_zone(&norm(&(&tool_position - &goal_position)?)?)?;
        let error = mat_mul(&goal_transposed, &tool_rotation)?.reshape((count, 9))?;
        let pick = |indices: &[u32]| error.index_select(&Tensor::new(indices, device)?, 1);
        let trace = pick(&[0, 4, 8])?.sum(1)?;
        let skew = (pick(&[7, 2, 3])? - pick(&[5, 6, 1])?)?;
        let angle = beyond_dead_zone(&atan2(&(norm(&skew)? * 0.5)?, &((trace - 1.0)? * 0.5)?)?)?;
        let z_symmetric = ((dot(&column(&goal_rotation, 2)?, &column(&tool_rotation, 2)?)?.neg()? + 1.0)? * 0.5)?;
        let mask = |mode: Tolerance| {
            Tensor::from_vec(
                targets
                    .iter()
                    .map(|t| if t.tolerance == mode { 1.0 } else { 0.0 })
                    .collect::<Vec<f64>>(),
                count,
                device,
            )
        };
        let rotation_distance = ((angle * mask(Tolerance::Pose)?)? + (z_symmetric * mask(Tolerance::ZSymmetric)?)?)?;
        let distance = (position + (rotation_distance * ROTATION_WEIGHT)?)?;

        let collision = collision(batch, params, device, &links, &d, &a)?;
        let loss = ((&distance * DISTANCE_WEIGHT)? + (&collision * COLLISION_WEIGHT)?)?;
        Ok(Self {
            q,
            d,
            a,
            tool: (tool_rotation, tool_position),
            distance,
            collision,
            loss,
        })
    }
}

/// A link frame in the world, `[B, 3]` each: the rotation's columns and the origin.
#[derive(Clone)]
struct Frame {
    x: Tensor,
    y: Tensor,
    z: Tensor,
    origin: Tensor,
}

impl Frame {
    /// The frame turned by the angle of cosine `c` and sine `s` (`[B, 1]`) about its z axis.
    fn turn(&self, c: &Tensor, s: &Tensor) -> candle_core::Result<Self> {
        Ok(Self {
            x: (self.x.broadcast_mul(c)? + self.y.broadcast_mul(s)?)?,
            y: (self.y.broadcast_mul(c)? - self.x.broadcast_mul(s)?)?,
            z: self.z.clone(),
            origin: self.origin.clone(),
        })
    }

    /// The frame turned by the angle of cosine `c` and sine `s` (`[B, 1]`) about its x axis.
    fn twist(&self, c: &Tensor, s: &Tensor) -> candle_core::Result<Self> {
        Ok(Self {
            x: self.x.clone(),
            y: (self.y.broadcast_mul(c)? + self.z.broadcast_mul(s)?)?,
            z: (self.z.broadcast_mul(c)? - self.y.broadcast_mul(s)?)?,
            origin: self.origin.clone(),
        })
    }

    /// The frame moved by `d` along its z axis and `a` along its x axis (`[B, 1]`).
    fn along(&self, d: &Tensor, a: &Tensor) -> candle_core::Result<Self> {
        Ok(Self {
            origin: ((&self.origin + self.x.broadcast_mul(a)?)? + self.z.broadcast_mul(d)?)?,
            ..self.clone()
        })
    }
}

/// The collision cost per sample, `[B]`.
fn collision(batch: &Batch, params: &Params, device: &Device, links: &[Frame], d: &Var, a: &Var) -> Result<Tensor, OptimizeError> {
    let count = batch.samples.len();
    let groups = Groups::of(batch);
    if batch.model.candidates.is_empty() || batch.model.pair_count == 0 {
        return Ok(Tensor::zeros(count, DType::F64, device)?);
    }
    // Capsule ends in the world, [B, K, 3].
    let mut pieces = Vec::new();
    for &(link, kind) in &batch.capsules {
        let Frame { x, z, origin, .. } = &links[link];
        let z = z.broadcast_mul(&d.as_tensor().narrow(1, link - 1, 1)?)?;
        let (start, end) = match kind {
            CapsuleKind::D => (origin.clone(), (origin + &z)?),
            CapsuleKind::A => {
                let start = (origin + &z)?;
                let x = x.broadcast_mul(&a.as_tensor().narrow(1, link - 1, 1)?)?;
                let end = (&start + x)?;
                (start, end)
            }
            CapsuleKind::Point => (origin.clone(), origin.clone()),
        };
        pieces.push(start);
        pieces.push(end);
    }
    // [B, K, 6]: each capsule's start and end.
    let capsule_ends = Tensor::stack(&pieces, 1)?.reshape((count, batch.capsules.len(), 6))?;
    let indices = |values: Vec<u32>| Tensor::from_vec(values.clone(), values.len(), device);
    let mut columns = Vec::new();

    if !groups.closed.is_empty() {
        let gaps = CapsuleGaps::new(groups.closed.clone());
        columns.push(gaps.apply(&capsule_ends)?);
    }
    if !groups.shapes.is_empty() {
        // The plane through each measured witness: d0 - n . (c - c0), c the same point of the axis.
        let mut along = Vec::new();
        let mut measured = Vec::new();
        let mut normal = Vec::new();
        let mut centre = Vec::new();
        for b in 0..count {
            let s = batch.samples[b];
            let (dd, aa) = batch.rows(params, s.design);
            let frames = forward(&batch.designs[s.design], dd, aa, batch.q(params, b));
            let witnesses = shape_witnesses(batch, params, b, &frames);
            for &(_, index) in &groups.shapes {
                let w = witnesses[index].expect("a witness per shape candidate");
                along.push(w.along);
                measured.push(w.distance);
                normal.extend([w.normal.x, w.normal.y, w.normal.z]);
                centre.extend([w.centre.x, w.centre.y, w.centre.z]);
            }
        }
        let m = groups.shapes.len();
        let ia = indices(groups.shapes.iter().map(|s| s.0 as u32).collect())?;
        let chosen = capsule_ends.index_select(&ia, 1)?;
        let (p1, q1) = (chosen.narrow(2, 0, 3)?, chosen.narrow(2, 3, 3)?);
        let along = Tensor::from_vec(along, (count, m, 1), device)?;
        let point = (&p1 + (q1 - &p1)?.broadcast_mul(&along)?)?;
        let offset = (point - Tensor::from_vec(centre, (count, m, 3), device)?)?;
        let moved = dot(&Tensor::from_vec(normal, (count, m, 3), device)?, &offset)?;
        columns.push((Tensor::from_vec(measured, (count, m), device)? - moved)?);
    }
    columns.push(Tensor::full(FAR_M, (count, 1), device)?);
    let row = Tensor::cat(&columns, 1)?;
    let pad = row.dim(1)? - 1;

    // The closest candidate of each checked pair, chosen as the CPU path chooses (the first
    // strictly smallest): a tensor minimum would pass the whole gradient to every tied
    // candidate, and the two segments of a link tie wherever their shared corner is closest.
    let values: Vec<Vec<f64>> = row.detach().to_vec2()?;
    let mut choice = Vec::with_capacity(count * batch.model.pair_count);
    for sample in &values {
        let mut best: Vec<Option<usize>> = vec![None; batch.model.pair_count];
        for (index, &(pair, _, _)) in batch.model.candidates.iter().enumerate() {
            let column = groups.column[index];
            if best[pair].is_none_or(|kept| sample[column] < sample[kept]) {
                best[pair] = Some(column);
            }
        }
        choice.extend(best.into_iter().map(|c| c.unwrap_or(pad) as u32));
    }
    let choice = Tensor::from_vec(choice, (count, batch.model.pair_count), device)?;
    let per_pair = row.gather(&choice, 1)?;
    let e = (-1.0f64).exp();
    let scale = 1.0 / (1.0 - e);
    let loss = ((per_pair * (-1.0 / COLLISION_THRESHOLD_M))?.exp()? - e)?.relu()?;
    Ok((loss.sum(1)? * scale)?)
}
