#!/usr/bin/env bash
# The default experiment, run by `scripts/run quickstart` after the build:
# experiments/quickstart.toml (small rods, cloth and cantilever; the paper's method, its
# ablations, the supervised baseline and the full-space reference) into runs/quickstart/.
# A second run reuses every finished stage. Extra arguments go to `latentbench run`
# (e.g. --force rollouts).
set -euo pipefail
build_dir="${1:-build}"
shift || true
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
"$build_dir/latentbench" run experiments/quickstart.toml -o runs/quickstart "$@"
echo
echo "quickstart tables (Markdown; CSV and LaTeX beside them): $root/runs/quickstart/tables/"
echo "quickstart page (tables, figures and videos in one page): $root/runs/quickstart/index.html"
echo "quickstart figures (PNG): $root/runs/quickstart/figures/"
