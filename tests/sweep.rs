//! Design-space sweeps through the binary: shards merge into the unsharded sweep byte for byte,
//! an interrupted sweep resumes, folders are never taken over, the GA repeats for a seed, scores
//! span 0 to 1 over the reference, and a record is what a single run reports.

mod common;

use assert_cmd::Command;
use common::repo;
use sha2::Digest;
use std::path::Path;

fn validate_design() -> Command {
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo());
    cmd
}

/// Two presets, two shipped designs and two tasks: ten pairs, a second or two of work.
const DESIGNS: [&str; 3] = ["designs/ur5e.json", "designs/modular-elbow.json", "catalog:table1"];
const SCENARIOS: [&str; 2] = ["scenarios/cluttered/task-00.json", "scenarios/cluttered/task-01.json"];
const FILES: [&str; 4] = ["sweep.json", "results.jsonl", "results.csv", "table.txt"];

fn sweep(out: &Path, extra: &[&str]) -> std::process::Output {
    let output = validate_design()
        .arg("sweep")
        .args(DESIGNS)
        .arg("--scenarios")
        .args(SCENARIOS)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("runs");
    assert!(
        output.status.success(),
        "sweep {extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn assert_same_files(a: &Path, b: &Path) {
    for name in FILES {
        assert_eq!(read(&a.join(name)), read(&b.join(name)), "{name} differs");
    }
    assert!(!b.join("pairs.partial.jsonl").exists(), "a finished sweep keeps no partial log");
}

#[test]
fn shards_run_as_separate_processes_merge_into_the_unsharded_sweep_byte_for_byte() {
    let dir = tempfile::tempdir().expect("temp dir");
    let whole = dir.path().join("whole");
    sweep(&whole, &["--threads", "2"]);
    let records = read(&whole.join("results.jsonl"));
    assert_eq!(records.lines().count(), 10, "{records}");
    let shards: Vec<_> = (1..=3).map(|k| dir.path().join(format!("shard-{k}"))).collect();
    for (k, shard) in shards.iter().enumerate() {
        sweep(shard, &["--shard", &format!("{}/3", k + 1), "--threads", "1"]);
    }
    let merged = dir.path().join("merged");
    let output = validate_design()
        .arg("merge")
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_same_files(&whole, &merged);

    // Two shards of three do not make the sweep.
    let output = validate_design()
        .arg("merge")
        .args(&shards[..2])
        .arg("--out")
        .arg(dir.path().join("partial"))
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("shards missing: 3/3"));
}

#[test]
fn an_interrupted_sweep_resumes_without_running_its_finished_pairs() {
    let dir = tempfile::tempdir().expect("temp dir");
    let whole = dir.path().join("whole");
    sweep(&whole, &[]);
    // The state of an interruption: the manifest, six finished pairs, a seventh cut short.
    let resumed = dir.path().join("resumed");
    std::fs::create_dir(&resumed).expect("mkdir");
    std::fs::copy(whole.join("sweep.json"), resumed.join("sweep.json")).expect("copy");
    let text = read(&whole.join("results.jsonl"));
    // Each line of the partial log carries its sweep's identity: the start of the manifest's
    // SHA-256.
    let manifest = read(&whole.join("sweep.json"));
    let id: String = sha2::Sha256::digest(manifest.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let stamped = |line: &str| format!("{{\"sweep\":\"{}\",\"record\":{line}}}", &id[..16]);
    let lines: Vec<String> = text.lines().map(stamped).collect();
    let mut partial: String = lines[..6].iter().rev().map(|l| format!("{l}\n")).collect();
    partial.push_str(&lines[6][..lines[6].len() / 2]);
    std::fs::write(resumed.join("pairs.partial.jsonl"), partial).expect("write");
    let output = sweep(&resumed, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("10 pairs (4 computed now, 6 resumed; 1 line cut short or damaged left out)"),
        "{stderr}"
    );
    assert_same_files(&whole, &resumed);
    // A finished sweep run again computes nothing.
    let output = sweep(&resumed, &[]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("(0 computed now, 10 resumed)"));
}

#[test]
fn a_killed_sweep_keeps_every_pair_it_finished() {
    let dir = tempfile::tempdir().expect("temp dir");
    let whole = dir.path().join("whole");
    sweep(&whole, &["--threads", "1"]);
    let killed = dir.path().join("killed");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("validate-design"))
        .current_dir(repo())
        .arg("sweep")
        .args(DESIGNS)
        .arg("--scenarios")
        .args(SCENARIOS)
        .arg("--out")
        .arg(&killed)
        .args(["--threads", "1", "--quiet"])
        .spawn()
        .expect("starts");
    let partial = killed.join("pairs.partial.jsonl");
    let logged = || std::fs::read_to_string(&partial).map_or(0, |t| t.lines().count());
    let start = std::time::Instant::now();
    while logged() < 3 && start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().expect("killed");
    child.wait().expect("reaped");
    // Pairs are logged as they finish: three of ten are on disk while the sweep runs.
    let text = read(&partial);
    let kept = text.lines().count();
    assert!((3..10).contains(&kept), "{kept} pairs logged when killed:\n{text}");
    assert!(text.ends_with('\n'), "only whole lines: {text}");
    let output = sweep(&killed, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!("10 pairs ({} computed now, {kept} resumed)", 10 - kept)),
        "{stderr}"
    );
    assert_same_files(&whole, &killed);
}

