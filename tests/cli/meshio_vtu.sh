# .vtu files written by meshio (what users convert with): ascii, binary
# (header and data in one base64 text, unlike VTK), zlib, lzma and UInt64
# headers. bisect info reads the right counts (boundary lines ignored) and
# bisect refine works on them. Needs /usr/bin/python3 with meshio
# (python3-meshio); skipped without it.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
if ! /usr/bin/python3 -c "import meshio" 2>/dev/null; then
  echo "meshio_vtu: skipped (no meshio for /usr/bin/python3)"
  exit 0
fi
/usr/bin/python3 "$ROOT/tests/cli/meshio_write.py" 2>/dev/null
n=0
for kind in ascii binary zlib lzma zlib64; do
  for shape in tri tet; do
    f=$shape-$kind.vtu
    [[ -f $f ]] || fail "meshio did not write $f"
    expect_exit 0 "$BISECT" info "$f"
    if [[ $shape == tri ]]; then
      dim=2 cells=32 vertices=25 cell_array=material point_array=temperature
      region=$ROOT/data/regions/circle.json
    else
      dim=3 cells=6 vertices=8 cell_array=region point_array=u
      region=$ROOT/data/regions/sphere.json
    fi
    grep -qx "dimension: $dim" "$WORK/out" || fail "$f: dimension $dim expected"
    grep -qx "cells: $cells" "$WORK/out" || fail "$f: $cells cells expected: $(cat "$WORK/out")"
    grep -qx "vertices: $vertices" "$WORK/out" || fail "$f: $vertices vertices expected"
    grep -q "cell array: $cell_array (1 components)" "$WORK/out" || fail "$f: cell array $cell_array"
    grep -q "point array: $point_array (1 components)" "$WORK/out" || fail "$f: point array $point_array"
    expect_exit 0 "$BISECT" refine "$f" --region "$region" -n 2 -o "out-$f" --quiet --check
    expect_exit 0 "$BISECT" check "out-$f" --against "$f"
    n=$((n + 1))
  done
done
echo "meshio_vtu: $n files ok"
