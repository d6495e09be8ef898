//! The render stage: pictures (SVG parsed back with usvg, PNG), the HTML report in a real headless
//! Chromium, the MJCF scene in MuJoCo, and byte-identical output for the same input.

mod common;

use assert_cmd::Command;
use common::repo;
use proving_ground::engine::MujocoKinematics;
use proving_ground::pipeline::{self, LoadOptions, ValidateOptions};
use proving_ground::render::{self, png};
use resvg::usvg;
use std::path::{Path, PathBuf};

/// Where Debian installs Chromium (`.ci/run` installs it).
use common::{chromium, CHROMIUM};

fn validate_design() -> Command {
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo());
    cmd
}

fn files_in(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("folder exists")
        .map(|e| e.expect("entry").path())
        .map(|p| {
            (
                p.file_name().expect("name").to_string_lossy().into_owned(),
                std::fs::read(&p).expect("readable"),
            )
        })
        .collect();
    files.sort();
    files
}

/// Counts the nodes of a usvg group by kind (paths, texts, groups), recursively.
fn count(group: &usvg::Group, counts: &mut [usize; 3]) {
    for node in group.children() {
        match node {
            usvg::Node::Path(_) => counts[0] += 1,
            usvg::Node::Text(_) => counts[1] += 1,
            usvg::Node::Group(g) => {
                counts[2] += 1;
                count(g, counts);
            }
            usvg::Node::Image(_) => {}
        }
    }
}

/// The ur5e on cluttered task 00 with the straight planner: goals reached, blocked (no_path)
/// and unreachable, so every kind of picture is made.
fn blocked_run() -> (pipeline::Validation, proving_ground::report::Report) {
    let loaded = pipeline::load(&repo().join("designs/ur5e.json"), &LoadOptions::default()).expect("ur5e loads");
    let scenario = pipeline::load_scenario(&repo().join("scenarios/cluttered/task-00.json")).expect("task 00 loads");
    let opts = ValidateOptions {
        engines: pipeline::Engines::from_names([]).expect("no engine"),
        planner: proving_ground::plan::PlannerOptions {
            kind: proving_ground::plan::PlannerKind::Straight,
            ..Default::default()
        },
        ..Default::default()
    };
    let validation = pipeline::validate(loaded, scenario, &opts).expect("validates");
    let report = proving_ground::report::build(&validation);
    (validation, report)
}

#[test]
fn pictures_parse_back_with_their_views_bodies_and_plot_marks() {
    let (validation, report) = blocked_run();
    let outcomes: Vec<&str> = report.goals.iter().map(|g| g.outcome).collect();
    assert!(
        outcomes.contains(&"no_path") && outcomes.contains(&"unreachable") && outcomes.contains(&"reached"),
        "{outcomes:?}"
    );
    let pictures = render::pictures(&validation, &report);
    let names: Vec<&str> = pictures.iter().map(|p| p.name.as_str()).collect();
    let goals = validation.scenario.goals.len();
    assert_eq!(names.len(), goals + 2, "{names:?}");
    assert_eq!(
        (names[0], names[1], names[goals], names[goals + 1]),
        ("scene", "goal-000", "goal-007", "clearance")
    );
    for picture in &pictures {
        let tree = png::parse(&picture.name, &picture.svg).expect("usvg parses every picture");
        let mut counts = [0; 3];
        count(tree.root(), &mut counts);
        let [paths, texts, _] = counts;
        if picture.name == "clearance" {
            let segments = validation.replayed.len();
            let marks = |id: &str| match tree.node_by_id(id) {
                Some(usvg::Node::Group(g)) => g.children().len(),
                _ => 0,
            };
            let finite = validation
                .replayed
                .iter()
                .filter(|s| s.certified.certified_clearance_m.is_finite())
                .count();
            let touches = validation.replayed.iter().filter(|s| s.certified.touch.is_some()).count();
            let attempts = validation.replayed.iter().filter(|s| !s.planned).count();
            assert_eq!(marks("certified"), finite, "one bound line per segment with a bound");
            assert_eq!(marks("measured"), segments, "one closest-approach dot per segment");
            assert_eq!(marks("blocked"), touches, "one cross per blocked segment");
            assert_eq!(marks("attempts"), attempts, "one shaded band per attempt");
            assert!(touches >= 3, "task 00 with the straight planner has three blocked goals: {touches}");
            assert!(tree.node_by_id("closest-pair").is_some(), "the closest pair is marked");
            // Each kind's bound: a line per segment with a pair of that kind; the lowest of the
            // kinds is the segment's whole bound.
            for (id, kind) in [("certified-obstacles", 0), ("certified-self", 1), ("certified-floor", 2)] {
                let lines = validation
                    .replayed
                    .iter()
                    .filter(|s| {
                        let k = &s.certified.certified_by_kind;
                        [k.obstacles_m, k.self_m, k.floor_m][kind].is_some()
                    })
                    .count();
                assert!(lines > 0 && marks(id) == lines, "{id}: {} lines, {lines} segments", marks(id));
            }
            for segment in &validation.replayed {
                let k = &segment.certified.certified_by_kind;
                let lowest = [k.obstacles_m, k.self_m, k.floor_m]
                    .into_iter()
                    .flatten()
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(lowest, segment.certified.certified_clearance_m, "{k:?}");
            }
        } else {
            // Four view labels, title, subtitle, seven legend entries and the scale bar's label: 14.
            assert!(texts >= 14, "{}: {texts} texts", picture.name);
            assert!(
                paths > 1000,
                "{}: {paths} paths: the robot and eight sphere obstacles in four views",
                picture.name
            );
        }
    }
    // A blocked goal's picture names the blocking pair and shows the robot where it stops.
    let blocked = report.goals.iter().position(|g| g.outcome == "no_path").expect("a blocked goal");
    let svg = &pictures[blocked + 1].svg;
    assert!(
        svg.contains("no path: the straight attempt from the previous goal is blocked at s = "),
        "{}",
        &svg[..600]
    );
}

