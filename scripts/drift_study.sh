#!/usr/bin/env bash
# The constraint-drift study of docs/drift-study.md: long_strand's length errors with
# stretch springs only, with constraints at one projection iteration per step, and
# with constraints converged, each with and without stretch springs on top; and the
# relaxation baselines (Gauss-Seidel, i.e. PBD, and Jacobi) at 20 and 100 sweeps.
# Prints the study's table in Markdown.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --release --bin strands
echo "| configuration | command | max_rel_length_error | max_rel_length_error_free | particle-steps/s |"
echo "|---|---|---|---|---|"
row() {
    local label=$1
    shift
    ./target/release/strands run long_strand "$@" --json | python3 -c '
import json, sys
r = json.load(sys.stdin)
label, command = sys.argv[1], sys.argv[2]
error, free, speed = r["max_rel_length_error"], r["max_rel_length_error_free"], r["particle_steps_per_second"]
print(f"| {label} | `{command}` | {error:.2e} | {free:.2e} | {speed:.2e} |")
' "$label" "strands run long_strand $*"
}
row "stretch springs only" --solver springs
row "constraints, 1 iteration" --iterations 1
row "constraints, 1 iteration + springs" --iterations 1 --stretch-springs
row "constraints, converged" --solver tridiagonal
row "constraints, converged + springs" --stretch-springs
row "Gauss-Seidel relaxation (PBD), 20 sweeps" --solver gauss-seidel --iterations 20
row "Gauss-Seidel relaxation (PBD), 100 sweeps" --solver gauss-seidel --iterations 100
row "Jacobi relaxation, 20 sweeps" --solver jacobi --iterations 20
row "Jacobi relaxation, 100 sweeps" --solver jacobi --iterations 100

# The step size: long_strand from dt = 1/3000 to one step per 1/60 s frame, the exact
# solve beside 20 Gauss-Seidel sweeps.
echo
echo "| dt | exact: max_rel_length_error | exact: away from contact | Gauss-Seidel 20: max_rel_length_error | Gauss-Seidel 20: away from contact |"
echo "|---|---|---|---|---|"
for steps in 3000 1200 600 300 200 120 60; do
    dt=$(python3 -c "print(1 / $steps)")
    figures() {
        ./target/release/strands run long_strand --dt "$dt" --substeps 1 "$@" --json | python3 -c '
import json, sys
r = json.load(sys.stdin)
error, free = r["max_rel_length_error"], r["max_rel_length_error_free"]
print(f"{error:.2e} | {free:.2e}", end="")
'
    }
    echo "| 1/$steps | $(figures) | $(figures --solver gauss-seidel --iterations 20) |"
done
