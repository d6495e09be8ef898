#!/bin/bash
# A sweep as a Slurm job array: one shard per array task, then one merge.
#
#   sbatch --array=1-16 scripts/slurm-sweep.sh                       # the shards
#   validate-design merge sweep-shards/* --out sweep-merged          # when all have finished
#
# Each shard writes its own folder and resumes where it stopped when resubmitted, so a task
# that hits its time limit is simply run again. The merged folder is byte for byte what one
# unsharded `validate-design sweep` would have written. Edit DESIGNS and SCENARIOS; build the
# binary once (`cargo build --release`) where every node can read it.
#SBATCH --job-name=pg-sweep
#SBATCH --cpus-per-task=4
#SBATCH --time=02:00:00
# Slurm opens the log before the script runs: it goes in the submit folder, which exists.
#SBATCH --output=pg-sweep-%A_%a.out
set -euo pipefail

BIN=${BIN:-target/release/validate-design}
DESIGNS=${DESIGNS:-catalog:modular6}
SCENARIOS=${SCENARIOS:-scenarios/cluttered}
SHARDS=${SLURM_ARRAY_TASK_COUNT:?run with sbatch --array=1-N}
K=${SLURM_ARRAY_TASK_ID:?run with sbatch --array=1-N}

mkdir -p sweep-shards
# Word splitting of DESIGNS is intended: several design arguments.
# shellcheck disable=SC2086
"$BIN" sweep $DESIGNS --scenarios "$SCENARIOS" --shard "$K/$SHARDS" \
    --threads "${SLURM_CPUS_PER_TASK:-1}" --out "sweep-shards/$K" --quiet
