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
        let index = |i: usize| i32::try_from(i).map_err(|_| OptimizeError::Batch(format!("{i} does not fit the GPU kernel's indices")));
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
        let mut candidate_real = Vec::with_capacity(order.len() * 7);
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

/// The fused objective (see the module's documentation): on the CPU, or on a CUDA GPU.
#[derive(Debug, Clone, Default)]
pub struct Fused {
    #[cfg(feature = "cuda")]
    gpu: Option<candle_core::CudaDevice>,
}

impl Fused {
    /// On the CPU, samples in parallel (the same bits on any number of threads).
    pub fn cpu() -> Self {
        Self::default()
    }

    /// On CUDA GPU `ordinal`: the same bits as [`Fused::cpu`].
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
            })
        }
        #[cfg(not(feature = "cuda"))]
        {
            let _ = device;
            Err(OptimizeError::Tensor(candle_core::Error::msg("built without the `cuda` feature")))
        }
    }
}

impl super::Objective for Fused {
    fn evaluate(&mut self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
        // Beyond the kernel's limits the CPU evaluates it: the same bits, only slower.
        #[cfg(feature = "cuda")]
        if let (Some(gpu), true) = (&self.gpu, fits(batch)) {
            return evaluate(gpu, batch, params);
        }
        let inputs = Inputs::new(batch, params)?;
        let mut out = vec![0.0; batch.samples.len() * inputs.width()];
        out.par_chunks_mut(inputs.width())
            .enumerate()
            .for_each(|(b, row)| super::fused_cpu::sample(&inputs, b, row));
        Ok(unpack(&out, batch.dof))
    }
}

/// `batch` at `params` on `device` (see the module's documentation).
///
/// # Errors
/// [`OptimizeError::Tensor`] when NVRTC, an allocation, a copy or the launch fails.
#[cfg(feature = "cuda")]
fn evaluate(device: &candle_core::CudaDevice, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
    use candle_core::cuda_backend::cudarc::driver::{LaunchConfig, PushKernelArg};
    let inputs = Inputs::new(batch, params)?;
    let count = batch.samples.len();
    if count == 0 {
        return Ok(unpack(&[], batch.dof));
    }
    // The device rejects empty buffers: an unused one gets a placeholder.
    let up = |v: &[f64]| device.clone_htod(if v.is_empty() { &[0.0][..] } else { v });
    let up_i = |v: &[i32]| device.clone_htod(if v.is_empty() { &[0][..] } else { v });
    let (q, d, a) = (up(&inputs.q)?, up(&inputs.d)?, up(&inputs.a)?);
    let (sample_design, sample_goal) = (up_i(&inputs.sample_design)?, up_i(&inputs.sample_goal)?);
    let (design_static, goal_static) = (up(&inputs.design_static)?, up(&inputs.goal_static)?);
    let (capsule_link, capsule_kind) = (up_i(&inputs.capsule_link)?, up_i(&inputs.capsule_kind)?);
    let (candidate_int, candidate_real) = (up_i(&inputs.candidate_int)?, up(&inputs.candidate_real)?);
    let witness = up(&inputs.witness)?;
    let mut out = device.alloc_zeros::<f64>(count * inputs.width())?;

    let function = device.get_or_load_custom_func("paper_objective", "proving_ground_fused_objective", ptx()?)?;
    let mut launch = function.builder();
    for scalar in &inputs.scalars {
        launch.arg(scalar);
    }
    launch
        .arg(&inputs.constants)
        .arg(&q)
        .arg(&d)
        .arg(&a)
        .arg(&sample_design)
        .arg(&sample_goal)
        .arg(&design_static)
        .arg(&goal_static)
        .arg(&capsule_link)
        .arg(&capsule_kind)
        .arg(&candidate_int)
        .arg(&candidate_real)
        .arg(&witness)
        .arg(&mut out);
    let blocks = u32::try_from(count.div_ceil(BLOCK as usize))
        .map_err(|_| OptimizeError::Batch(format!("{count} samples are too many for one launch")))?;
    let config = LaunchConfig {
        grid_dim: (blocks, 1, 1),
        block_dim: (BLOCK, 1, 1),
        shared_mem_bytes: 0,
    };
    // SAFETY: the arguments are in the kernel's order and types (six ints, the constants, then
    // the device buffers), every buffer holds what the kernel reads for `count` samples, and
    // `out` holds `count * width` values.
    unsafe { launch.launch(config) }
        .map_err(|e| OptimizeError::Tensor(candle_core::Error::msg(format!("launching the fused objective: {e:?}"))))?;
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
