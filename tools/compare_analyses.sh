#!/usr/bin/env bash
# Are the main job's analyses unchanged by a change of code? Runs the analyses after the loop
# (rules surrogate, surrogate_validation, maps, decide) at two revisions on the same finished cases,
# and lists every output that differs (sha256, byte for byte), is new or is gone. Across the split
# of the surrogate into its model and its validation (issue 50), model.joblib and model.json differ
# by design: the model's metadata no longer repeats the validation's and the study's numbers.
#
#   bash tools/compare_analyses.sh OLD_REV [NEW_REV] [CASES_CSV]
#
# NEW_REV defaults to HEAD; CASES_CSV to the main job's published 96 cases
# (docs/main_job/run_2026-12-04/cases.csv), put in place as results/converge/table.csv so that no
# case and no loop step runs. Each revision runs in a fresh clone under ${TMPDIR:-/tmp} with this
# repository's .venv; about 3.5 min of 2 cores each. Exit status 0: every output of OLD_REV is
# byte-identical at NEW_REV (new outputs are listed, not failed); 1: some differ or are gone.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
old="${1:?usage: compare_analyses.sh OLD_REV [NEW_REV] [CASES_CSV]}"
new="${2:-HEAD}"
cases="$(realpath "${3:-$repo/docs/main_job/run_2026-12-04/cases.csv}")"
work="$(mktemp -d "${TMPDIR:-/tmp}/compare_analyses.XXXXXX")"
echo "work directory: $work"

run() {  # run REV NAME: the analyses at REV in $work/NAME; the outputs' checksums in $work/NAME.sha256
    local rev="$1" dir="$work/$2"
    git clone -q "$repo" "$dir"
    git -C "$dir" checkout -q "$(git -C "$repo" rev-parse "$rev")"
    ln -s "$repo/.venv" "$dir/.venv"
    mkdir -p "$dir/results/converge"
    cp "$cases" "$dir/results/converge/table.csv"
    echo "$2 ($rev = $(git -C "$dir" rev-parse --short HEAD)): running surrogate, its validation, maps, decide ..."
    (cd "$dir" && .venv/bin/snakemake --cores 2 --allowed-rules surrogate surrogate_validation maps decide \
        -- results/maps/machine_map.png results/decisions/recommendations.csv \
        results/surrogate/surrogate_metrics.csv > "$work/$2.log" 2>&1) \
        || { echo "$2: the analyses failed, see $work/$2.log" >&2; exit 2; }
    (cd "$dir/results" && find . -type f ! -name "*.log" | sort | xargs sha256sum) > "$work/$2.sha256"
}

run "$old" old
run "$new" new
status=0
while read -r sum path; do
    other="$(awk -v p="$path" '$2 == p {print $1}' "$work/new.sha256")"
    if [ -z "$other" ]; then echo "gone:    $path"; status=1
    elif [ "$other" != "$sum" ]; then echo "differs: $path"; status=1
    fi
done < "$work/old.sha256"
awk 'NR == FNR {seen[$2] = 1; next} !($2 in seen) {print "new:     " $2}' "$work/old.sha256" "$work/new.sha256"
verdict="$([ $status -eq 0 ] && echo "every one of $old's byte-identical" || echo "NOT all identical")"
echo "$(wc -l < "$work/old.sha256") outputs at $old, $(wc -l < "$work/new.sha256") at $new: $verdict"
exit $status
