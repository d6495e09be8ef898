//! The paper's objective fused: one function per sample computes the forward kinematics, the
//! pose distance, the capsule gaps, each checked pair's closest candidate and the collision cost,
//! and writes the gradient of its loss (the chain rule written out, the closest points held on
//! their segments as `gaps.rs` holds them). On a CUDA GPU it is one kernel per evaluation
//! (`fused.cu`, compiled by NVRTC once per process, a thread per sample); on the CPU the same
//! kernel in Rust (`fused_cpu.rs`), samples in parallel. Both round identically (IEEE basic
//! operations, no contraction, [`super::portable`]'s transcendental functions), so a GPU run
//! reproduces a CPU run bit for bit, through every Adam step. The candle graph
//! ([`super::Tensors`]) computes the same objective with candle's autodiff and is its oracle.
//!
//! Built with candle ops on a GPU instead, a step was hundreds of kernel launches and a host
//! round trip per custom operation, slower than the CPU below a few hundred designs.
//!
//! Obstacles without a closed form (boxes, cylinders, meshes) enter as on the candle path: parry
//! measures a witness per sample and shape candidate on the host (in parallel, one sample per
//! task, so the thread count changes nothing), and the kernel takes the plane through it.

use super::problem::{forward, rot_x, shape_witnesses, Batch, CapsuleKind, Evaluation, Params};
use super::OptimizeError;
use crate::collide::CapsuleOther;
use crate::ik::{COLLISION_THRESHOLD_M, COLLISION_WEIGHT, DISTANCE_WEIGHT, ROTATION_WEIGHT};
use crate::scenario::Tolerance;
use nalgebra::Vector3;
use rayon::prelude::*;

/// The GPU kernel's limits (its per-thread arrays).
#[cfg(feature = "cuda")]
const MAX_DOF: usize = 16;
#[cfg(feature = "cuda")]
const MAX_CAPSULES: usize = 64;
/// Threads per block: the kernel keeps its frames and capsule ends in per-thread memory.
#[cfg(feature = "cuda")]
const BLOCK: u32 = 128;

/// The kernel's constants, as `struct Constants` in `fused.cu`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub(super) struct Constants {
    pub(super) distance_weight: f64,
    pub(super) rotation_weight: f64,
    pub(super) collision_weight: f64,
    pub(super) threshold: f64,
    pub(super) dead_zone: f64,
    pub(super) sqrt_floor: f64,
    pub(super) point_segment_m2: f64,
    pub(super) meet: f64,
}

// SAFETY: plain f64 fields, `repr(C)`, the layout the kernel declares.
#[cfg(feature = "cuda")]
unsafe impl candle_core::cuda_backend::cudarc::driver::DeviceRepr for Constants {}

/// Whether the GPU kernel takes `batch` (its arrays are sized for at most 16 joints and 64
/// capsules; beyond that the CPU evaluates it).
#[cfg(feature = "cuda")]
fn fits(batch: &Batch) -> bool {
    batch.dof <= MAX_DOF && batch.capsules.len() <= MAX_CAPSULES
}

/// The PTX of `fused.cu`, compiled on first use.
#[cfg(feature = "cuda")]
fn ptx() -> Result<&'static str, OptimizeError> {
    use candle_core::cuda_backend::cudarc::nvrtc::{compile_ptx_with_opts, CompileOptions};
    static PTX: std::sync::OnceLock<Result<String, String>> = std::sync::OnceLock::new();
    PTX.get_or_init(|| {
        let options = CompileOptions {
            fmad: Some(false),
            name: Some("fused.cu".into()),
            ..Default::default()
        };
        compile_ptx_with_opts(include_str!("fused.cu"), options)
            .map(|ptx| ptx.to_src())
            .map_err(|e| format!("{e:?}"))
    })
    .as_deref()
    .map_err(|e| OptimizeError::Tensor(candle_core::Error::msg(format!("NVRTC could not compile the fused objective: {e}"))))
}

/// `i` as the kernels' 32-bit index.
fn index(i: usize) -> Result<i32, OptimizeError> {
    i32::try_from(i).map_err(|_| OptimizeError::Batch(format!("{i} does not fit the GPU kernel's indices")))
}

/// Row-major entries of a 3 x 3 matrix.
fn row_major(m: &nalgebra::Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|i| m[(i / 3, i % 3)])
}

/// The kernel's arguments for one evaluation, on the host.
pub(super) struct Inputs {
    /// Samples, joints, capsules, candidates, checked pairs, shape columns.
    pub(super) scalars: [i32; 6],
    pub(super) constants: Constants,
    pub(super) q: Vec<f64>,
    pub(super) d: Vec<f64>,
    pub(super) a: Vec<f64>,
    pub(super) sample_design: Vec<i32>,
    pub(super) sample_goal: Vec<i32>,
    pub(super) design_static: Vec<f64>,
    pub(super) goal_static: Vec<f64>,
    pub(super) capsule_link: Vec<i32>,
    pub(super) capsule_kind: Vec<i32>,
    pub(super) candidate_int: Vec<i32>,
    pub(super) candidate_real: Vec<f64>,
    pub(super) witness: Vec<f64>,
}

