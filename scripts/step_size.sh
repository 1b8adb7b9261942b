#!/usr/bin/env bash
# The step-size study of docs/step-size.md: every built-in scenario that has contact,
# and the dense pile, at dt = 1/3000, 1/1200, 1/600, 1/300, 1/120 and 1/60 (a tick of
# about 1/100 s, or one step when the step is longer), with the crossing check at every
# step. Prints a Markdown table per scenario.
#
# Usage: scripts/step_size.sh [scenario ...]   (default: all of them)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --release --bin strands
scenarios=("$@")
[ ${#scenarios[@]} -gt 0 ] || scenarios=(long_strand spaghetti_factory meatball_factory branches furry_creature pile)
for scenario in "${scenarios[@]}"; do
    echo
    echo "### \`$scenario\`"
    echo
    echo "| dt | steps | max_rel_length_error | away from contact | edge_crossings | fail-safe steps | particle-steps/s | real-time factor |"
    echo "|---|---|---|---|---|---|---|---|"
    for rate in 3000 1200 600 300 120 60; do
        substeps=$(( rate >= 100 ? rate / 100 : 1 ))
        ./target/release/strands run "$scenario" --dt "$(python3 -c "print(1/$rate)")" --substeps "$substeps" --json \
            | python3 -c '
import json, sys
r = json.load(sys.stdin)
cells = [
    "1/" + sys.argv[1],
    str(r["steps"]),
    "%.2e" % r["max_rel_length_error"],
    "%.2e" % r["max_rel_length_error_free"],
    str(r["edge_crossings"]),
    str(r["failsafe_steps"]),
    "%.2e" % r["particle_steps_per_second"],
    "%.3f" % r["real_time_factor"],
]
print("| " + " | ".join(cells) + " |")
' "$rate"
    done
done