/// 625 catalog robots on one task: a sweep long enough to be caught running.
const SHARD_SWEEP: [&str; 6] = ["sweep", "catalog:modular6", "--scenarios", SCENARIOS[0], "--shard", "1/25"];

/// A reach-only sweep of catalog robots that runs for many seconds on one thread: long enough
/// to be caught running.
fn long_sweep(out: &Path, extra: &[&str]) -> std::process::Child {
    std::process::Command::new(assert_cmd::cargo::cargo_bin("validate-design"))
        .current_dir(repo())
        .args(SHARD_SWEEP)
        .args(["--threads", "1", "--quiet"])
        .arg("--out")
        .arg(out)
        .args(extra)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts")
}

fn lines_logged(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("pairs.partial.jsonl")).map_or(0, |t| t.lines().count())
}

fn wait_for_lines(dir: &Path, lines: usize) {
    let start = std::time::Instant::now();
    while lines_logged(dir) < lines && start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

#[test]
fn sigint_stops_a_sweep_that_keeps_every_pair_it_finished_and_resumes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    let child = long_sweep(&out, &[]);
    wait_for_lines(&out, 20);
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
    let output = child.wait_with_output().expect("reaped");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    let kept = lines_logged(&out);
    assert!(
        stderr.contains(&format!("interrupted: {kept} of 625 pairs finished and kept in")),
        "{kept} lines logged: {stderr}"
    );
    assert!(read(&out.join("pairs.partial.jsonl")).ends_with('\n'));
    // Resumed to the end: the records are the ones a sweep without interruption writes.
    let resumed = validate_design().args(SHARD_SWEEP).arg("--out").arg(&out).output().expect("runs");
    let stderr = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("({} computed now, {kept} resumed)", 625 - kept)),
        "{stderr}"
    );
    let whole = dir.path().join("whole");
    let fresh = validate_design()
        .args(SHARD_SWEEP)
        .args(["--quiet", "--out"])
        .arg(&whole)
        .output()
        .expect("runs");
    assert!(fresh.status.success());
    assert_same_files(&whole, &out);
}

