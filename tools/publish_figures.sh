#!/usr/bin/env bash
# Copy the main job's key figures into docs/figures/ for the README (run after `snakemake`).
# Usage: tools/publish_figures.sh [WORKFLOW_DIR]   (default: this checkout)
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
src="$(cd "${1:-$repo}" && pwd)/results"
mkdir -p "$repo/docs/figures"
for f in maps/machine_map maps/powder_band_map maps/powder_cluster_map maps/parallel_coordinates \
         maps/regime_overlay maps/sensitivity_ranking convergence/statistics convergence/distributions \
         convergence/sampling_study surrogate/surrogate_parity surrogate/surrogate_r2_vs_neurons \
         surrogate/surrogate_learning_curve pictures/normal pictures/narrow_gap_large pictures/small_particles; do
  cp "$src/$f.png" "$repo/docs/figures/$(basename "$f").png"
done
cp "$src"/maps/sensitivity_ranking_table.csv "$src"/summary.txt "$src"/convergence/summary.json \
   "$src"/surrogate/surrogate_metrics.csv "$src"/tables/points.csv "$repo/docs/figures/"