impl Inputs {
    /// The arguments for `batch` at `params` (see `fused.cu` for the layout).
    ///
    /// # Errors
    /// [`OptimizeError::Batch`] for counts beyond the kernel's 32-bit indices.
    pub(super) fn new(batch: &Batch, params: &Params) -> Result<Self, OptimizeError> {
        let n = batch.dof;
        let count = batch.samples.len();
        let mut design_static = Vec::with_capacity(batch.designs.len() * (2 * n + 24));
        for frame in &batch.designs {
            design_static.extend(frame.alpha.iter().map(|a| a.cos()));
            design_static.extend(frame.alpha.iter().map(|a| a.sin()));
            design_static.extend(row_major(&frame.world_from_base.rotation.to_rotation_matrix().into_inner()));
            design_static.extend(frame.world_from_base.translation.vector.iter());
            let twist = rot_x(frame.alpha[n - 1]);
            design_static.extend(row_major(&(twist * frame.tool.rotation.to_rotation_matrix().into_inner())));
            design_static.extend((twist * frame.tool.translation.vector).iter());
        }
        let mut goal_static = Vec::with_capacity(batch.targets.len() * 13);
        for target in &batch.targets {
            goal_static.extend(target.position.iter());
            goal_static.extend(row_major(&target.rotation));
            goal_static.push(match target.tolerance {
                Tolerance::Pose => 0.0,
                Tolerance::ZSymmetric => 1.0,
                Tolerance::Position => 2.0,
            });
        }
        let capsule_link = batch.capsules.iter().map(|&(link, _)| index(link)).collect::<Result<Vec<_>, _>>()?;
        let capsule_kind = batch
            .capsules
            .iter()
            .map(|&(_, kind)| match kind {
                CapsuleKind::D => 0,
                CapsuleKind::A => 1,
                CapsuleKind::Point => 2,
            })
            .collect();

        // Candidates grouped by pair, the model's order kept within each (the first strictly
        // smallest is chosen, as on the CPU); shape candidates numbered in the model's order.
        let r = crate::model::PAPER_CAPSULE_RADIUS_M;
        let mut order: Vec<usize> = (0..batch.model.candidates.len()).collect();
        order.sort_by_key(|&i| batch.model.candidates[i].0);
        let mut shape_column = vec![0; batch.model.candidates.len()];
        let mut shape_count = 0;
        for (column, candidate) in shape_column.iter_mut().zip(&batch.model.candidates) {
            if matches!(candidate.2, CapsuleOther::Shape(_)) {
                *column = shape_count;
                shape_count += 1;
            }
        }
        let mut candidate_int = Vec::with_capacity(order.len() * 4);
        let mut candidate_real = Vec::with_capacity(order.len() * 11);
        for &i in &order {
            let (pair, capsule, other) = batch.model.candidates[i];
            let (kind, other_index, reals) = match other {
                CapsuleOther::Capsule(j) => (0, j, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, r + r]),
                CapsuleOther::Rounded { start, end, radius } => (1, 0, [start.x, start.y, start.z, end.x, end.y, end.z, r + radius]),
                CapsuleOther::Floor(height) => (2, 0, [height, 0.0, 0.0, 0.0, 0.0, 0.0, r]),
                CapsuleOther::Shape(_) => (3, shape_column[i], [0.0; 7]),
            };
            candidate_int.extend([index(pair)?, index(capsule)?, kind, index(other_index)?]);
            candidate_real.extend(reals);
            // A rounded obstacle's axis centre and half length, for the far-pair bound.
            let centre = (Vector3::new(reals[0], reals[1], reals[2]) + Vector3::new(reals[3], reals[4], reals[5])) * 0.5;
            let half = (Vector3::new(reals[3], reals[4], reals[5]) - Vector3::new(reals[0], reals[1], reals[2])).norm() * 0.5;
            candidate_real.extend([centre.x, centre.y, centre.z, half]);
        }
        let witness = if shape_count == 0 {
            vec![]
        } else {
            (0..count)
                .into_par_iter()
                .flat_map_iter(|b| {
                    let s = batch.samples[b];
                    let (d, a) = batch.rows(params, s.design);
                    let frames = forward(&batch.designs[s.design], d, a, batch.q(params, b));
                    shape_witnesses(batch, params, b, &frames).into_iter().flatten().flat_map(|w| {
                        [
                            w.distance, w.along, w.normal.x, w.normal.y, w.normal.z, w.centre.x, w.centre.y, w.centre.z,
                        ]
                    })
                })
                .collect()
        };
        Ok(Self {
            scalars: [
                index(count)?,
                index(n)?,
                index(batch.capsules.len())?,
                index(order.len())?,
                index(batch.model.pair_count)?,
                index(shape_count)?,
            ],
            constants: Constants {
                distance_weight: DISTANCE_WEIGHT,
                rotation_weight: ROTATION_WEIGHT,
                collision_weight: COLLISION_WEIGHT,
                threshold: COLLISION_THRESHOLD_M,
                dead_zone: super::POSE_DEAD_ZONE,
                sqrt_floor: super::tensor::SQRT_FLOOR,
                point_segment_m2: crate::frames::POINT_SEGMENT_M2,
                meet: super::gaps::MEET_M,
            },
            q: params.q.clone(),
            d: params.d.clone(),
            a: params.a.clone(),
            sample_design: batch.samples.iter().map(|s| index(s.design)).collect::<Result<_, _>>()?,
            sample_goal: batch.samples.iter().map(|s| index(s.goal)).collect::<Result<_, _>>()?,
            design_static,
            goal_static,
            capsule_link,
            capsule_kind,
            candidate_int,
            candidate_real,
            witness,
        })
    }

    /// Values per sample in the kernel's output.
    fn width(&self) -> usize {
        2 + 3 * self.scalars[1] as usize
    }
}

