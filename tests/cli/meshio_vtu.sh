# .vtu files written by meshio (what users convert with): ascii, binary
# (header and data in one base64 text, unlike VTK), zlib, lzma and UInt64
# headers. bisect info reads the right counts (boundary lines as tagged entities) and
# bisect refine works on them. Needs /usr/bin/python3 with meshio
# (python3-meshio); skipped without it.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
/usr/bin/python3 -c "import meshio" 2>/dev/null ||
  fail "meshio_vtu: python3-meshio is not installed (scripts/install-deps.sh installs it)"
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
# And meshio reads what bisect writes: .vtu zlib (the default) and
# uncompressed (meshio 5 knows no LZ4 compressor: --compression lz4 is for
# VTK and ParaView, as the README says), and the .msh 4.1 binary with one block per entity, cells and cell data aligned.
printf '%s\n' '{"type": "sphere", "center": [0.3, 0.3, 0.3], "radius": 0.4}' >s3.json
for c in zlib lz4 none; do
  expect_exit 0 "$BISECT" refine tet-zlib.vtu --region s3.json -n 3 -o ours-$c.vtu --compression $c -q
done
expect_exit 0 "$BISECT" refine tet-zlib.vtu --region s3.json -n 3 -o ours.msh -q
cells=$("$BISECT" info ours.msh | sed -n 's/^cells: //p')
/usr/bin/python3 - "$cells" <<'PY' || fail "meshio misreads bisect's output"
import sys, meshio
cells = int(sys.argv[1])
for name in ["ours-zlib.vtu", "ours-none.vtu", "ours.msh"]:
    m = meshio.read(name)
    tets = [b for b in m.cells if b.type == "tetra"]
    n = sum(len(b.data) for b in tets)
    assert n == cells, (name, n, cells)
    for key in ("bisect:state", "bisect:marking", "region"):
        assert key in m.cell_data, (name, key, list(m.cell_data))
        assert sum(len(a) for a in m.cell_data[key]) == n, (name, key)
    print(name, n, "tets,", len(m.cell_data), "cell arrays")
PY
# A bisection state altered by a user (one cell's bisect:state, through
# meshio): every command that reads it refuses the file, check included.
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 2 -o kuhn.vtu
expect_exit 0 "$BISECT" refine kuhn.vtu --region "$ROOT/data/regions/sphere.json" -n 3 -o kuhn-r.vtu -q --quality-csv none
expect_exit 0 "$BISECT" check kuhn-r.vtu
/usr/bin/python3 - <<'PY' || fail "meshio could not alter the state"
import meshio
m = meshio.read("kuhn-r.vtu")
s = m.cell_data["bisect:state"][0]
s[4] = int(s[4]) ^ 1
meshio.write("kuhn-altered.vtu", m)
PY
for cmd in check info; do
  expect_exit 1 "$BISECT" $cmd kuhn-altered.vtu
  grep -q "kuhn-altered.vtu: the bisection state is inconsistent" "$WORK/err" ||
    fail "$cmd of an altered state: $(cat "$WORK/err")"
done
echo "meshio_vtu: $n files ok, and meshio reads bisect's .vtu (zlib, none) and .msh; an altered state is refused"