#[test]
fn one_run_writes_a_folder_at_a_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    let mut first = long_sweep(&out, &[]);
    wait_for_lines(&out, 1);
    let holder = format!("in use by another validate-design (pid {})", first.id());
    let second = validate_design()
        .args([
            "sweep",
            "designs/ur5e.json",
            "--scenarios",
            SCENARIOS[0],
            "--seed",
            "1",
            "--force",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    let merge = validate_design()
        .args(["merge", "no-such-shard", "--force", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let running = first.try_wait().expect("polled").is_none();
    first.kill().expect("killed");
    first.wait().expect("reaped");
    assert!(running, "the first sweep ended before the others were tried");
    for output in [second, merge] {
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(&holder), "{stderr}");
    }
    // Its holder dead, the folder is taken over without any cleanup.
    let taken = validate_design()
        .args(["sweep", "designs/ur5e.json", "--scenarios", SCENARIOS[0], "--force", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(taken.status.success(), "{}", String::from_utf8_lossy(&taken.stderr));
}

/// The folder holds this tool's files, nothing else (no temporary, no partial log, no lock file
/// once the run that held it ended).
fn assert_no_litter(dir: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["results.csv", "results.jsonl", "sweep.json", "table.txt"],
        "{}",
        dir.display()
    );
}

/// Runs `args` with the crash hook at every write step in turn (a fresh `out` each time), then
/// `again` to finish the work; `check` looks at each finished folder. Ends at the first step
/// count the run survives.
fn crash_at_every_step(name: &str, args: &[&str], out: impl Fn(usize) -> std::path::PathBuf, again: &[&str], check: impl Fn(&Path)) {
    for at in 1.. {
        assert!(at < 200, "{name}: still crashing at step {at}");
        let folder = out(at);
        let crashed = validate_design()
            .args(args)
            .arg(&folder)
            .env(proving_ground::files::CRASH_AT, at.to_string())
            .output()
            .expect("runs");
        match crashed.status.code() {
            Some(0) => break,
            Some(137) => {}
            code => panic!("{name} crashed at step {at}: {code:?} {}", String::from_utf8_lossy(&crashed.stderr)),
        }
        let rerun = validate_design().args(args).arg(&folder).args(again).output().expect("runs");
        assert!(
            rerun.status.success(),
            "{name} after a crash at step {at}: {}",
            String::from_utf8_lossy(&rerun.stderr)
        );
        check(&folder);
    }
}

#[test]
fn a_crash_at_any_write_step_of_a_sweep_or_a_merge_is_repaired_by_running_it_again() {
    let dir = tempfile::tempdir().expect("temp dir");
    let whole = dir.path().join("whole");
    sweep(&whole, &[]);
    let same_as_whole = |folder: &Path| {
        assert_same_files(&whole, folder);
        assert_no_litter(folder);
    };
    let mut args = vec!["sweep"];
    args.extend(DESIGNS);
    args.push("--scenarios");
    args.extend(SCENARIOS);
    args.extend(["--quiet", "--out"]);
    crash_at_every_step("sweep", &args, |at| dir.path().join(format!("sweep-{at}")), &[], same_as_whole);
    let shards: Vec<String> = (1..=2)
        .map(|k| {
            let shard = dir.path().join(format!("shard-{k}"));
            sweep(&shard, &["--shard", &format!("{k}/2")]);
            shard.to_string_lossy().into_owned()
        })
        .collect();
    let mut args = vec!["merge", "--quiet"];
    args.extend(shards.iter().map(String::as_str));
    args.push("--out");
    crash_at_every_step("merge", &args, |at| dir.path().join(format!("merge-{at}")), &[], same_as_whole);
}

#[test]
fn a_catalog_id_is_a_design_wherever_a_design_is() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The id a sweep prints is a design for a single run.
    let output = validate_design()
        .args([
            "modular6/Ll-Is-Ll-Il-D-Ls",
            "--scenario",
            SCENARIOS[0],
            "--reach-only",
            "--mujoco-checks",
            "0",
        ])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(matches!(output.status.code(), Some(0 | 1 | 3)), "{stdout}");
    assert!(stdout.contains("design modular6/Ll-Is-Ll-Il-D-Ls (modular, 6 joints"), "{stdout}");
    // In a sweep, its record is the catalog's own.
    let single = dir.path().join("single");
    sweep_of(&["preset/UR20"], &single);
    let table1 = dir.path().join("table1");
    sweep_of(&["catalog:table1"], &table1);
    let line = read(&single.join("results.jsonl"));
    assert!(read(&table1.join("results.jsonl")).contains(line.trim()), "{line}");
    // The best designs as files any command takes: the sweep's overall ranking, the GA's best.
    let best = dir.path().join("best");
    let output = validate_design()
        .args([
            "sweep",
            "preset/UR20",
            "modular6/Ll-Is-Ll-Il-D-Ls",
            "designs/ur5e.json",
            "--scenarios",
            SCENARIOS[0],
        ])
        .args(["--top", "2", "--best-designs"])
        .arg(&best)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let ranking: Vec<String> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .skip_while(|l| !l.starts_with("overall:"))
        .skip(2)
        .filter_map(|l| l.split_whitespace().nth(1).map(str::to_string))
        .collect();
    let mut written: Vec<String> = std::fs::read_dir(&best)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    let expected: Vec<String> = ranking
        .iter()
        .enumerate()
        .map(|(k, id)| format!("{:02}-{}.json", k + 1, id.replace('/', "_")))
        .collect();
    assert_eq!(written, expected, "{ranking:?}");
    for name in &written {
        let run = validate_design()
            .arg(best.join(name))
            .args(["--scenario", SCENARIOS[0], "--reach-only", "--mujoco-checks", "0", "--quiet"])
            .output()
            .expect("runs");
        assert!(
            matches!(run.status.code(), Some(0 | 1 | 3)),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let ga_best = dir.path().join("ga-best.json");
    let output = validate_design()
        .args([
            "ga",
            "--scenario",
            SCENARIOS[0],
            "--population",
            "8",
            "--generations",
            "2",
            "--best-design",
        ])
        .arg(&ga_best)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let id = stdout
        .lines()
        .find_map(|l| l.strip_prefix("best "))
        .and_then(|l| l.split(':').next())
        .expect("the best id");
    let design: serde_json::Value = serde_json::from_str(&read(&ga_best)).expect("json");
    assert_eq!(design["name"], id, "{stdout}");

    // What is not an id says what an id is.
    for (id, message) in [
        ("modular6/Ll-Is-Ll-Il-D-Lx", "unknown slot code `Lx`"),
        ("modular5/Ll-Is-Ll-Il-D-Ls", "says 5 slots and lists 6"),
        ("preset/UR3", "no such preset; expected one of preset/UR5e"),
    ] {
        let output = validate_design().args([id, "--reach-only"]).output().expect("runs");
        assert_eq!(output.status.code(), Some(2), "{id}");
        assert!(String::from_utf8_lossy(&output.stderr).contains(message), "{id}");
    }
}

fn sweep_of(designs: &[&str], out: &Path) {
    let output = validate_design()
        .arg("sweep")
        .args(designs)
        .args(["--scenarios", SCENARIOS[0], "--quiet", "--out"])
        .arg(out)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn quiet_without_a_folder_is_refused_rather_than_throwing_the_results_away() {
    for command in [
        &["sweep", "designs/ur5e.json", "--scenarios", SCENARIOS[0], "--quiet"][..],
        &["ga", "--quiet"],
    ] {
        let output = validate_design().args(command).output().expect("runs");
        assert_eq!(output.status.code(), Some(2), "{command:?}");
        assert!(String::from_utf8_lossy(&output.stderr).contains("--out"), "{command:?}");
    }
}

#[test]
fn a_folder_holding_another_sweep_or_other_files_is_not_taken_over() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    sweep(&out, &[]);
    let other_seed = validate_design()
        .arg("sweep")
        .args(DESIGNS)
        .arg("--scenarios")
        .args(SCENARIOS)
        .arg("--out")
        .arg(&out)
        .args(["--seed", "1"])
        .output()
        .expect("runs");
    assert_eq!(other_seed.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&other_seed.stderr);
    assert!(
        stderr.contains("holds another sweep (seed 0 and 4 IK seeds instead of 1 and 4)") && stderr.contains("--force"),
        "{stderr}"
    );
    sweep(&out, &["--seed", "1", "--force"]);

    let foreign = dir.path().join("foreign");
    std::fs::create_dir(&foreign).expect("mkdir");
    std::fs::write(foreign.join("notes.txt"), "mine").expect("write");
    for extra in [&[][..], &["--force"][..]] {
        let output = validate_design()
            .arg("sweep")
            .arg("designs/ur5e.json")
            .arg("--scenarios")
            .arg(SCENARIOS[0])
            .arg("--out")
            .arg(&foreign)
            .args(extra)
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(2), "{extra:?}");
        assert!(String::from_utf8_lossy(&output.stderr).contains("is not empty and holds no sweep (notes.txt)"));
    }
    assert_eq!(read(&foreign.join("notes.txt")), "mine");
}

#[test]
fn the_ga_repeats_itself_for_a_seed_on_any_number_of_threads() {
    let dir = tempfile::tempdir().expect("temp dir");
    let run = |threads: &str, seed: &str, name: &str| {
        let out = dir.path().join(name);
        let output = validate_design()
            .args(["ga", "--scenario", SCENARIOS[0], "--population", "12", "--generations", "4"])
            .args(["--seed", seed, "--threads", threads, "--out"])
            .arg(&out)
            .output()
            .expect("runs");
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        read(&out)
    };
    let first = run("1", "3", "a.json");
    // An existing --out is refused before the GA runs (a whole GA here would outlast the timeout).
    let output = validate_design()
        .args([
            "ga",
            "--scenario",
            SCENARIOS[0],
            "--population",
            "100000",
            "--generations",
            "100000",
            "--out",
        ])
        .arg(dir.path().join("a.json"))
        .timeout(std::time::Duration::from_secs(60))
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("the file exists; pass --force to replace it"));
    assert_eq!(first, run("2", "3", "b.json"));
    assert_ne!(first, run("2", "4", "c.json"), "another seed searches elsewhere");
    let result: serde_json::Value = serde_json::from_str(&first).expect("json");
    assert_eq!(result["history"].as_array().map(Vec::len), Some(5));
    // Elitist survival: the best loss never gets worse.
    let best: Vec<f64> = result["history"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|g| g["best_loss"].as_f64().unwrap_or(f64::INFINITY))
        .collect();
    assert!(best.windows(2).all(|w| w[1] <= w[0]), "{best:?}");
}

#[test]
fn scores_are_zero_and_one_at_the_reference_worst_and_best_and_a_reference_is_reused() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The shipped designs stand in for the brute force.
    let reference = dir.path().join("reference");
    let output = validate_design()
        .args(["sweep", "designs/*.json", "--scenarios", SCENARIOS[0], "--out"])
        .arg(&reference)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let csv = read(&reference.join("results.csv"));
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert!(rows.len() >= 10, "{csv}");
    let scores: Vec<f64> = rows.iter().filter_map(|r| r[10].parse().ok()).collect();
    assert!(scores.contains(&0.0) && scores.contains(&1.0), "{scores:?}");
    assert!(scores.iter().all(|&s| (0.0..=1.0).contains(&s)));

    // A design outside it scored against the saved distribution.
    let losses: Vec<f64> = rows.iter().filter_map(|r| r[9].parse().ok()).collect();
    let (best, worst) = losses
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(b, w), &l| (b.min(l), w.max(l)));
    let scored = dir.path().join("scored");
    let output = validate_design()
        .args(["sweep", "catalog:table1", "--scenarios", SCENARIOS[0], "--reference"])
        .arg(&reference)
        .arg("--out")
        .arg(&scored)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let csv = read(&scored.join("results.csv"));
    let row: Vec<&str> = csv
        .lines()
        .find(|l| l.starts_with("preset/UR15,"))
        .expect("the UR15's record")
        .split(',')
        .collect();
    let loss: f64 = row[9].parse().expect("a loss");
    let score: f64 = row[10].parse().expect("a score");
    assert!(
        (score - (worst - loss) / (worst - best)).abs() < 1e-4,
        "{row:?} best {best} worst {worst}"
    );
    assert!(read(&scored.join("table.txt")).contains(&format!("against a reference sweep of {} designs", rows.len())));

    // A shard, or a sweep run with another IK seed, is not a reference.
    let output = validate_design()
        .args(["sweep", "catalog:table1", "--scenarios", SCENARIOS[0], "--seed", "1", "--reference"])
        .arg(&reference)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("was run with IK seed 0 and 4 IK starts, this run with 1 and 4"));

    // A reference that lost lines, or all of them, would shift every score: refused.
    let results = read(&reference.join("results.jsonl"));
    let designs = results.lines().count();
    for kept in [designs - 3, 0] {
        let cut = dir.path().join(format!("cut-{kept}"));
        std::fs::create_dir(&cut).expect("mkdir");
        std::fs::copy(reference.join("sweep.json"), cut.join("sweep.json")).expect("copy");
        let lines: String = results.lines().take(kept).map(|l| format!("{l}\n")).collect();
        std::fs::write(cut.join("results.jsonl"), lines).expect("write");
        let output = validate_design()
            .args(["sweep", "catalog:table1", "--scenarios", SCENARIOS[0], "--reference"])
            .arg(&cut)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(&format!(
                "results.jsonl holds {kept} records where its sweep.json lists {designs} designs x 1 scenarios"
            )),
            "{stderr}"
        );
    }
}

