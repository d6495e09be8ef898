//! Re-checks the general 6R's out-of-reach proofs (first order, see `docs/ik.md`) against the
//! exact solver: a proof says no pose within the goal's tolerance has a solution, so any pose
//! sampled there that has one (FK-verified) refutes it.
//!
//! `cargo run --release --example proof_audit -- [ARMS] [SAMPLES] [SEED]` (defaults 600, 1000,
//! 0). Arms are drawn in turn as random free DH designs, economic ones (the paper's grid, as
//! `python/bench.py` draws them) and arms of the modular catalog. For each, three poses are
//! pushed past the workspace boundary along a random direction of pose space (found by
//! bisection) by 0.3 to 6 times the tolerance, as `tests/general_ik.rs`'s boundary test does;
//! each pose without a solution is asked for the proof over the whole tolerance with the
//! sweep's checks (`out_of_reach_within`) and with a validation's (`out_of_reach_checked`: more
//! poses on the tolerance's boundary), and each proof is re-checked with SAMPLES poses of its
//! tolerance (half on its boundary). Prints the counts and every refuted proof.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proving_ground::ik::general::General6R;
use proving_ground::ik::search::Radii;
use proving_ground::model::Model;
use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;
use std::path::Path;

fn unit_vector(rng: &mut impl Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let norm = v.norm();
        if (0.1..1.0).contains(&norm) {
            return v / norm;
        }
    }
}

fn dh_design(name: &str, rows: &[[f64; 3]]) -> Result<(Model, String), Box<dyn std::error::Error>> {
    let joints: Vec<String> = rows
        .iter()
        .map(|[d, a, alpha]| format!("{{\"d\": {d}, \"a\": {a}, \"alpha\": {alpha}}}"))
        .collect();
    let text = format!("{{\"name\": \"{name}\", \"mode\": \"free\", \"joints\": [{}]}}", joints.join(","));
    let design = proving_ground::design::parse(&text, Path::new("arm.json"))?;
    Ok((proving_ground::model::from_design(&design), text))
}

/// An arm and, for a DH design, its JSON (printed with a refuted proof, to load it again).
fn arm(rng: &mut rand_chacha::ChaCha8Rng, index: usize) -> Result<(Model, String), Box<dyn std::error::Error>> {
    let four_places = |x: f64| (x * 1e4).round() / 1e4;
    Ok(match index % 3 {
        0 => {
            let rows: Vec<[f64; 3]> = (0..6)
                .map(|_| [rng.random_range(-0.3..0.3), rng.random_range(-0.5..0.5), rng.random_range(-PI..PI)].map(four_places))
                .collect();
            dh_design(&format!("random-{index}"), &rows)?
        }
        1 => {
            let rows: Vec<[f64; 3]> = (0..6)
                .map(|_| {
                    [
                        [0.0, 0.1, 0.2, 0.3][rng.random_range(0..4)],
                        [0.0, 0.2, 0.3, 0.4][rng.random_range(0..4)],
                        [0.0, PI / 2.0, -PI / 2.0][rng.random_range(0..3)],
                    ]
                })
                .collect();
            dh_design(&format!("economic-{index}"), &rows)?
        }
        _ => {
            let entry = catalog_entry(&modular6_slots(rng.random_range(0..15_625)));
            (entry.load().model, entry.id)
        }
    })
}

/// Whether some of `samples` poses within the tolerance of `centre` has a solution (FK-checked).
fn refuted(model: &Model, solver: &General6R, centre: &Isometry3<f64>, samples: usize, rng: &mut impl Rng) -> bool {
    (0..samples).any(|k| {
        let (rp, ro) = if k % 2 == 0 {
            (1e-3, 1f64.to_radians())
        } else {
            (1e-3 * rng.random::<f64>(), 1f64.to_radians() * rng.random::<f64>())
        };
        let (u, w) = (unit_vector(rng), unit_vector(rng));
        let sample = Isometry3::from_parts(
            Translation3::from(centre.translation.vector + u * rp),
            centre.rotation * UnitQuaternion::from_scaled_axis(w * ro),
        );
        solver.solve(&sample).configurations.iter().any(|q| {
            let (position, angle) = proving_ground::frames::pose_difference(&model.tool_pose(q), &sample);
            position < 1e-6 && angle < 1e-6
        })
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |k: usize, default: u64| -> Result<u64, Box<dyn std::error::Error>> {
        Ok(args.get(k).map(|a| a.parse::<u64>()).transpose()?.unwrap_or(default))
    };
    let (arms, samples, seed) = (number(0, 600)? as usize, number(1, 1000)? as usize, number(2, 0)?);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut tried, mut proven, mut checked, mut refuted_sweep, mut refuted_checked) = (0, 0, 0, 0, 0);
    for index in 0..arms {
        let (model, text) = arm(&mut rng, index)?;
        let Some(solver) = General6R::new(&model) else { continue };
        for _ in 0..3 {
            let start = model.tool_pose(&model.random_configuration(&mut rng));
            let split: f64 = rng.random_range(0.0..PI / 2.0);
            let (dp, dr) = (
                unit_vector(&mut rng) * (split.cos() * 1e-3),
                unit_vector(&mut rng) * split.sin().to_radians(),
            );
            let along = |s: f64| {
                Isometry3::from_parts(
                    Translation3::from(start.translation.vector + dp * s),
                    start.rotation * UnitQuaternion::from_scaled_axis(dr * s),
                )
            };
            let solvable = |s: f64| !solver.solve(&along(s)).configurations.is_empty();
            let mut high = 1.0;
            while solvable(high) && high < 4096.0 {
                high *= 2.0;
            }
            if high >= 4096.0 {
                continue;
            }
            let mut low = if high > 1.0 { high / 2.0 } else { 0.0 };
            for _ in 0..40 {
                let middle = 0.5 * (low + high);
                if solvable(middle) {
                    low = middle;
                } else {
                    high = middle;
                }
            }
            for beyond in [0.3, 0.95, 1.5, 3.0, 6.0] {
                let centre = along(high + beyond);
                if !solver.solve(&centre).configurations.is_empty() {
                    continue;
                }
                tried += 1;
                let sweep = solver.out_of_reach_within(&centre, Radii::REACHED, 0.0);
                let strict = solver.out_of_reach_checked(&centre, Radii::REACHED, 0.0);
                if sweep.is_none() && strict.is_none() {
                    continue;
                }
                proven += usize::from(sweep.is_some());
                checked += usize::from(strict.is_some());
                // Its own stream: the poses drawn next do not depend on which proofs were given.
                let mut samples_rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ (tried as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
                if refuted(&model, &solver, &centre, samples, &mut samples_rng) {
                    refuted_sweep += usize::from(sweep.is_some());
                    refuted_checked += usize::from(strict.is_some());
                    let t = centre.translation.vector;
                    let r = centre.rotation;
                    println!(
                        "refuted: {text} pose [{}, {}, {}] quaternion [{}, {}, {}, {}] (sweep's proof {}, validation's {})",
                        t.x,
                        t.y,
                        t.z,
                        r.w,
                        r.i,
                        r.j,
                        r.k,
                        if sweep.is_some() { "given" } else { "refused" },
                        if strict.is_some() { "given" } else { "refused" }
                    );
                }
            }
        }
    }
    println!(
        "{tried} poses beyond the boundary; the sweep's proof: {proven} given, {refuted_sweep} refuted; the validation's: {checked} given, {refuted_checked} refuted ({samples} poses re-checked per proof)"
    );
    Ok(())
}