#[test]
fn pictures_png_and_html_are_byte_identical_whatever_the_thread_count() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut runs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("t{threads}"));
        let output = validate_design()
            .args([
                "designs/paper-real-world.json",
                "--engines",
                "none",
                "--quiet",
                "--threads",
                threads,
            ])
            .arg("--svg")
            .arg(out.join("svg"))
            .arg("--png")
            .arg(out.join("png"))
            .arg("--html")
            .arg(out.join("report.html"))
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
        runs.push(out);
    }
    for sub in ["svg", "png"] {
        let (a, b) = (files_in(&runs[0].join(sub)), files_in(&runs[1].join(sub)));
        assert_eq!(a.len(), 36 + 2, "{sub}: scene, 36 goals, clearance");
        assert!(a == b, "{sub}: the pictures differ between --threads 1 and 2");
    }
    let html = |run: &PathBuf| std::fs::read(run.join("report.html")).expect("html written");
    assert!(html(&runs[0]) == html(&runs[1]), "the HTML differs between --threads 1 and 2");
    // The page has the text report's whole summary and the clearance of each kind per goal.
    let page = String::from_utf8(html(&runs[0])).expect("UTF-8 page");
    for part in [
        "<section id=\"summary\">",
        "criteria: reached",
        "trajectory: 36 of 36 goals",
        "paper loss ",
        "<th>obstacles</th><th>self</th><th>floor</th>",
    ] {
        assert!(page.contains(part), "the page lacks {part}");
    }
    // A PNG decodes at the SVG's size.
    let bytes = std::fs::read(runs[0].join("png/scene.png")).expect("png");
    let pixmap = resvg::tiny_skia::Pixmap::decode_png(&bytes).expect("a PNG");
    assert_eq!((pixmap.width(), pixmap.height()), (1280, 960));
}

#[test]
fn picture_folder_that_is_a_file_or_an_input_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("plain");
    std::fs::write(&file, "x").expect("write");
    let output = validate_design()
        .args(["designs/paper-real-world.json", "--reach-only", "--quiet", "--svg"])
        .arg(&file)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("plain") && stderr.contains("not a folder"), "{stderr}");
    // --html over the design it read.
    let output = validate_design()
        .args([
            "designs/paper-real-world.json",
            "--reach-only",
            "--quiet",
            "--html",
            "designs/paper-real-world.json",
        ])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("refusing to write"), "{stderr}");
}

#[test]
fn html_report_renders_a_3d_view_in_headless_chromium_without_errors() {
    if !Path::new(CHROMIUM).exists() {
        println!("skipped: {CHROMIUM} is not installed (apt-get install chromium; .ci/run installs it)");
        return;
    }
    let (validation, report) = blocked_run();
    let dir = tempfile::tempdir().expect("temp dir");
    let page = dir.path().join("report.html");
    std::fs::write(&page, render::page(&validation, &report)).expect("write page");

    // The page sets its title to `ok <ms> ms` after its first frame (and after checking its own
    // kinematics against ours), or to `error: ...` on any error or console error.
    let (dom, stderr) = chromium(&page, &["--dump-dom"]);
    let title = dom.split("<title>").nth(1).and_then(|t| t.split("</title>").next()).unwrap_or("");
    assert!(title.starts_with("ok "), "page title `{title}`; chromium stderr:\n{stderr}");
    for bad in ["Uncaught", "CONSOLE(", "SyntaxError"] {
        let lines: Vec<&str> = stderr.lines().filter(|l| l.contains(bad) && !l.contains("GPU stall")).collect();
        assert!(lines.is_empty(), "console: {lines:?}");
    }

    // The 3D canvas (page y 90..640 at 1280 px wide) is not blank: pixel variance of a
    // screenshot. A white canvas gives 0; the robot, obstacles and floor grid give thousands.
    let shot = dir.path().join("shot.png");
    let (_, stderr) = chromium(&page, &["--window-size=1280,1000", &format!("--screenshot={}", shot.display())]);
    let bytes = std::fs::read(&shot).unwrap_or_else(|e| panic!("no screenshot ({e}); chromium stderr:\n{stderr}"));
    let pixmap = resvg::tiny_skia::Pixmap::decode_png(&bytes).expect("a PNG screenshot");
    let (width, pixels) = (pixmap.width() as usize, pixmap.pixels());
    let luma: Vec<f64> = (120..600)
        .flat_map(|y| (40..width - 40).map(move |x| (x, y)))
        .map(|(x, y)| pixels[y * width + x].demultiply())
        .map(|p| 0.299 * f64::from(p.red()) + 0.587 * f64::from(p.green()) + 0.114 * f64::from(p.blue()))
        .collect();
    let mean = luma.iter().sum::<f64>() / luma.len() as f64;
    let variance = luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luma.len() as f64;
    let dark = luma.iter().filter(|&&l| l < 160.0).count();
    assert!(
        variance > 100.0 && dark > 2000,
        "canvas looks blank: variance {variance:.1}, {dark} dark pixels"
    );
}

