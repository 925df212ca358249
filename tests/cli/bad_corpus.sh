# Hostile input (tests/bad/cases.tsv): every bad file is refused with exit 1
# and one line naming the file and the problem; no output, CSV or temporary
# file appears, and an existing output stays byte-identical even with
# --force; an unwritable CSV leaves no mesh. The odd but valid files of
# tests/bad/good.tsv are accepted. Absurd numbers are usage errors.
source "$(dirname "$0")/lib.bash"
# A directory of its own, so that any file left behind shows.
mkdir "$WORK/run"
cd "$WORK/run"
BAD=$ROOT/tests/bad
square=$ROOT/data/square.msh
tet=$BAD/good-tet.msh
circle=$ROOT/data/regions/circle.json
ball=$WORK/ball.json
echo '{"type": "sphere", "center": [0.2, 0.2, 0.2], "radius": 0.5, "solid": true}' >"$ball"

failures=0
report() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# mesh/region for a row: a bad mesh with a good region, or a bad region with
# a good mesh of the right dimension.
pick() { # kind file -> sets mesh, region, named
  case $1 in
    mesh) mesh=$BAD/$2 region=$circle named=$BAD/$2 ;;
    region) mesh=$square region=$BAD/$2 named=$BAD/$2 ;;
    region3) mesh=$tet region=$BAD/$2 named=$BAD/$2 ;;
    *) fail "cases.tsv: unknown kind '$1' for $2" ;;
  esac
}
nothing_written() { # what
  if [[ -n $(ls -A) ]]; then
    report "files left behind for $1: $(ls -A | tr '\n' ' ')"
    rm -rf ./* ./.[!.]*
  fi
}

precious=$WORK/precious
echo precious >"$precious"
cases=0
while IFS=$'\t' read -r file kind expected; do
  [[ -z $file || $file == \#* ]] && continue
  cases=$((cases + 1))
  pick "$kind" "$file"
  # 1. No output exists: exit 1, one line naming the file and the problem.
  set +e
  timeout 20 "$BISECT" refine "$mesh" --region "$region" -o out.vtu -q >"$WORK/out" 2>"$WORK/err"
  got=$?
  set -e
  if [[ $got != 1 ]]; then
    report "$file: exit $got, expected 1 ($(head -c 200 "$WORK/err"))"
    rm -f out.vtu out.quality.csv
    continue
  fi
  if [[ $(wc -l <"$WORK/err") != 1 ]] || ! grep -qF -- "$named" "$WORK/err" ||
     ! grep -qF -- "$expected" "$WORK/err"; then
    report "$file: stderr should be one line naming the file and '$expected': $(head -c 300 "$WORK/err")"
  fi
  [[ -s $WORK/out ]] && report "$file: something on stdout"
  nothing_written "$file"
  # 2. An existing output is not touched, even with --force.
  cp "$precious" out.vtu
  set +e
  timeout 20 "$BISECT" refine "$mesh" --region "$region" -o out.vtu -q --force >/dev/null 2>&1
  got=$?
  set -e
  [[ $got == 1 ]] || report "$file --force: exit $got, expected 1"
  cmp -s "$precious" out.vtu || report "$file --force: existing output changed"
  rm -f out.vtu
  nothing_written "$file --force"
done <"$BAD/cases.tsv"
(( cases >= 30 )) || fail "only $cases cases in tests/bad/cases.tsv"

# Odd but valid input is accepted.
while IFS=$'\t' read -r file kind; do
  [[ -z $file || $file == \#* ]] && continue
  pick "$kind" "$file"
  [[ $kind == mesh && $file == *tet* ]] && region=$ball
  set +e
  "$BISECT" refine "$mesh" --region "$region" -o out.vtu -q --check >/dev/null 2>"$WORK/err"
  got=$?
  set -e
  [[ $got == 0 ]] || report "$file (valid) refused: exit $got: $(head -c 300 "$WORK/err")"
  rm -f out.vtu out.quality.csv
done <"$BAD/good.tsv"

# Absurd numbers are usage errors, before anything is read or written.
usage_error() { # option value
  set +e
  "$BISECT" refine "$square" --region "$circle" "$1" "$2" -o out.vtu -q >/dev/null 2>"$WORK/err"
  got=$?
  set -e
  [[ $got == 1 ]] || report "$1 $2: exit $got, expected 1 (usage error)"
  [[ $(wc -l <"$WORK/err") == 1 ]] || report "$1 $2: one line expected on stderr"
  rm -f out.vtu out.quality.csv
}
for n in 100000000 -1 1e3 ten 99999999999999999999; do usage_error -n "$n"; done
for m in -5 ten 1e99; do usage_error --max-elements "$m"; done

# An output that cannot be written is found out with nothing left behind:
# the mesh is not kept when its CSV fails.
unwritable() { # named, options...
  local named=$1; shift
  set +e
  "$BISECT" refine "$square" --region "$circle" -q "$@" >/dev/null 2>"$WORK/err"
  got=$?
  set -e
  [[ $got == 1 ]] || report "$*: exit $got, expected 1"
  { [[ $(wc -l <"$WORK/err") == 1 ]] && grep -qF -- "$named" "$WORK/err"; } ||
    report "$*: one line naming $named expected: $(head -c 200 "$WORK/err")"
  grep -q 'Success' "$WORK/err" && report "$*: message blames 'Success'"
  [[ ! -e out.vtu ]] || report "$*: out.vtu left behind although the CSV failed"
  rm -rf out.vtu out.quality.csv
}
unwritable "$WORK/none/q.csv" -o out.vtu --quality-csv "$WORK/none/q.csv"
mkdir csvdir
unwritable csvdir -o out.vtu --quality-csv csvdir --force
rmdir csvdir
unwritable "$WORK/none/o.vtu" -o "$WORK/none/o.vtu"

(( failures == 0 )) || fail "$failures failures over $cases bad cases"
echo "bad_corpus: $cases bad cases, ok"
