#!/usr/bin/env bash
# Builds the Python package as a user does (`pip install ./python` into a fresh virtual
# environment) and runs its tests against the release binary the Rust tests built
# (target/release/validate-design). Used by .ci/run; run from anywhere.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$(mktemp -d)/venv"
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet "$root/python" pytest
cd "$root/python"
"$venv/bin/python" -m pytest -q tests
