#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in build-fuzz/ and
# runs each for FUZZ_SECONDS (default 60) on a seed corpus made of the good
# and bad sample files. Crashing, leaking or hanging inputs are kept in
# fuzz/crashes/<target>/. Usage: scripts/fuzz.sh [target...]
#   FUZZ_SECONDS=600 scripts/fuzz.sh fuzz_msh
#   FUZZ_RUNS=1000000 scripts/fuzz.sh fuzz_refine   # one run of a million executions
# The corpus in build-fuzz/corpus/<target> is kept between runs, so a second
# run starts where the first stopped. One process, one core.
# Needs clang and libclang-rt-14-dev (Debian 12: apt-get install clang libclang-rt-14-dev).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD_DIR:-$ROOT/build-fuzz}
SECONDS_EACH=${FUZZ_SECONDS:-60}
RUNS=${FUZZ_RUNS:-}
# With FUZZ_RUNS, the run stops after that many executions (FUZZ_SECONDS, if
# also given, still caps it).
[[ -n $RUNS && -z ${FUZZ_SECONDS:-} ]] && SECONDS_EACH=86400
TARGETS=("$@")
[[ ${#TARGETS[@]} -gt 0 ]] || TARGETS=(fuzz_msh fuzz_vtu fuzz_region fuzz_refine)

CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DBISECT_FUZZ=ON -DBISECT_TESTS=OFF >/dev/null
cmake --build "$BUILD" -j2 --target "${TARGETS[@]}"

# Seed corpora: copies, so that libFuzzer's additions never land in the repo.
seed() { # target, file patterns...
  local dir=$BUILD/corpus/$1; shift
  mkdir -p "$dir"
  local f
  for f in "$@"; do [[ -f $f ]] && cp -f "$f" "$dir/" || true; done
}
shopt -s nullglob
seed fuzz_msh "$ROOT"/data/*.msh "$ROOT"/tests/data/msh/*.msh "$ROOT"/tests/bad/*.msh
seed fuzz_vtu "$ROOT"/tests/bad/*.vtu
seed fuzz_region "$ROOT"/data/regions/*.json "$ROOT"/tests/bad/*.json
seed fuzz_refine
[[ -n $(ls "$BUILD/corpus/fuzz_refine") ]] || head -c 64 /dev/zero >"$BUILD/corpus/fuzz_refine/zeros"
# A few .vtu files written by bisect itself, when the binary is around.
for b in "$ROOT"/build/bisect "$BUILD"/bisect; do
  if [[ -x $b ]]; then
    for d in 2 3 4; do
      "$b" generate kuhn --dim "$d" --cells 1 -o "$BUILD/corpus/fuzz_vtu/kuhn$d.vtu" --force >/dev/null 2>&1 || true
    done
    break
  fi
done

# Files written by VTK's own writer in every mode, when python3-vtk9 is there.
/usr/bin/python3 "$ROOT/scripts/vtu_seeds.py" "$BUILD/corpus/fuzz_vtu" 2>/dev/null || true

# Dictionaries help the text formats.
cat >"$BUILD/msh.dict" <<'DICT'
"$MeshFormat"
"$EndMeshFormat"
"$Nodes"
"$EndNodes"
"$Elements"
"$EndElements"
"$Entities"
"$EndEntities"
"$NodeData"
"$EndNodeData"
"$ElementData"
"$EndElementData"
"$PhysicalNames"
"4.1 0 8"
"2.2 0 8"
"2.2 1 8"
"4.1 1 8"
"\"bisect:order\""
"\"bisect:stage\""
"\"bisect:tag\""
"\"bisect:marking\""
DICT
cat >"$BUILD/region.dict" <<'DICT'
"\"type\""
"\"sphere\""
"\"hemisphere\""
"\"box\""
"\"halfspace\""
"\"moving_sphere\""
"\"union\""
"\"intersection\""
"\"regions\""
"\"center\""
"\"radius\""
"\"normal\""
"\"offset\""
"\"min\""
"\"max\""
"\"velocity\""
"\"solid\""
"true"
"1e308"
"-0"
DICT

CRASHES=$ROOT/fuzz/crashes
status=0
for t in "${TARGETS[@]}"; do
  mkdir -p "$CRASHES/$t"
  dict=()
  case $t in
    fuzz_msh) dict=(-dict="$BUILD/msh.dict") ;;
    fuzz_region) dict=(-dict="$BUILD/region.dict") ;;
  esac
  runs=()
  [[ -n $RUNS ]] && runs=(-runs="$RUNS")
  echo "== $t: ${RUNS:+$RUNS executions, at most }${SECONDS_EACH}s"
  # Stops at the first crash, leak or timeout, whose input is written to
  # fuzz/crashes/<target>/. FUZZ_KEEP_GOING=1 forks and goes on after one.
  keep=()
  [[ ${FUZZ_KEEP_GOING:-0} == 1 ]] && keep=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  set +e
  # VTK 9.1 leaks a few arrays on its error paths: leak checks off for fuzz_vtu.
  leaks=1
  [[ $t == fuzz_vtu ]] && leaks=0
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=$leaks:allocator_may_return_null=0} \
  UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
    "$BUILD/$t" "$BUILD/corpus/$t" "${dict[@]}" "${keep[@]}" "${runs[@]}" -max_total_time="$SECONDS_EACH" \
      -timeout=10 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$CRASHES/$t/" >"$BUILD/$t.log" 2>&1
  rc=$?
  set -e
  grep -E 'SUMMARY|ERROR: libFuzzer|FUZZ PROPERTY FAILED|Test unit written|crash saved|stat::number_of_executed_units|stat::average_exec_per_sec' "$BUILD/$t.log" | sort | uniq -c || true
  # The last progress line: executions, coverage, crashes (fork mode counts them).
  grep -E '^#[0-9]+' "$BUILD/$t.log" | tail -1 || true
  [[ $rc == 0 ]] || { echo "$t: exit $rc (see $BUILD/$t.log and $CRASHES/$t/)"; status=1; }
done
exit $status
