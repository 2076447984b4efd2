#!/usr/bin/env bash
# Copy the fidelity study's outputs (after `snakemake fidelity`) into docs/fidelity/, the folder
# the README cites: the per-preset, per-point and knob tables, the summary, the figures, and the
# two cases tables behind them. Usage: tools/publish_fidelity.sh [WORKFLOW_DIR] (default: here)
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
src="$(cd "${1:-$repo}" && pwd)"
mkdir -p "$repo/docs/fidelity"
cp "$src"/results/fidelity/* "$repo/docs/fidelity/"
cp "$src"/results/tables/fidelity.csv "$repo/docs/fidelity/cases_presets.csv"
cp "$src"/results/tables/knobs.csv "$repo/docs/fidelity/cases_knobs.csv"
cp "$src"/config.yaml "$repo/docs/fidelity/config.yaml"  # the configuration it ran with
"${PYTHON:-$repo/.venv/bin/python}" "$repo/tools/publish_checksums.py" "$repo/docs/fidelity"  # its SHA256SUMS
echo "published to $repo/docs/fidelity:"; ls "$repo/docs/fidelity"