/// The kernel's output rows as an [`Evaluation`].
fn unpack(values: &[f64], n: usize) -> Evaluation {
    let count = values.len() / (2 + 3 * n);
    let mut evaluation = Evaluation {
        distance: Vec::with_capacity(count),
        collision: Vec::with_capacity(count),
        grad_q: Vec::with_capacity(count * n),
        grad_d: Vec::with_capacity(count * n),
        grad_a: Vec::with_capacity(count * n),
    };
    for row in values.chunks_exact(2 + 3 * n) {
        evaluation.distance.push(row[0]);
        evaluation.collision.push(row[1]);
        evaluation.grad_q.extend_from_slice(&row[2..2 + n]);
        evaluation.grad_d.extend_from_slice(&row[2 + n..2 + 2 * n]);
        evaluation.grad_a.extend_from_slice(&row[2 + 2 * n..]);
    }
    evaluation
}

/// Below this many samples per CPU thread a GPU batch runs on the CPU: a GPU step costs about
/// 0.2 ms whatever the batch (one thread's latency through one sample, and the launches), the
/// CPU about 1 us per sample and thread. Measured on an H200 with 16 cores: 8 designs x 32
/// samples 0.05 s on the GPU, 0.03 s on the CPU; 64 designs 0.06 s against 0.17 s.
#[cfg(feature = "cuda")]
const GPU_FROM_SAMPLES_PER_THREAD: usize = 64;

/// The fused objective (see the module's documentation): on the CPU, or on a CUDA GPU.
#[derive(Debug, Clone, Default)]
pub struct Fused {
    #[cfg(feature = "cuda")]
    gpu: Option<candle_core::CudaDevice>,
    /// Batches of fewer samples run on the CPU (the same bits, sooner).
    #[cfg(feature = "cuda")]
    gpu_from: usize,
}

impl Fused {
    /// On the CPU, samples in parallel (the same bits on any number of threads).
    pub fn cpu() -> Self {
        Self::default()
    }

    /// On CUDA GPU `ordinal`: the same bits as [`Fused::cpu`]. A batch of fewer than 64 samples
    /// per CPU thread runs on the CPU, where it is done sooner (see [`Fused::gpu_always`]).
    ///
    /// # Errors
    /// [`OptimizeError::Tensor`] when there is no such GPU or the crate was built without the
    /// `cuda` feature.
    pub fn cuda(ordinal: usize) -> Result<Self, OptimizeError> {
        let device = candle_core::Device::new_cuda(ordinal)?;
        #[cfg(feature = "cuda")]
        {
            Ok(Self {
                gpu: Some(device.as_cuda_device()?.clone()),
                gpu_from: GPU_FROM_SAMPLES_PER_THREAD * rayon::current_num_threads(),
            })
        }
        #[cfg(not(feature = "cuda"))]
        {
            let _ = device;
            Err(OptimizeError::Tensor(candle_core::Error::msg("built without the `cuda` feature")))
        }
    }
}

impl Fused {
    /// Every batch on the GPU, however small (to time or test the kernels themselves).
    #[must_use]
    pub fn gpu_always(self) -> Self {
        #[cfg(feature = "cuda")]
        {
            Self { gpu_from: 0, ..self }
        }
        #[cfg(not(feature = "cuda"))]
        {
            self
        }
    }

    /// The GPU, where `batch` goes there: within the kernel's limits and not too small.
    #[cfg(feature = "cuda")]
    fn gpu_for(&self, batch: &Batch) -> Option<&candle_core::CudaDevice> {
        self.gpu.as_ref().filter(|_| fits(batch) && batch.samples.len() >= self.gpu_from)
    }
}

