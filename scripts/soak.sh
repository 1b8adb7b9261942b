#!/usr/bin/env bash
# The soak: a factory for a million steps (or $2), in chunks that each continue the
# previous one from its snapshot bit for bit, so the cost per step and the memory can
# be read as the pile grows. Every step is checked for crossings; a crossing, a length
# error above 1e-9 or a non-finite state (the runner exits non-zero) fails the soak.
#
# Usage: scripts/soak.sh [spaghetti_factory|meatball_factory] [steps, default 1000000]
#                        [chunks, default 20]
# Prints one Markdown row per chunk: simulated time, particles, steps per wall second,
# peak memory of that chunk's process, the errors so far and the crossings.
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-spaghetti_factory}
steps=${2:-1000000}
chunks=${3:-20}
cargo build --quiet --release --bin strands
dir=target/soak_$scenario
mkdir -p "$dir"
# The built-in factories step at 1/600 s.
dt=$(python3 -c "print(1/600)")
echo "| chunk | simulated | particles | steps/s | peak RSS | max_rel_length_error | away from contact | edge_crossings | fail-safe steps |"
echo "|---|---|---|---|---|---|---|---|---|"
from=()
for ((k = 1; k <= chunks; k++)); do
    t=$(python3 -c "print(repr($steps * $dt * $k / $chunks))")
    /usr/bin/time -f "%M" -o "$dir/rss_$k" \
        ./target/release/strands run "$scenario" "${from[@]}" --seconds "$t" \
        --snapshot-at "$t" --snapshot "$dir/chunk_$k.ron" --json > "$dir/chunk_$k.json"
    python3 - "$dir/chunk_$k.json" "$dir/rss_$k" "$k" "$steps" "$chunks" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
rss_mib = int(open(sys.argv[2]).read().split()[-1]) / 1024
k, steps, chunks = int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
rate = steps / chunks / r["wall_seconds"]
print(f"| {k} | {r['sim_time']:.1f} s | {r['particles']} | {rate:.0f} | {rss_mib:.0f} MiB | "
      f"{r['max_rel_length_error']:.2e} | {r['max_rel_length_error_free']:.2e} | "
      f"{r['edge_crossings']} | {r['failsafe_steps']} |")
sys.exit(0 if r["edge_crossings"] == 0 and r["max_rel_length_error"] < 1e-9 else 1)
PY
    from=(--from "$dir/chunk_$k.ron")
done
