#!/usr/bin/env bash
# The soak: a factory for a million steps (or $2), with a drain that keeps its pile at
# $3 particles (default 400; 0 for no drain: the pile then grows until the box is full),
# in chunks ($4, default 20) that each continue the previous one from its snapshot, so
# the cost per step and the memory can be read along the run. Every step is checked for
# crossings; a crossing, a length error above 1e-9 or a non-finite state (the runner
# exits non-zero) fails the soak.
#
# Usage: scripts/soak.sh [spaghetti_factory|meatball_factory] [steps] [drain] [chunks]
# Prints one Markdown row per chunk: simulated time, particles, steps per wall second,
# peak memory of that chunk's process, the errors so far, the crossings and fail-safe
# steps so far, and the strands the drain took out in that chunk.
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-spaghetti_factory}
steps=${2:-1000000}
drain=${3:-400}
chunks=${4:-20}
cargo build --quiet --release --bin strands
dir=target/soak_${scenario}_$drain
mkdir -p "$dir"
# Every chunk runs this copy: a rebuild while the soak runs does not change it midway.
cp target/release/strands "$dir/strands"
# The soak's scene: the built-in one with the drain, and a meatball factory that keeps
# dropping (the built-in one stops at 16).
python3 - "assets/scenes/$scenario.ron" "$dir/scene.ron" "$drain" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
drain = int(sys.argv[3])
text = re.sub(r"\bmax: 16,", "max: 1000000000,", text)
if drain > 0:
    end = text.rstrip().rfind(")")
    text = text[:end] + f"    drain: Some((max_particles: {drain})),\n)\n"
open(sys.argv[2], "w").write(text)
PY
dt=$(python3 -c "import re; print(re.search(r'dt: ([0-9.e-]+)', open('$dir/scene.ron').read()).group(1))")
echo "| chunk | simulated | particles | steps/s | peak RSS | max_rel_length_error | away from contact | edge_crossings | fail-safe steps | drained |"
echo "|---|---|---|---|---|---|---|---|---|---|"
from=(--scene "$dir/scene.ron")
for ((k = 1; k <= chunks; k++)); do
    t=$(python3 -c "print(repr($steps * $dt * $k / $chunks))")
    /usr/bin/time -f "%M" -o "$dir/rss_$k" \
        "$dir/strands" run "${from[@]}" --seconds "$t" --threads 1 \
        --snapshot-at "$t" --snapshot "$dir/chunk_$k.ron" --json > "$dir/chunk_$k.json"
    python3 - "$dir/chunk_$k.json" "$dir/rss_$k" "$k" "$steps" "$chunks" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
rss_mib = int(open(sys.argv[2]).read().split()[-1]) / 1024
k, steps, chunks = int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
rate = steps / chunks / r["wall_seconds"]
drained = next((int(m.group(1)) for n in r["notes"]
                if (m := re.match(r"the drain took out (\d+) strands", n))), 0)
print(f"| {k} | {r['sim_time']:.1f} s | {r['particles']} | {rate:.0f} | {rss_mib:.0f} MiB | "
      f"{r['max_rel_length_error']:.2e} | {r['max_rel_length_error_free']:.2e} | "
      f"{r['edge_crossings']} | {r['failsafe_steps']} | {drained} |", flush=True)
sys.exit(0 if r["edge_crossings"] == 0 and r["max_rel_length_error"] < 1e-9 else 1)
PY
    from=(--from "$dir/chunk_$k.ron")
done
