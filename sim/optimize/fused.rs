//! The objective on a CUDA GPU as one kernel per evaluation (`fused.cu`, compiled by NVRTC once
//! per process): a thread per sample computes the forward kinematics, the pose distance, the
//! capsule gaps, each checked pair's closest candidate and the collision cost, and writes the
//! gradient of its loss. Built with candle ops instead, a step was hundreds of kernel launches
//! and a host round trip per custom operation, slower than the CPU below a few hundred designs.
//!
//! Obstacles without a closed form (boxes, cylinders, meshes) enter as on the CPU path: parry
//! measures a witness per sample and shape candidate on the host (in parallel, one sample per
//! task, so the thread count changes nothing), and the kernel takes the plane through it.

#![cfg_attr(not(feature = "cuda"), allow(dead_code))]

use super::problem::{forward, rot_x, shape_witnesses, Batch, CapsuleKind, Evaluation, Params};
use super::OptimizeError;
use crate::collide::CapsuleOther;
use crate::ik::{COLLISION_THRESHOLD_M, COLLISION_WEIGHT, DISTANCE_WEIGHT, ROTATION_WEIGHT};
use crate::scenario::Tolerance;
use rayon::prelude::*;

/// The kernel's limits (its per-thread arrays).
const MAX_DOF: usize = 16;
const MAX_CAPSULES: usize = 64;
/// Threads per block: the kernel keeps its frames and capsule ends in per-thread memory.
#[cfg(feature = "cuda")]
const BLOCK: u32 = 128;

/// The kernel's constants, as `struct Constants` in `fused.cu`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
struct Constants {
    distance_weight: f64,
    rotation_weight: f64,
    collision_weight: f64,
    threshold: f64,
    dead_zone: f64,
    sqrt_floor: f64,
    point_segment_m2: f64,
    meet: f64,
}

// SAFETY: plain f64 fields, `repr(C)`, the layout the kernel declares.
#[cfg(feature = "cuda")]
unsafe impl candle_core::cuda_backend::cudarc::driver::DeviceRepr for Constants {}

/// Whether the fused kernel takes `batch` (its arrays are sized for at most 16 joints and 64
/// capsules; beyond that the candle graph evaluates it).
pub(super) fn fits(batch: &Batch) -> bool {
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
    scalars: [i32; 6],
    constants: Constants,
    q: Vec<f64>,
    d: Vec<f64>,
    a: Vec<f64>,
    sample_design: Vec<i32>,
    sample_goal: Vec<i32>,
    design_static: Vec<f64>,
    goal_static: Vec<f64>,
    capsule_link: Vec<i32>,
    capsule_kind: Vec<i32>,
    candidate_int: Vec<i32>,
    candidate_real: Vec<f64>,
    witness: Vec<f64>,
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

/// `batch` at `params` on `device` (see the module's documentation).
///
/// # Errors
/// [`OptimizeError::Tensor`] when NVRTC, an allocation, a copy or the launch fails.
#[cfg(feature = "cuda")]
pub(super) fn evaluate(device: &candle_core::CudaDevice, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError> {
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

    /// The largest difference relative to the largest magnitude of either.
    fn normwise(ours: &[f64], theirs: &[f64]) -> f64 {
        let scale = ours.iter().chain(theirs).fold(0.0f64, |m, x| m.max(x.abs()));
        let apart = ours.iter().zip(theirs).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        apart / scale.max(f64::MIN_POSITIVE)
    }

    /// The kernel, compiled for the CPU with the system's C++ compiler, against the candle
    /// objective: the same values and gradients up to rounding, on designs of 5 to 7 joints,
    /// spheres, boxes and cylinders, the floor, pose, z-symmetric and position goals, IK starts
    /// (at the dead zone) and random configurations (in collision).
    #[test]
    fn the_kernel_computes_what_the_candle_objective_computes() {
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
        let (mut colliding, mut shapes) = (0, 0);
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
            let candle = Tensors::default().evaluate(&batch, &params).expect("candle");
            colliding += candle.collision.iter().filter(|&&c| c > 0.0).count();
            for (what, ours, theirs) in [
                ("distance", &kernel.distance, &candle.distance),
                ("collision", &kernel.collision, &candle.collision),
                ("grad q", &kernel.grad_q, &candle.grad_q),
                ("grad d", &kernel.grad_d, &candle.grad_d),
                ("grad a", &kernel.grad_a, &candle.grad_a),
            ] {
                assert_eq!(ours.len(), theirs.len(), "{what}");
                let apart = normwise(ours, theirs);
                eprintln!("{} on {}: {what} {apart:e} apart", design.name, scenario.name);
                assert!(apart <= 1e-12, "{} on {}: {what} {apart:e} apart", design.name, scenario.name);
            }
        }
        assert!(
            colliding > 20 && shapes > 0,
            "{colliding} samples in collision, {shapes} shape columns: too little checked"
        );
    }
}
