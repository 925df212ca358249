# refine --indicator NAME (--above X | --top F | --dorfler THETA) [--depth K]:
# the marked sets follow the rules exactly (counted against numpy), --depth K
# bisects every marked cell K times (each output cell inside a marked input
# cell has at most 1/2^K of its volume), the result conforms, and bad
# indicators get one line naming the file and the problem.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
# Files are made and measured with the pybisect module of this build (meshio
# has no 4D cells).
export PYTHONPATH="$(dirname "$BISECT")/python${PYTHONPATH:+:$PYTHONPATH}"
/usr/bin/python3 -c 'import pybisect' 2>/dev/null || fail "pybisect is not built in $(dirname "$BISECT")/python"
for dim in 2 3 4; do
  expect_exit 0 "$BISECT" generate kuhn --dim "$dim" --cells 3 -o "k$dim.vtu" -q
done
/usr/bin/python3 - <<'PY'
import pybisect, numpy as np
rng = np.random.default_rng(7)
for dim in (2, 3, 4):
    k = pybisect.read(f"k{dim}.vtu")
    n = k.num_cells
    eta = rng.random(n)
    eta[5] = eta[6] = eta.max()          # a tie: the lower id goes first
    nan = eta.copy(); nan[4] = np.nan
    neg = eta.copy(); neg[2] = -1
    m = pybisect.Mesh(k.points, k.cells, point_data={"peta": rng.random(k.num_vertices)},
                      cell_data={"eta": eta, "bad3": np.zeros((n, 3)), "nan": nan, "neg": neg})
    m.write(f"in{dim}.vtu")
    order = sorted(range(n), key=lambda c: (-eta[c], c))
    top = order[: int(np.ceil(0.1 * n))]
    total, acc, dor = (eta ** 2).sum(), 0.0, []
    for c in order:
        if acc >= 0.5 * total:
            break
        dor.append(c); acc += eta[c] ** 2
    with open(f"expect{dim}.txt", "w") as f:
        f.write(f"{int((eta > 0.7).sum())} {len(top)} {len(dor)}\n")
    np.save(f"eta{dim}.npy", eta)
PY
for dim in 2 3 4; do
  read -r above top dorfler <"expect$dim.txt"
  for rule in "--above 0.7:$above" "--top 0.1:$top" "--dorfler 0.5:$dorfler"; do
    opt=${rule%:*} want=${rule##*:}
    # shellcheck disable=SC2086
    expect_exit 0 "$BISECT" refine "in$dim.vtu" --indicator eta $opt -o "out$dim.vtu" -f -q --json
    got=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["selected"])' "$WORK/out")
    [[ $got == "$want" ]] || fail "$dim D $opt: $got cells marked, expected $want"
    expect_exit 0 "$BISECT" check "out$dim.vtu" --against "in$dim.vtu"
  done
  # A point array: a cell's value is the largest of its vertices'.
  expect_exit 0 "$BISECT" refine "in$dim.vtu" --indicator peta --top 0.2 -o "p$dim.vtu" -f -q
  expect_exit 0 "$BISECT" check "p$dim.vtu" --against "in$dim.vtu"
  # --depth: every cell inside a marked cell is 2^-depth of it or smaller.
  for depth in 2 "$dim"; do
    expect_exit 0 "$BISECT" refine "in$dim.vtu" --indicator eta --top 0.05 --depth "$depth" \
      -o "d$dim.vtu" -f -q
    expect_exit 0 "$BISECT" check "d$dim.vtu" --against "in$dim.vtu"
    /usr/bin/python3 - "$dim" "$depth" <<'PY'
import sys, math, pybisect, numpy as np
dim, depth = int(sys.argv[1]), int(sys.argv[2])
def cells(name):
    m = pybisect.read(name)
    x = np.asarray(m.points)[np.asarray(m.cells)]
    vol = np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / math.factorial(dim)
    return x, vol
xin, vin = cells(f"in{dim}.vtu")
xout, vout = cells(f"d{dim}.vtu")
eta = np.load(f"eta{dim}.npy")
n = len(eta)
marked = sorted(range(n), key=lambda c: (-eta[c], c))[: int(np.ceil(0.05 * n))]
cent = xout.mean(axis=1)
for c in marked:
    # barycentric coordinates of the output centroids in input cell c
    a = xin[c]
    T = (a[1:] - a[0]).T
    lam = np.linalg.solve(T, (cent - a[0]).T).T
    inside = (lam >= -1e-12).all(axis=1) & (lam.sum(axis=1) <= 1 + 1e-12)
    assert inside.any(), c
    worst = vout[inside].max() / vin[c]
    assert worst <= 0.5 ** depth * (1 + 1e-9), (dim, depth, c, worst)