#[test]
fn a_sweep_record_is_what_the_single_reach_only_run_reports() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out");
    sweep(&out, &[]);
    let records: Vec<serde_json::Value> = read(&out.join("results.jsonl"))
        .lines()
        .map(|l| serde_json::from_str(l).expect("a record"))
        .collect();
    for (design, scenario) in [("designs/ur5e.json", SCENARIOS[0]), ("designs/modular-elbow.json", SCENARIOS[1])] {
        let json = dir.path().join("single.json");
        let output = validate_design()
            .args([design, "--scenario", scenario, "--reach-only", "--quiet", "--json"])
            .arg(&json)
            .output()
            .expect("runs");
        assert!(output.status.code().is_some_and(|c| c <= 1));
        let report: serde_json::Value = serde_json::from_str(&read(&json)).expect("report");
        let goals = report["goals"].as_array().expect("goals");
        let reached = goals.iter().filter(|g| g["outcome"] == "reached").count();
        let record = records
            .iter()
            .find(|r| r["design"] == design && r["scenario"] == scenario)
            .expect("the pair is in the sweep");
        assert_eq!(record["goals_solved"].as_u64(), Some(reached as u64), "{design} on {scenario}");
        assert_eq!(
            record["task_solved"].as_bool(),
            Some(report["verdict"]["passed"].as_bool() == Some(true))
        );
    }
}

