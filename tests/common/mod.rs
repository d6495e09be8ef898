//! Helpers shared by the integration tests.
#![allow(dead_code, unreachable_pub)]

use proving_ground::collide::{self, CollisionWorld, Distances, QueryOptions};
use proving_ground::engine::{self, EngineRun, GainOptions, Gains};
use proving_ground::model::Model;
use proving_ground::pipeline::{self, LoadOptions};
use proving_ground::plan::{TimedPath, TimingLimits};
use proving_ground::scenario::{generate, Scenario};
use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A free-mode design from standard DH rows `(d, a, alpha)`, one per joint.
pub fn dh_design(name: &str, rows: &[[f64; 3]]) -> Model {
    let joints: Vec<String> = rows
        .iter()
        .map(|[d, a, alpha]| format!("{{\"d\": {d}, \"a\": {a}, \"alpha\": {alpha}}}"))
        .collect();
    let text = format!("{{\"name\": \"{name}\", \"mode\": \"free\", \"joints\": [{}]}}", joints.join(","));
    let design = proving_ground::design::parse(&text, Path::new("arm.json")).expect("design parses");
    proving_ground::model::from_design(&design)
}

/// The real-world URDF shipped in designs/ (Franka Panda, STL collision meshes).
pub fn panda_urdf() -> PathBuf {
    repo().join("designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf")
}

/// Every design JSON in designs/, sorted.
pub fn design_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("designs"))
        .expect("designs/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
}

