"""Times the Python binding against the command line on the same work.

    python python/bench.py [DESIGNS] [THREADS]

`reach` on DESIGNS free 6-joint designs (default 200) on cluttered task 03 against
`validate-design sweep` of the same designs written as files (one process: its start-up and
file writing included), median of 5 runs each; then the per-pair cost of `reach`, and the
binding's overhead: `reach` against the same library call made from Rust
(`cargo run --release --example reach_batch`, which times parsing the designs' JSON and
`sweep::record::evaluate_batch`, median of 5).
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import proving_ground as pg

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
TASK = os.path.join(REPO, "scenarios", "cluttered", "task-03.json")
ROUNDS = 5


def designs(count):
    rng = np.random.default_rng(0)
    rows = np.zeros((count, 6, 3))
    rows[:, :, 0] = rng.choice([0.0, 0.1, 0.2, 0.3], size=(count, 6))
    rows[:, :, 1] = rng.choice([0.0, 0.2, 0.3, 0.4], size=(count, 6))
    rows[:, :, 2] = rng.choice([0.0, np.pi / 2, -np.pi / 2], size=(count, 6))
    return rows


def median_time(run, repeats=5):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    threads = int(sys.argv[2]) if len(sys.argv) > 2 else None
    rows = designs(count)
    batch = [pg.Design.from_dh(r, name=f"design-{k:04}") for k, r in enumerate(rows)]
    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for design in batch:
            path = os.path.join(folder, design.data["name"] + ".json")
            with open(path, "w", encoding="utf-8") as f:
                json.dump(design.data, f)
            paths.append(path)
        target = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps", "--offline"],
                                           cwd=REPO, capture_output=True, text=True, check=True).stdout)["target_directory"]
        binary = os.path.join(target, "release", "validate-design")
        thread_args = ["--threads", str(threads)] if threads else []

        def cli():
            out = os.path.join(folder, "sweep")
            subprocess.run([binary, "sweep", *paths, "--scenarios", TASK, "--out", out, "--force", "--quiet", *thread_args], check=True)

        env = dict(os.environ, **({"RAYON_NUM_THREADS": str(threads)} if threads else {}))

        def library():
            out = subprocess.run(
                ["cargo", "run", "--release", "--quiet", "--example", "reach_batch", "--", TASK, *paths],
                cwd=REPO, env=env, check=True, capture_output=True, text=True,
            ).stdout
            return float(out.split(": ")[1].split(" s ")[0])

        # Interleaved rounds: this machine's speed drifts by tens of per cent over a minute, so
        # each round compares the two measured side by side and the median of the rounds is kept.
        rounds = []
        for _ in range(ROUNDS):
            python = median_time(lambda: pg.reach(batch, TASK, threads=threads))
            rust = library()
            rounds.append((python / rust, python, rust))
        command = median_time(cli)
    overhead, python, rust = sorted(rounds)[ROUNDS // 2]
    print(f"{count} designs x 1 task, threads {threads or 'all'}: reach {python:.3f} s "
          f"({python / count * 1e3:.2f} ms per pair), validate-design sweep {command:.3f} s; ratio {python / command:.3f}")
    print(f"binding overhead over the library called from Rust ({rust:.3f} s), median of {ROUNDS} interleaved rounds: "
          f"{100 * (overhead - 1):+.1f} % (rounds: {', '.join(f'{100 * (r - 1):+.1f}' for r, _, _ in rounds)})")


if __name__ == "__main__":
    main()
