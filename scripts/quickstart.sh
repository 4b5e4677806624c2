#!/usr/bin/env bash
# The default experiment, run by `scripts/run quickstart` after the build.
# Until the experiment pipeline lands (issue 5) it simulates the small cloth scene.
set -euo pipefail
build_dir="${1:-build}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="runs/quickstart"
mkdir -p "$out"
"$build_dir/latentbench" simulate experiments/scenes/cloth.toml --variant small -o "$out/cloth_small.h5"
"$build_dir/latentbench" info "$out/cloth_small.h5"
echo "quickstart data: $root/$out/cloth_small.h5"