PY
  done
  # Errors: one line naming the file.
  expect_exit 1 "$BISECT" refine "in$dim.vtu" --indicator missing --above 0 -o x.vtu
  one_line_naming "in$dim.vtu: no cell or point array 'missing'"
  grep -q "cell array 'eta'" "$WORK/err" || fail "the message does not list the arrays"
  expect_exit 1 "$BISECT" refine "in$dim.vtu" --indicator bad3 --above 0 -o x.vtu
  one_line_naming "3 components"
  expect_exit 1 "$BISECT" refine "in$dim.vtu" --indicator nan --above 0 -o x.vtu
  one_line_naming "cell 4: indicator 'nan' is nan"
  expect_exit 1 "$BISECT" refine "in$dim.vtu" --indicator neg --dorfler 0.5 -o x.vtu
  one_line_naming "cell 2: indicator value -1 is negative"
  [[ ! -e x.vtu ]] || fail "an error left x.vtu"
done
# A .msh input's errors name its element tags (here 17 and 23, nodes 101..).
cat >tagged.msh <<'MSH'
$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
4
413 0 1 0
309 1 1 0
205 1 0 0
101 0 0 0
$EndNodes
$Elements
2
23 2 2 1 1 101 309 413
17 2 2 1 1 101 205 309
$EndElements
$ElementData
1
"eta"
1
0.0
3
0
1
2
17 0.5
23 -1
$EndElementData
MSH
expect_exit 1 "$BISECT" refine tagged.msh --indicator eta --dorfler 0.5 -o x.vtu
one_line_naming "tagged.msh: element 23: indicator value -1 is negative"
# Usage errors.
expect_exit 1 "$BISECT" refine in2.vtu --indicator eta -o x.vtu
one_line_naming "exactly one of --above X, --top F, --dorfler THETA"
expect_exit 1 "$BISECT" refine in2.vtu --indicator eta --top 1.5 -o x.vtu
one_line_naming "--top"
expect_exit 1 "$BISECT" refine in2.vtu --indicator eta --above 0.5 -n 3 -o x.vtu
one_line_naming "--iterations with --indicator"
expect_exit 1 "$BISECT" refine in2.vtu -o x.vtu
one_line_naming "needs --region SPEC or --indicator NAME"
# With --region too: the union of both markings.
expect_exit 0 "$BISECT" refine in3.vtu --indicator eta --above 0.99 -o a.vtu -f -q --json
only_ind=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["selected"])' "$WORK/out")
expect_exit 0 "$BISECT" refine in3.vtu --region "$ROOT/data/regions/everything3d.json" -o b.vtu -f -q --json
everything=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["selected"])' "$WORK/out")
expect_exit 0 "$BISECT" refine in3.vtu --indicator eta --above 0.99 \
  --region "$ROOT/data/regions/everything3d.json" -o c.vtu -f -q --json
both=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["selected"])' "$WORK/out")
[[ $both == "$everything" && $only_ind -lt $everything ]] || fail "union: $only_ind, $everything, $both"
# --origin: each output cell lies in the input cell it names, and the cells
# naming an input cell fill it (their volumes sum to its volume).
for dim in 2 3 4; do
  expect_exit 0 "$BISECT" refine "in$dim.vtu" --indicator eta --top 0.1 --depth 2 --origin \
    -o "o$dim.vtu" -f -q
  /usr/bin/python3 - "$dim" <<'PY'
import sys, math, pybisect, numpy as np
dim = int(sys.argv[1])
def geo(m):
    x = np.asarray(m.points)[np.asarray(m.cells)]
    return x, np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / math.factorial(dim)
a, b = pybisect.read(f"in{dim}.vtu"), pybisect.read(f"o{dim}.vtu")
xa, va = geo(a)
xb, vb = geo(b)
origin = np.asarray(b.cell_data["bisect:origin"]).astype(int)
assert origin.min() >= 0 and origin.max() < a.num_cells
sums = np.bincount(origin, weights=vb, minlength=a.num_cells)
assert np.allclose(sums, va, rtol=1e-12, atol=0), "volumes by origin differ"
cent = xb.mean(axis=1)
p0 = xa[origin, 0]
T = np.transpose(xa[origin, 1:] - p0[:, None, :], (0, 2, 1))
lam = np.linalg.solve(T, (cent - p0)[..., None])[..., 0]
assert (lam > -1e-12).all() and (lam.sum(axis=1) < 1 + 1e-12).all(), "a cell outside its origin"
PY
done
echo "indicator: rules, depth, point arrays, union and errors in 2D, 3D, 4D"
