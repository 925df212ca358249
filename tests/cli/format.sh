# The C++ sources follow .clang-format (clang-format 14, Debian's
# clang-format package): `clang-format -i` on them changes nothing.
source "$(dirname "$0")/lib.bash"
cd "$ROOT"
command -v clang-format >/dev/null || fail "clang-format is missing (scripts/install-deps.sh installs it)"
mapfile -t files < <(find src include apps tests bench fuzz python examples \
  \( -name '*.cpp' -o -name '*.hpp' \) -not -path 'fuzz/crashes/*' -not -path 'tests/bad/*' | sort)
((${#files[@]} > 50)) || fail "only ${#files[@]} C++ files found"
if ! clang-format --dry-run --Werror "${files[@]}" 2>"$WORK/format.log"; then
  grep -m 10 "warning:" "$WORK/format.log" >&2
  fail "$(grep -c 'warning:' "$WORK/format.log") places differ from .clang-format (run: clang-format -i on them)"
fi
echo "format: ${#files[@]} files follow .clang-format"
