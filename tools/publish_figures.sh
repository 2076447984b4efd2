#!/usr/bin/env bash
# Copy the main job's key figures into docs/figures/ for the README (run after `snakemake`).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mkdir -p docs/figures
for f in maps/machine_map maps/powder_band_map maps/powder_cluster_map maps/parallel_coordinates \
         maps/regime_overlay maps/sensitivity_ranking convergence/statistics convergence/distributions \
         convergence/sampling_study surrogate/surrogate_parity surrogate/surrogate_r2_vs_neurons \
         surrogate/surrogate_learning_curve pictures/normal pictures/narrow_gap_large pictures/small_particles; do
  cp "results/$f.png" "docs/figures/$(basename "$f").png"
done
cp results/maps/sensitivity_ranking_table.csv results/summary.txt results/convergence/summary.json \
   results/surrogate/surrogate_metrics.csv results/tables/points.csv docs/figures/