impl super::Objective for Fused {
    fn evaluate(&mut self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
        // Beyond the kernel's limits, or for a small batch, the CPU: the same bits.
        #[cfg(feature = "cuda")]
        if let Some(gpu) = self.gpu_for(batch) {
            return evaluate(gpu, batch, params);
        }
        let inputs = Inputs::new(batch, params)?;
        let mut out = vec![0.0; batch.samples.len() * inputs.width()];
        out.par_chunks_mut(inputs.width())
            .enumerate()
            .for_each(|(b, row)| super::fused_cpu::sample(&inputs, b, row));
        Ok(unpack(&out, batch.dof))
    }

    /// On a GPU, where no obstacle needs parry's witnesses from the host: every step on the
    /// device (see `device_loop`).
    fn optimize_whole(
        &mut self,
        batch: &Batch,
        designs: &[crate::design::Design],
        start: &Params,
        opts: &super::OptimizeOptions,
    ) -> Option<Result<super::Optimized, OptimizeError>> {
        #[cfg(feature = "cuda")]
        if let Some(gpu) = self.gpu_for(batch) {
            let shapes = batch.model.candidates.iter().any(|c| matches!(c.2, CapsuleOther::Shape(_)));
            if !shapes && !batch.samples.is_empty() {
                return Some(device_loop(gpu, batch, designs, start, opts));
            }
        }
        let _ = (batch, designs, start, opts);
        None
    }
}

/// A device buffer.
#[cfg(feature = "cuda")]
type Slice<T> = candle_core::cuda_backend::cudarc::driver::CudaSlice<T>;

/// `values` on `gpu`; the device rejects empty buffers, so an unused one gets a placeholder.
#[cfg(feature = "cuda")]
fn upload<T>(gpu: &candle_core::CudaDevice, values: &[T]) -> Result<Slice<T>, OptimizeError>
where
    T: candle_core::cuda_backend::cudarc::driver::DeviceRepr + Default + Clone + 'static,
{
    let placeholder = [T::default()];
    Ok(gpu.clone_htod(if values.is_empty() { &placeholder[..] } else { values })?)
}

/// Blocks of [`BLOCK`] threads for `threads` threads.
#[cfg(feature = "cuda")]
fn grid(threads: usize) -> Result<candle_core::cuda_backend::cudarc::driver::LaunchConfig, OptimizeError> {
    let blocks = u32::try_from(threads.div_ceil(BLOCK as usize))
        .map_err(|_| OptimizeError::Batch(format!("{threads} threads are too many for one launch")))?;
    Ok(candle_core::cuda_backend::cudarc::driver::LaunchConfig {
        grid_dim: (blocks.max(1), 1, 1),
        block_dim: (BLOCK, 1, 1),
        shared_mem_bytes: 0,
    })
}

/// `what`'s launch failure as an error.
#[cfg(feature = "cuda")]
fn failed(what: &str, e: candle_core::cuda_backend::cudarc::driver::DriverError) -> OptimizeError {
    OptimizeError::Tensor(candle_core::Error::msg(format!("launching {what}: {e:?}")))
}

/// The objective kernel's arguments that do not change while a batch is tuned, on the device.
#[cfg(feature = "cuda")]
struct ObjectiveOnDevice<'a> {
    gpu: &'a candle_core::CudaDevice,
    inputs: &'a Inputs,
    sample_design: Slice<i32>,
    sample_goal: Slice<i32>,
    design_static: Slice<f64>,
    goal_static: Slice<f64>,
    capsule_link: Slice<i32>,
    capsule_kind: Slice<i32>,
    candidate_int: Slice<i32>,
    candidate_real: Slice<f64>,
    witness: Slice<f64>,
}

#[cfg(feature = "cuda")]
impl<'a> ObjectiveOnDevice<'a> {
    fn new(gpu: &'a candle_core::CudaDevice, inputs: &'a Inputs) -> Result<Self, OptimizeError> {
        Ok(Self {
            gpu,
            inputs,
            sample_design: upload(gpu, &inputs.sample_design)?,
            sample_goal: upload(gpu, &inputs.sample_goal)?,
            design_static: upload(gpu, &inputs.design_static)?,
            goal_static: upload(gpu, &inputs.goal_static)?,
            capsule_link: upload(gpu, &inputs.capsule_link)?,
            capsule_kind: upload(gpu, &inputs.capsule_kind)?,
            candidate_int: upload(gpu, &inputs.candidate_int)?,
            candidate_real: upload(gpu, &inputs.candidate_real)?,
            witness: upload(gpu, &inputs.witness)?,
        })
    }