#[test]
fn table_1_puts_the_papers_numbers_beside_ours() {
    let output = validate_design()
        .args(["table1", "--scenarios", SCENARIOS[0]])
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    for expected in ["UR15", "36 %", "UR20", "77.43 %", "ABB2600", "20.50 mm", "regeneration"] {
        assert!(stdout.contains(expected), "{expected}: {stdout}");
    }
}

#[test]
fn an_edited_design_or_an_input_folder_is_never_taken_for_finished_work() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = dir.path().join("arm.json");
    std::fs::copy(repo().join("designs/modular-elbow.json"), &design).expect("copy");
    let run = |out: &Path, extra: &[&str]| {
        validate_design()
            .arg("sweep")
            .arg(&design)
            .arg("designs/ur5e.json")
            .args(["--scenarios", SCENARIOS[0], "--out"])
            .arg(out)
            .args(extra)
            .output()
            .expect("runs")
    };
    let out = dir.path().join("out");
    assert!(run(&out, &[]).status.success());
    let before = read(&out.join("results.jsonl"));
    let text = read(&design).replace("\"L-long\"", "\"I-long\"");
    std::fs::write(&design, text).expect("edit");
    // The edited design's pairs are computed again, the other design's kept: the same files as
    // a fresh sweep of the designs as they are now.
    let output = run(&out, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("2 pairs (1 computed now, 1 resumed)"), "{stderr}");
    let fresh = dir.path().join("fresh");
    assert!(run(&fresh, &[]).status.success());
    assert_same_files(&fresh, &out);
    assert_ne!(read(&out.join("results.jsonl")), before, "the edit changes the arm's record");

    // --force never replaces the reference it scores against.
    let output = run(&out, &["--reference", out.to_str().expect("utf-8 path"), "--force"]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("is an input of this run"), "{stderr}");
    assert!(out.join("results.jsonl").exists());
}