#[test]
fn scene_mjcf_loads_in_mujoco_with_every_obstacle_the_floor_and_a_site_per_goal() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("scene.xml");
    let robot = dir.path().join("robot.xml");
    for (path, extra) in [(&scene, vec!["--scene"]), (&robot, vec![])] {
        let output = validate_design()
            .args([
                "designs/ur5e.json",
                "--scenario",
                "scenarios/cluttered/task-00.json",
                "--describe",
                "--quiet",
                "--export-mjcf",
            ])
            .arg(path)
            .args(extra)
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    }
    let model = pipeline::load_model(&repo().join("designs/ur5e.json"), &LoadOptions::default()).expect("ur5e");
    let scenario = pipeline::load_scenario(&repo().join("scenarios/cluttered/task-00.json")).expect("task 00");
    let joints: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let colliders: usize = model.links.iter().map(|l| l.colliders.len()).sum();
    let loaded = MujocoKinematics::from_file(&scene, &joints).expect("MuJoCo loads the scene");
    let floor = usize::from(scenario.floor.is_some());
    assert_eq!(loaded.geom_count(), colliders + scenario.obstacles.len() + floor);
    assert_eq!(loaded.site_count(), 1 + scenario.goals.len(), "tool site and one per goal");
    let plain = MujocoKinematics::from_file(&robot, &joints).expect("MuJoCo loads the robot");
    assert_eq!(
        (plain.geom_count(), plain.site_count()),
        (colliders, 1),
        "without --scene: the robot alone"
    );
    // The scene's robot stands at the scenario's base pose: MuJoCo's tool site is our tool.
    let q = vec![0.3; model.dof()];
    let tool = loaded.sample(&q, &[], Some("tool")).expect("sample").site.expect("tool site");
    let ours = model.placed(&scenario.world_from_base).tool_pose(&q);
    assert!(
        (tool.translation.vector - ours.translation.vector).norm() < 1e-9,
        "{tool:?} vs {ours:?}"
    );
    // --scene needs --export-mjcf.
    let output = validate_design().args(["designs/ur5e.json", "--scene"]).output().expect("runs");
    assert_eq!(output.status.code(), Some(2));
}

#[test]
fn a_validated_scene_has_colours_and_a_keyframe_for_home_and_every_goal() {
    use mujoco_rs::prelude::*;
    let dir = tempfile::tempdir().expect("temp dir");
    let (scene, json) = (dir.path().join("scene.xml"), dir.path().join("report.json"));
    let output = validate_design()
        .args([
            "designs/ur5e.json",
            "--scenario",
            "scenarios/cluttered/task-00.json",
            "--reach-only",
        ])
        .args(["--mujoco-checks", "0", "--quiet", "--scene", "--export-mjcf"])
        .arg(&scene)
        .arg("--json")
        .arg(&json)
        .output()
        .expect("runs");
    assert!(
        matches!(output.status.code(), Some(0 | 1 | 3)),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let xml = std::fs::read_to_string(&scene).expect("scene written");
    assert!(
        xml.contains(r#"<default class="obstacle">"#) && xml.contains(r#"class="obstacle""#),
        "{xml}"
    );
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("report")).expect("JSON");
    let goals = report["goals"].as_array().expect("goals");
    // Direct mujoco-rs calls need the library loaded first (it is loaded at first use).
    proving_ground::engine::check_version().expect("MuJoCo is available");
    let mj = MjModel::from_xml_string(&xml).expect("MuJoCo loads the scene");
    let nq = mj.ffi().nq as usize;
    assert_eq!(mj.ffi().nkey as usize, 1 + goals.len(), "home and one key per goal");
    // Each goal's key is its chosen configuration (to the digits the file keeps), held by ctrl.
    for (k, goal) in goals.iter().enumerate() {
        let chosen: Vec<f64> = goal["chosen"]
            .as_array()
            .expect("chosen")
            .iter()
            .filter_map(serde_json::Value::as_f64)
            .collect();
        let key = &mj.key_qpos()[(k + 1) * nq..(k + 2) * nq];
        assert!(
            chosen.iter().zip(key).all(|(a, b)| (a - b).abs() < 1e-9),
            "goal {k}: {chosen:?} vs {key:?}"
        );
        assert_eq!(&mj.key_ctrl()[(k + 1) * nq..(k + 2) * nq], key);
    }
}
