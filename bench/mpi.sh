#!/usr/bin/env bash
# Distributed refinement's figures (README, "MPI"): strong and weak scaling
# of `bisect refine` under mpirun, timed as processes (read on rank 0,
# distribute, refine, exchange, rebalance, final check, write the .pvtu),
# with the exchange rounds per iteration, the edges (bytes) a rank sends, time
# in communication, the imbalance before and after rebalancing, and peak RSS
# of the largest rank. Ranks beyond the machine's cores are oversubscribed
# (marked so). Usage: bash bench/mpi.sh [MPI bisect] [serial bisect]
# (default build-mpi/bisect and build/bisect).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
M=${1:-$root/build-mpi/bisect}
S=${2:-$root/build/bisect}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
cores=$(nproc)
echo "machine: $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo), load $(cut -d' ' -f1-3 /proc/loadavg)"
"$S" generate kuhn --dim 4 --cells 1 -o hypercube.vtu -q
region=$root/data/regions/moving-sphere.json
run() { # P ITERATIONS LABEL
  local p=$1 n=$2 label=$3 over=""
  ((p > cores)) && over=" (oversubscribed)"
  mpirun --allow-run-as-root --oversubscribe -np "$p" "$M" refine hypercube.vtu --region "$region" \
    -n "$n" -m longest -o out.pvtu -q -f --quality-csv q.csv --json --threads 1 >run.json
  /usr/bin/python3 - "$label" "$p" "$over" <<'PY'
import csv, json, sys
label, p, over = sys.argv[1], int(sys.argv[2]), sys.argv[3]
j = json.load(open("run.json"))
rows = list(csv.DictReader(open("q.csv")))[1:]
rounds = [int(r["exchange_rounds"]) for r in rows]
before = max(float(r["imbalance"]) for r in rows)
after = max(float(r["imbalance_after_rebalance"]) for r in rows[:-1]) if len(rows) > 1 else 1.0
cells = j["cells"]
bytes_per_iter = j["edges_sent_max_rank"] * 2 * j["dim"] * 8 / max(1, j["iterations"])
print(f"{label}: P={p}{over}, {j['iterations']} iterations, {cells:,} pentatopes: "
      f"{j['seconds']:.2f} s ({j['seconds'] / cells * 1e6 * p:.2f} s per million pentatopes per rank), "
      f"rounds per iteration max {max(rounds)} (total {sum(rounds)}), "
      f"largest rank sends {bytes_per_iter / 1024:.1f} KiB per iteration, "
      f"exchange {j['exchange_seconds_max_rank']:.3f} s ({100 * j['exchange_seconds_max_rank'] / j['seconds']:.1f}%), "
      f"{j['rebalances']} rebalances {j['rebalance_seconds']:.2f} s ({100 * j['rebalance_seconds'] / j['seconds']:.0f}%), "
      f"imbalance up to {before:.2f}, after rebalancing up to {after:.2f}, "
      f"final check {j['final_check_seconds']:.2f} s, write {j['write_seconds']:.2f} s, "
      f"peak RSS of the largest rank {j['peak_rss_bytes_max_rank'] / 2**20:.0f} MiB "
      f"({j['peak_rss_bytes_max_rank'] / (cells / p):.0f} B per pentatope of a rank's share)")
PY
}
serial=$("$S" refine hypercube.vtu --region "$region" -n 25 -m longest -o s.vtu -q -f --quality-csv none --json --threads 1)
/usr/bin/python3 -c "import json,sys; j=json.load(sys.stdin); print(f\"serial, 1 thread: {j['cells']:,} pentatopes in {j['seconds']:.2f} s, peak RSS {j['peak_rss_bytes']/2**20:.0f} MiB\")" <<<"$serial"
echo "strong scaling (seed 000 5.3: moving sphere, 25 iterations; one thread per rank):"
for p in 1 2 4; do
  run "$p" 25 "  strong"
done
echo "weak scaling (about 2.6-3.3 M pentatopes per rank):"
run 1 24 "  weak"
run 2 25 "  weak"
# Reading the .pvtu back and coarsening it: the strong run's 2-piece output
# (P = 2), read by every rank (pieces_read_in_parallel) and coarsened on every
# part, against the serial coarsening of the serial output.
mpirun --allow-run-as-root --oversubscribe -np 2 "$M" refine hypercube.vtu --region "$region" \
  -n 25 -m longest -o out.pvtu -q -f --quality-csv none --threads 1
echo "coarsening 3 passes (--all) of the 25-iteration mesh, one thread per rank:"
"$S" coarsen s.vtu --all -n 3 -o sc.vtu -q -f --json --threads 1 >c.json
/usr/bin/python3 -c "import json; j=json.load(open('c.json')); print(f\"  serial, from s.vtu: {j['cells']:,} pentatopes left in {j['seconds']:.2f} s\")"
for p in 1 2 4; do
  over=""
  ((p > cores)) && over=" (oversubscribed)"
  mpirun --allow-run-as-root --oversubscribe -np "$p" "$M" coarsen out.pvtu --all -n 3 -o c.pvtu -q -f \
    --json --threads 1 >c.json
  /usr/bin/python3 - "$p" "$over" <<'PY'
import json, sys
j = json.load(open("c.json"))
print(f"  P={sys.argv[1]}{sys.argv[2]}, from out.pvtu (pieces read in parallel: {j['pieces_read_in_parallel']}): "
      f"{j['cells']:,} pentatopes left in {j['seconds']:.2f} s, "
      f"{j['rounds']} rounds moving {j['moved_cells']:,} cells between parts, "
      f"peak RSS of the largest rank {j['peak_rss_bytes_max_rank'] / 2**20:.0f} MiB")
PY
done