    /// The objective of every sample at `q`, `d`, `a` into `out` (rows of `2 + 3 n`).
    fn launch(&self, q: &Slice<f64>, d: &Slice<f64>, a: &Slice<f64>, out: &mut Slice<f64>) -> Result<(), OptimizeError> {
        use candle_core::cuda_backend::cudarc::driver::PushKernelArg;
        let function = self.gpu.get_or_load_custom_func("paper_objective", MODULE, ptx()?)?;
        let mut launch = function.builder();
        for scalar in &self.inputs.scalars {
            launch.arg(scalar);
        }
        launch
            .arg(&self.inputs.constants)
            .arg(q)
            .arg(d)
            .arg(a)
            .arg(&self.sample_design)
            .arg(&self.sample_goal)
            .arg(&self.design_static)
            .arg(&self.goal_static)
            .arg(&self.capsule_link)
            .arg(&self.capsule_kind)
            .arg(&self.candidate_int)
            .arg(&self.candidate_real)
            .arg(&self.witness)
            .arg(out);
        // SAFETY: the arguments are in the kernel's order and types (six ints, the constants,
        // then the device buffers), every buffer holds what the kernel reads for the inputs'
        // samples, and `out` holds a row of `2 + 3 n` values for each.
        unsafe { launch.launch(grid(self.inputs.scalars[0] as usize)?) }.map_err(|e| failed("the fused objective", e))?;
        Ok(())
    }
}

/// The module `fused.cu` is loaded as.
#[cfg(feature = "cuda")]
const MODULE: &str = "proving_ground_fused_objective";

/// `fused.cu`'s `struct Step`: the constants of one step of the optimizer.
#[cfg(feature = "cuda")]
#[repr(C)]
#[derive(Debug, Clone, Copy)]
struct Step {
    n: i32,
    samples: i32,
    designs: i32,
    goals: i32,
    beta1: f64,
    beta2: f64,
    epsilon: f64,
    joint_rate: f64,
    design_rate: f64,
    bias1: f64,
    bias2: f64,
    hardware_weight: f64,
    distance_weight: f64,
    collision_weight: f64,
    max_length: f64,
    economic_lower: f64,
    economic_upper: f64,
}

// SAFETY: four i32 then f64 fields, `repr(C)`, the layout the kernels declare.
#[cfg(feature = "cuda")]
unsafe impl candle_core::cuda_backend::cudarc::driver::DeviceRepr for Step {}

/// Offsets and members of `groups` lists of samples, each in sample order.
#[cfg(feature = "cuda")]
fn compressed(groups: usize, of: impl Fn(usize) -> usize, samples: usize) -> (Vec<i32>, Vec<i32>) {
    let mut members = vec![Vec::new(); groups];
    for b in 0..samples {
        members[of(b)].push(b as i32);
    }
    let mut offsets = vec![0i32];
    for m in &members {
        offsets.push(offsets[offsets.len() - 1] + m.len() as i32);
    }
    (offsets, members.concat())
}