/// Every shipped robot as `(id, model)`: the designs and the Panda URDF (chain to panda_hand).
pub fn shipped_models() -> Vec<(String, Model)> {
    let mut models: Vec<(String, Model)> = design_files()
        .iter()
        .map(|path| {
            let model = pipeline::load_model(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            (stem(path), model)
        })
        .collect();
    let opts = LoadOptions {
        tip_link: Some("panda_hand".into()),
        ..LoadOptions::default()
    };
    models.push((
        "panda".into(),
        pipeline::load_model(&panda_urdf(), &opts).expect("the Panda URDF loads"),
    ));
    models
}

/// File stem as a string.
pub fn stem(path: &Path) -> String {
    path.file_stem().expect("file has a stem").to_string_lossy().into_owned()
}

/// A fixture under tests/fixtures/.
pub fn fixture(name: &str) -> PathBuf {
    repo().join("tests/fixtures").join(name)
}

/// The paper's robot placed in its course, with the course's collision world.
pub struct Course {
    pub model: Model,
    pub scenario: Scenario,
    pub world: CollisionWorld,
}

/// The paper's robot in its course.
pub fn course() -> Course {
    let model = pipeline::load_model(&repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("shipped design loads");
    let scenario = generate::course(generate::COURSE_SEED);
    let model = model.placed(&scenario.world_from_base);
    let world = pipeline::collision_world(&model, &scenario, &[]).expect("world builds");
    Course { model, scenario, world }
}

/// From the course home through the first `goals` goal configurations, with the gains the
/// engines use for it.
pub fn tour(course: &Course, goals: usize) -> (TimedPath, Gains) {
    let mut waypoints = vec![generate::COURSE_HOME.to_vec()];
    waypoints.extend(generate::course_configurations().into_iter().take(goals));
    let labels: Vec<Option<usize>> = (0..goals).map(Some).collect();
    let path = TimedPath::through(&waypoints, &labels, &TimingLimits::of(&course.model));
    let gains = engine::gains(&course.model, &path, &GainOptions::default());
    (path, gains)
}

/// 41 configurations on the straight joint-space path from the course's goal 12 to goal 23: the
/// two low goals of the box region face each other across the box, so the path runs through it
/// (see scenario/generate/course.rs).
pub fn box_crossing_samples() -> Vec<(f64, Vec<f64>)> {
    let configurations = generate::course_configurations();
    let (from, to) = (&configurations[12], &configurations[23]);
    (0..=40)
        .map(|i| {
            let s = i as f64 / 40.0;
            (s, from.iter().zip(to).map(|(a, b)| a + s * (b - a)).collect())
        })
        .collect()
}

/// Deepest exact (parry3d) penetration per pair over `samples`, sorted by pair names.
pub fn parry_depths(model: &Model, world: &CollisionWorld, samples: &[(f64, Vec<f64>)]) -> Vec<(String, String, f64)> {
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let mut deepest = Vec::new();
    for (_, q) in samples {
        model.forward(q, &mut ws);
        collide::distances(world, &ws.link_in_world, &QueryOptions::default(), &mut out);
        for d in out.within_margin.iter().filter(|d| d.distance < 0.0) {
            let pair = &world.pairs()[d.pair];
            deepen(&mut deepest, &pair.a_name, &pair.b_name, -d.distance);
        }
    }
    deepest.sort_by(|x, y| (&x.0, &x.1).cmp(&(&y.0, &y.1)));
    deepest
}

/// Deepest engine penetration per pair over a run, sorted by pair names.
pub fn engine_depths(run: &EngineRun) -> Vec<(String, String, f64)> {
    let mut deepest = Vec::new();
    for c in &run.contacts {
        deepen(&mut deepest, &c.a, &c.b, c.max_depth_m);
    }
    deepest.sort_by(|x, y| (&x.0, &x.1).cmp(&(&y.0, &y.1)));
    deepest
}

fn deepen(deepest: &mut Vec<(String, String, f64)>, a: &str, b: &str, depth: f64) {
    match deepest.iter_mut().find(|(x, y, _)| x == a && y == b) {
        Some(entry) => entry.2 = entry.2.max(depth),
        None => deepest.push((a.to_string(), b.to_string(), depth)),
    }
}

/// A U-shaped prism (closed, faces outwards), `unit` metres per grid step: 3 x 3 units in x-y
/// with a notch 1 unit wide (x in [1, 2]) and 2 deep opening towards +y, extruded 1 unit along z.
pub fn u_mesh(unit: f64) -> proving_ground::model::TriMesh {
    let outline = [
        [0.0, 0.0],
        [3.0, 0.0],
        [3.0, 3.0],
        [2.0, 3.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 3.0],
        [0.0, 3.0],
    ];
    let cap = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [0, 4, 5], [0, 5, 7], [5, 6, 7]];
    let mut vertices = Vec::new();
    for z in [0.0, 1.0] {
        vertices.extend(outline.iter().map(|[x, y]| [x * unit, y * unit, z * unit]));
    }
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for [a, b, c] in cap {
        triangles.push([a, c, b]); // bottom, facing -z
        triangles.push([a + 8, b + 8, c + 8]); // top, facing +z
    }
    for i in 0..8u32 {
        let j = (i + 1) % 8;
        triangles.push([i, j, j + 8]);
        triangles.push([i, j + 8, i + 8]);
    }
    proving_ground::model::TriMesh {
        uri: "u.stl".into(),
        file: PathBuf::from("u.stl"),
        scale: [1.0; 3],
        vertices,
        triangles,
    }
}

/// A goal at `pose` (FK of some configuration, usually) with `tolerance`.
pub fn pose_goal(
    name: String,
    pose: &nalgebra::Isometry3<f64>,
    tolerance: proving_ground::scenario::Tolerance,
) -> proving_ground::scenario::Goal {
    proving_ground::scenario::Goal {
        name,
        position: pose.translation.vector,
        rotation: pose.rotation,
        tolerance,
        task: None,
    }
}

/// A point uniformly in the ball of `radius`.
pub fn in_ball(rng: &mut impl rand::Rng, radius: f64) -> nalgebra::Vector3<f64> {
    unit(rng) * radius * rng.random::<f64>().cbrt()
}

/// Whether some whole-turn equivalent of `q` is within the model's limits.
pub fn within_limits(model: &Model, q: &[f64]) -> bool {
    model.joints.iter().zip(q).all(|(joint, value)| {
        joint.limits.is_none_or(|[lower, upper]| {
            let k = ((lower - value) / std::f64::consts::TAU).ceil();
            value + k * std::f64::consts::TAU <= upper
        })
    })
}

/// A random unit vector (uniform in direction: rejection from the unit ball).
pub fn unit(rng: &mut impl rand::Rng) -> nalgebra::Vector3<f64> {
    loop {
        let v = nalgebra::Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let n: f64 = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

/// Where Debian's Chromium is (`.ci/run` installs it); browser tests skip, saying so, without it.
pub const CHROMIUM: &str = "/usr/bin/chromium";

/// Runs headless Chromium on `page` with WebGL on SwiftShader; returns (stdout, stderr).
pub fn chromium(page: &Path, extra: &[&str]) -> (String, String) {
    let profile = tempfile::tempdir().expect("temp dir");
    let output = std::process::Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(extra)
        .arg(page)
        .output()
        .expect("chromium runs");
    (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// The numeric oracle for proofs: 300 random starts, no closed form, no joint-space search.
pub fn dense_numeric() -> proving_ground::ik::IkOptions {
    proving_ground::ik::IkOptions {
        seeds: 300,
        analytic: false,
        search_boxes: 0,
        ..proving_ground::ik::IkOptions::default()
    }
}

/// Asserts that `numeric` (see [`dense_numeric`]) reaches goal `index` nowhere within its
/// tolerance, collisions aside, as `proof` claims; `context` names the case.
pub fn assert_unreached(
    numeric: &mut proving_ground::ik::Ik,
    goal: &proving_ground::scenario::Goal,
    index: usize,
    proof: &str,
    context: &str,
) {
    let found = numeric.solve(goal, index, None);
    let reached = found.solutions.iter().find(|s| s.pose_reached);
    assert!(
        reached.is_none(),
        "{context} goal {index}: {proof}; yet reached at {:?}",
        reached.map(|s| &s.q)
    );
}

/// A scenario of one sphere (`radius` m at `centre`) and one `pose` goal at `tool`, no floor.
pub fn sphere_and_goal(centre: nalgebra::Vector3<f64>, radius: f64, tool: &nalgebra::Isometry3<f64>) -> Scenario {
    use proving_ground::scenario::{Goal, Obstacle, Tolerance};
    Scenario {
        name: "sphere".into(),
        world_from_base: nalgebra::Isometry3::identity(),
        floor: None,
        obstacles: vec![Obstacle {
            name: "sphere".into(),
            world_from_shape: nalgebra::Isometry3::translation(centre.x, centre.y, centre.z),
            shape: proving_ground::model::Shape::Sphere { radius },
        }],
        goals: vec![Goal {
            name: "goal".into(),
            position: tool.translation.vector,
            rotation: tool.rotation,
            tolerance: Tolerance::Pose,
            task: None,
        }],
        home: None,
        provenance: None,
        notes: Vec::new(),
    }
}

/// A unit vector drawn uniformly from the sphere.
pub fn unit_vector(rng: &mut impl rand::Rng) -> nalgebra::Vector3<f64> {
    loop {
        let v = nalgebra::Vector3::new(
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
