#!/usr/bin/env bash
# The long-run check: both factories for 100 s (or $SECONDS_TO_RUN) with the crossing
# check at every step, their figures printed as a Markdown table. A crossing anywhere
# makes the script exit non-zero. Each run takes ten to twenty minutes on one core.
#
# Usage: scripts/long_runs.sh [seconds, default 100]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-100}
cargo build --quiet --release --bin strands
echo "| scenario | simulated | particles | strands | max_rel_length_error | away from contact | edge_crossings | fail-safe steps | unresolved | wall time |"
echo "|---|---|---|---|---|---|---|---|---|---|"
status=0
for scenario in spaghetti_factory meatball_factory; do
    ./target/release/strands run "$scenario" --seconds "$seconds" --json > "target/long_run_$scenario.json"
    python3 - "target/long_run_$scenario.json" <<'PY' || status=1
import json, sys
r = json.load(open(sys.argv[1]))
unresolved = sum(1 for n in r["notes"] if "unresolved" in n)
print(f"| {r['scenario']} | {r['sim_time']:.0f} s | {r['particles']} | {r['strands']} | "
      f"{r['max_rel_length_error']:.2e} | {r['max_rel_length_error_free']:.2e} | "
      f"{r['edge_crossings']} | {r['failsafe_steps']} | {unresolved} | {r['wall_seconds']:.0f} s |")
sys.exit(0 if r["edge_crossings"] == 0 and r["max_rel_length_error"] < 1e-9 else 1)
PY
done
exit $status
