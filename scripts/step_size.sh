#!/usr/bin/env bash
# The step-size study of docs/step-size.md: every built-in scenario and the dense pile
# at dt = 1/3000, 1/1200, 1/600, 1/300, 1/120 and 1/60 (a tick of about 1/100 s, or one
# step when the step is longer), with the crossing check at every step, two runs at a
# time (one per core). Prints a Markdown table per scenario.
#
# Usage: scripts/step_size.sh [scenario ...]   (default: all of them)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --release --bin strands
scenarios=("$@")
[ ${#scenarios[@]} -gt 0 ] || scenarios=(long_strand spaghetti_factory meatball_factory branches pile furry_creature furry_creature_limp scale sandbox)
out=$(mktemp -d)
for scenario in "${scenarios[@]}"; do
    for rate in 3000 1200 600 300 120 60; do
        echo "$scenario $rate"
    done
done | xargs -P 2 -L 1 bash -c '
    substeps=$(( $1 >= 100 ? $1 / 100 : 1 ))
    ./target/release/strands run "$0" --threads 1 --dt "$(python3 -c "print(1/$1)")" \
        --substeps "$substeps" --json > "'"$out"'/$0.$1.json"
'
for scenario in "${scenarios[@]}"; do
    echo
    echo "### \`$scenario\`"
    echo
    echo "| dt | steps | max error | away from contact | crossed steps | fail-safe steps | collision impulses | particle-steps/s | real-time factor | particles at the end |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    for rate in 3000 1200 600 300 120 60; do
        python3 -c '
import json, sys
r = json.load(open(sys.argv[1]))
cells = [
    "1/" + sys.argv[2],
    str(r["steps"]),
    "%.2e" % r["max_rel_length_error"],
    "%.2e" % (r["max_rel_length_error_free"] or 0.0),
    str(r["edge_crossings"]),
    str(r["failsafe_steps"]),
    str(r["collisions"]),
    "%.3g M" % (r["particle_steps_per_second"] / 1e6),
    "%.3f" % r["real_time_factor"],
    str(r["particles"]),
]
print("| " + " | ".join(cells) + " |")
' "$out/$scenario.$rate.json" "$rate"
    done
done
rm -r "$out"