/// [`super::optimize`] with every step on `gpu`: the objective kernel, then `fused.cu`'s
/// `choose`, `keep`, `joint_step` and `design_step`, the same operations in the same order as
/// the CPU's loop, so the result is the CPU's, bit for bit (the CUDA test compares them).
/// Nothing crosses to the host until the end.
#[cfg(feature = "cuda")]
fn device_loop(
    gpu: &candle_core::CudaDevice,
    batch: &Batch,
    designs: &[crate::design::Design],
    start: &Params,
    opts: &super::OptimizeOptions,
) -> Result<super::Optimized, OptimizeError> {
    use candle_core::cuda_backend::cudarc::driver::PushKernelArg;
    let n = batch.dof;
    let count = batch.samples.len();
    let goals = batch.targets.len();
    let inputs = Inputs::new(batch, start)?;
    let width = inputs.width();
    let (free_d, free_a) = super::free_lengths(designs, n, start);
    let flags = |v: &[bool]| v.iter().map(|&f| i32::from(f)).collect::<Vec<i32>>();
    let economic: Vec<i32> = designs
        .iter()
        .map(|d| i32::from(d.mode == crate::design::DesignMode::Economic))
        .collect();
    let limits: Vec<f64> = designs
        .iter()
        .flat_map(|d| d.joints.iter().flat_map(|j| [j.limits[0], j.limits[1]]))
        .collect();
    let (design_offsets, design_samples) = compressed(designs.len(), |b| batch.samples[b].design, count);
    let (slot_offsets, slot_samples) = compressed(
        designs.len() * goals,
        |b| batch.samples[b].design * goals + batch.samples[b].goal,
        count,
    );

    let up = |v: &[f64]| upload(gpu, v);
    let up_i = |v: &[i32]| upload(gpu, v);
    let (mut q, mut d, mut a) = (up(&start.q)?, up(&start.d)?, up(&start.a)?);
    let objective_kernel = ObjectiveOnDevice::new(gpu, &inputs)?;
    let (free_d, free_a, economic, limits) = (up_i(&flags(&free_d))?, up_i(&flags(&free_a))?, up_i(&economic)?, up(&limits)?);
    let (design_offsets, design_samples) = (up_i(&design_offsets)?, up_i(&design_samples)?);
    let (slot_offsets, slot_samples) = (up_i(&slot_offsets)?, up_i(&slot_samples)?);
    let mut out = gpu.alloc_zeros::<f64>(count * width)?;
    let (mut first_q, mut second_q) = (gpu.alloc_zeros::<f64>(start.q.len())?, gpu.alloc_zeros::<f64>(start.q.len())?);
    let rows = start.d.len().max(1);
    let (mut first_d, mut second_d) = (gpu.alloc_zeros::<f64>(rows)?, gpu.alloc_zeros::<f64>(rows)?);
    let (mut first_a, mut second_a) = (gpu.alloc_zeros::<f64>(rows)?, gpu.alloc_zeros::<f64>(rows)?);
    let mut chosen = gpu.alloc_zeros::<i32>(count)?;
    let mut objective = gpu.alloc_zeros::<f64>(designs.len().max(1))?;

    let function = |name: &str| gpu.get_or_load_custom_func(name, MODULE, ptx()?).map_err(OptimizeError::from);
    let (choose, keep, joint_step, design_step) = (
        function("choose")?,
        function("keep")?,
        function("joint_step")?,
        function("design_step")?,
    );
    let (lower, upper) = super::ECONOMIC_RANGE_M;
    let mut step_constants = Step {
        n: index(n)?,
        samples: index(count)?,
        designs: index(designs.len())?,
        goals: index(goals)?,
        beta1: super::BETA1,
        beta2: super::BETA2,
        epsilon: super::EPSILON,
        joint_rate: opts.joint_rate,
        design_rate: opts.design_rate,
        bias1: 1.0,
        bias2: 1.0,
        hardware_weight: crate::ik::HARDWARE_WEIGHT,
        distance_weight: DISTANCE_WEIGHT,
        collision_weight: COLLISION_WEIGHT,
        max_length: crate::limits::MAX_LENGTH_M,
        economic_lower: lower,
        economic_upper: upper,
    };

    // SAFETY (every launch below): the arguments are in each kernel's order and types, and every
    // buffer holds what the kernel reads or writes for `count` samples and the batch's designs.
    let choose_now = |d: &_, a: &_, out: &_, chosen: &mut _, objective: &mut _, s: &Step| -> Result<(), OptimizeError> {
        let mut launch = choose.builder();
        launch
            .arg(s)
            .arg(d)
            .arg(a)
            .arg(out)
            .arg(chosen)
            .arg(objective)
            .arg(&slot_offsets)
            .arg(&slot_samples);
        unsafe { launch.launch(grid(designs.len())?) }.map_err(|e| failed("choose", e))?;
        Ok(())
    };

    objective_kernel.launch(&q, &d, &a, &mut out)?;
    choose_now(&d, &a, &out, &mut chosen, &mut objective, &step_constants)?;
    let initial = gpu.clone_dtoh(&objective)?;
    let (mut best_q, mut best_d, mut best_a) = (up(&start.q)?, up(&start.d)?, up(&start.a)?);
    let mut best_out = gpu.alloc_zeros::<f64>(count * width)?;
    gpu.memcpy_dtod(&out, &mut best_out)?;
    let mut best_objective = up(&initial)?;
    let mut best_step = gpu.alloc_zeros::<i32>(designs.len().max(1))?;

    for step in 1..=opts.steps {
        step_constants.bias1 = 1.0 - super::BETA1.powi(step as i32);
        step_constants.bias2 = 1.0 - super::BETA2.powi(step as i32);
        let s = step_constants;
        let mut launch = design_step.builder();
        launch
            .arg(&s)
            .arg(&mut d)
            .arg(&mut a)
            .arg(&mut first_d)
            .arg(&mut second_d)
            .arg(&mut first_a)
            .arg(&mut second_a)
            .arg(&out)
            .arg(&chosen)
            .arg(&design_offsets)
            .arg(&design_samples)
            .arg(&free_d)
            .arg(&free_a)
            .arg(&economic);
        unsafe { launch.launch(grid(designs.len())?) }.map_err(|e| failed("design_step", e))?;
        let mut launch = joint_step.builder();
        launch
            .arg(&s)
            .arg(&mut q)
            .arg(&mut first_q)
            .arg(&mut second_q)
            .arg(&out)
            .arg(&objective_kernel.sample_design)
            .arg(&limits);
        unsafe { launch.launch(grid(count)?) }.map_err(|e| failed("joint_step", e))?;
        objective_kernel.launch(&q, &d, &a, &mut out)?;
        choose_now(&d, &a, &out, &mut chosen, &mut objective, &s)?;
        let step_index = index(step)?;
        let mut launch = keep.builder();
        launch
            .arg(&s)
            .arg(&step_index)
            .arg(&objective)
            .arg(&mut best_objective)
            .arg(&mut best_step)
            .arg(&q)
            .arg(&d)
            .arg(&a)
            .arg(&out)
            .arg(&mut best_q)
            .arg(&mut best_d)
            .arg(&mut best_a)
            .arg(&mut best_out)
            .arg(&design_offsets)
            .arg(&design_samples);
        unsafe { launch.launch(grid(designs.len())?) }.map_err(|e| failed("keep", e))?;
    }
    let designs_count = designs.len();
    Ok(super::Optimized {
        params: Params {
            q: gpu.clone_dtoh(&best_q)?,
            d: gpu.clone_dtoh(&best_d)?[..start.d.len()].to_vec(),
            a: gpu.clone_dtoh(&best_a)?[..start.a.len()].to_vec(),
        },
        objective: (
            initial[..designs_count].to_vec(),
            gpu.clone_dtoh(&best_objective)?[..designs_count].to_vec(),
        ),
        evaluation: unpack(&gpu.clone_dtoh(&best_out)?, n),
        best_step: gpu.clone_dtoh(&best_step)?[..designs_count].iter().map(|&s| s as usize).collect(),
    })
}

