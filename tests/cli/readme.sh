# The README is the user's manual: every command example in a ```sh block
# runs as written, in order, in a scratch directory (with `bisect` on PATH and
# the bundled data/ beside it), and exits 0. The two ```bash set-up blocks
# (scripts/run-sample.sh, scripts/test.sh) are what CI and a newcomer run.
source "$(dirname "$0")/lib.bash"
mkdir -p "$WORK/bin" "$WORK/run"
ln -s "$BISECT" "$WORK/bin/bisect"
ln -s "$ROOT/data" "$WORK/run/data"
ln -s "$ROOT/scripts" "$WORK/run/scripts"
ln -s "$(dirname "$BISECT")" "$WORK/run/build" # the build tree (cmake --install build ...)
cd "$WORK/run"
export PATH="$WORK/bin:$PATH"
# Fences may be indented (an example inside a list item): so may its lines.
commands=$(awk '/^ *```/ { if (inside) { inside = 0; next } if ($0 ~ /^ *```sh$/) { inside = 1; next } }
                inside { sub(/^ +/, ""); print }' "$ROOT/README.md")
[[ -n $commands ]] || fail "no sh blocks in README.md"
count=0
while IFS= read -r line; do
  [[ -z $line || $line == \#* ]] && continue
  count=$((count + 1))
  set +e
  bash -c "$line" >"$WORK/out" 2>"$WORK/err"
  got=$?
  set -e
  [[ $got == 0 ]] || { tail -3 "$WORK/err" >&2; fail "README example exits $got: $line"; }
done <<<"$commands"
(( count >= 20 )) || fail "only $count README examples found"
# Every command's --help ends with an example, as the README promises.
for cmd in $("$BISECT" --help | awk '/^Subcommands:/ { on = 1; next } on && !NF { exit } on && /^  [a-z]/ { print $1 }'); do
  "$BISECT" "$cmd" --help | grep -q "^Examples\?: bisect $cmd " || fail "bisect $cmd --help has no example"
done
echo "readme: $count examples ran"
