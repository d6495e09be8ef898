#!/usr/bin/env bash
# Builds the Python package as a user does (`pip install ./python`, into a fresh virtual
# environment) and runs its tests against the release binary the Rust tests built
# (cargo's target folder: target/, or CARGO_TARGET_DIR's). Used by .ci/run; run from anywhere.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
if python3 -m venv "$scratch/venv" 2>/dev/null; then
  python="$scratch/venv/bin/python"
  "$python" -m pip install --quiet --upgrade pip
  "$python" -m pip install --quiet "$root/python" pytest
else
  # A Python without the venv module (Debian's python3 without python3-venv): a private
  # target folder instead, so nothing is installed for the user.
  echo "python/test.sh: no venv module; installing into $scratch/site instead"
  python3 -m pip install --quiet --target "$scratch/site" "$root/python" pytest
  export PYTHONPATH="$scratch/site"
  python=python3
fi
cd "$root/python"
"$python" -m pytest -q -p no:cacheprovider tests
