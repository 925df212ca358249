# Coincident duplicate vertices (an export that did not merge nodes) are
# reported as duplicates, naming both and where they are, not as a hanging
# node; 2D and 3D.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
/usr/bin/python3 - <<'PY'
import meshio, numpy as np
p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0.]])
meshio.write("dup2.vtu", meshio.Mesh(p, [("triangle", np.array([[0, 1, 2], [4, 3, 2]]))]))
p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [0, 1, 0.]])
meshio.write("dup3.vtu", meshio.Mesh(p, [("tetra", np.array([[0, 1, 2, 3], [1, 5, 3, 4]]))]))
PY
expect_exit 1 "$BISECT" info dup2.vtu
one_line_naming "dup2.vtu: duplicate vertices: 1 and 4 are both at (1, 0)"
expect_exit 1 "$BISECT" refine dup3.vtu --region "$ROOT/data/regions/everything3d.json" -o out.vtu
one_line_naming "dup3.vtu: duplicate vertices: 2 and 5 are both at (0, 1, 0)"
[[ ! -e out.vtu ]] || fail "an output was written"
echo "duplicates: reported as duplicates in 2D and 3D"