/// `batch` at `params` on `device` (see the module's documentation).
///
/// # Errors
/// [`OptimizeError::Tensor`] when NVRTC, an allocation, a copy or the launch fails.
#[cfg(feature = "cuda")]
fn evaluate(device: &candle_core::CudaDevice, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
    let inputs = Inputs::new(batch, params)?;
    if batch.samples.is_empty() {
        return Ok(unpack(&[], batch.dof));
    }
    let (q, d, a) = (upload(device, &inputs.q)?, upload(device, &inputs.d)?, upload(device, &inputs.a)?);
    let mut out = device.alloc_zeros::<f64>(batch.samples.len() * inputs.width())?;
    ObjectiveOnDevice::new(device, &inputs)?.launch(&q, &d, &a, &mut out)?;
    Ok(unpack(&device.clone_dtoh(&out)?, batch.dof))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::{Objective, OptimizeOptions, Tensors};
    use rand::{Rng, SeedableRng};
    use std::io::Write;
    use std::path::Path;

    impl Inputs {
        /// The arguments as `fused_host.cpp` reads them.
        fn write(&self, path: &Path) -> std::io::Result<()> {
            let mut out = Vec::new();
            self.scalars.iter().for_each(|v| out.extend(v.to_le_bytes()));
            let c = self.constants;
            for v in [
                c.distance_weight,
                c.rotation_weight,
                c.collision_weight,
                c.threshold,
                c.dead_zone,
                c.sqrt_floor,
                c.point_segment_m2,
                c.meet,
            ] {
                out.extend(v.to_le_bytes());
            }
            let reals = [&self.q, &self.d, &self.a];
            let ints = [&self.sample_design, &self.sample_goal];
            let statics = [&self.design_static, &self.goal_static];
            let capsules = [&self.capsule_link, &self.capsule_kind, &self.candidate_int];
            let tail = [&self.candidate_real, &self.witness];
            let f64s = |out: &mut Vec<u8>, v: &Vec<f64>| {
                out.extend((v.len() as u64).to_le_bytes());
                v.iter().for_each(|x| out.extend(x.to_le_bytes()));
            };
            let i32s = |out: &mut Vec<u8>, v: &Vec<i32>| {
                out.extend((v.len() as u64).to_le_bytes());
                v.iter().for_each(|x| out.extend(x.to_le_bytes()));
            };
            reals.iter().for_each(|v| f64s(&mut out, v));
            ints.iter().for_each(|v| i32s(&mut out, v));
            statics.iter().for_each(|v| f64s(&mut out, v));
            capsules.iter().for_each(|v| i32s(&mut out, v));
            tail.iter().for_each(|v| f64s(&mut out, v));
            std::fs::File::create(path)?.write_all(&out)
        }
    }

    /// The five outputs of two evaluations side by side.
    fn fields<'a>(x: &'a Evaluation, y: &'a Evaluation) -> [(&'static str, &'a [f64], &'a [f64]); 5] {
        [
            ("distance", &x.distance, &y.distance),
            ("collision", &x.collision, &y.collision),
            ("grad q", &x.grad_q, &y.grad_q),
            ("grad d", &x.grad_d, &y.grad_d),
            ("grad a", &x.grad_a, &y.grad_a),
        ]
    }

    /// The kernel, compiled for the CPU with the system's C++ compiler, against its Rust port
    /// (bit for bit) and the candle graph (to 1e-9), on designs of 4 to 7 joints,
    /// spheres, boxes and cylinders, the floor, pose, z-symmetric and position goals, IK starts
    /// (at the dead zone) and random configurations (in collision).
    #[test]
    fn the_kernel_is_its_rust_port_and_computes_what_the_candle_graph_computes() {
        let compiler = std::env::var("CXX").unwrap_or_else(|_| "c++".into());
        let dir = tempfile::tempdir().expect("temporary folder");
        let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/optimize");
        let host = dir.path().join("fused_host");
        let built = std::process::Command::new(&compiler)
            .args(["-O2", "-ffp-contract=off", "-std=c++17", "-o"])
            .arg(&host)
            .arg(here.join("fused_host.cpp"))
            .status();
        match built {
            Ok(status) => assert!(status.success(), "{compiler} could not build fused_host.cpp"),
            Err(why) => {
                eprintln!("skipped: no C++ compiler `{compiler}` to build the kernel for the CPU ({why})");
                return;
            }
        }
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let cases = [
            ("free-offset-6dof.json", "scenarios/cluttered/task-00.json", None),
            ("free-redundant-7dof.json", "scenarios/cluttered/task-05.json", None),
            ("economic-elbow.json", "scenarios/cluttered/task-11.json", None),
            ("modular-elbow.json", "scenarios/course.json", None),
            ("paper-real-world.json", "scenarios/course.json", None),
            (
                "free-offset-6dof.json",
                "scenarios/cluttered/task-03.json",
                Some(Tolerance::Position),
            ),
            (
                "economic-scara.json",
                "scenarios/cluttered/task-07.json",
                Some(Tolerance::ZSymmetric),
            ),
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(25);
        let (mut colliding, mut shapes, mut worst) = (0, 0, 0.0f64);
        for (design, scenario, tolerance) in cases {
            let design = crate::design::load(&repo.join("designs").join(design)).expect("shipped design");
            let mut scenario = crate::pipeline::load_scenario(&repo.join(scenario)).expect("shipped scenario");
            if let Some(tolerance) = tolerance {
                scenario.goals.iter_mut().for_each(|g| g.tolerance = tolerance);
            }
            let opts = OptimizeOptions {
                seeds: 2,
                ..Default::default()
            };
            let (batch, mut params) = crate::optimize::starts(&design, &scenario, &opts).expect("starts");
            // Every other sample moved away from its start, half of those far.
            for (b, q) in params.q.chunks_mut(batch.dof).enumerate() {
                let reach = [0.0, 0.05, 0.0, 1.5][b % 4];
                q.iter_mut().for_each(|v| *v += rng.random_range(-1.0..=1.0) * reach);
            }
            let inputs = Inputs::new(&batch, &params).expect("inputs");
            shapes += inputs.scalars[5];
            let (input, output) = (dir.path().join("in.bin"), dir.path().join("out.bin"));
            inputs.write(&input).expect("write the inputs");
            let ran = std::process::Command::new(&host)
                .arg(&input)
                .arg(&output)
                .status()
                .expect("run fused_host");
            assert!(ran.success());
            let bytes = std::fs::read(&output).expect("output");
            let values: Vec<f64> = bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect();
            let kernel = unpack(&values, batch.dof);
            // The Rust port is the kernel, to the bit.
            let port = Fused::cpu().evaluate(&batch, &params).expect("fused on the CPU");
            for (what, ours, theirs) in fields(&port, &kernel) {
                let differ = ours.iter().zip(theirs).position(|(a, b)| a.to_bits() != b.to_bits());
                assert!(
                    differ.is_none(),
                    "{} on {}: {what}[{differ:?}] differs from fused.cu's",
                    design.name,
                    scenario.name
                );
            }
            // The candle graph: the same objective, up to the rounding of other transcendental
            // functions and of another order of the chain rule.
            let candle = Tensors::default().evaluate(&batch, &params).expect("candle");
            colliding += candle.collision.iter().filter(|&&c| c > 0.0).count();
            for (what, ours, theirs) in fields(&port, &candle) {
                assert_eq!(ours.len(), theirs.len(), "{what}");
                for (i, (a, b)) in ours.iter().zip(theirs).enumerate() {
                    // Just beyond the dead zone the position's gradient is the direction of a
                    // residual of a few nm, which the last bits of the kinematics (other sines
                    // here) turn by up to 1e-16 / residual: 1e-7 at 2e-9 m (an IK start's).
                    let sample = if ours.len() == batch.samples.len() { i } else { i / batch.dof };
                    if port.distance[sample] < 1e-6 {
                        continue;
                    }
                    worst = worst.max((a - b).abs() / b.abs().max(1.0));
                    assert!(
                        (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                        "{} on {}: {what}[{i}] fused {a} candle {b}",
                        design.name,
                        scenario.name
                    );
                }
            }
        }
        eprintln!("fused against candle: {worst:e} apart at most (relative to the larger of 1 and the value)");
        assert!(
            colliding > 20 && shapes > 0,
            "{colliding} samples in collision, {shapes} shape columns: too little checked"
        );
    }
}
