# Reading a .pvtu (read_pvtu): one VTK's own parallel writer made
# (vtkXMLPUnstructuredGridWriter, the one ParaView uses, with the grid split
# into pieces that share points by vtkExtractUnstructuredGridPiece) reads as the mesh it was written from:
# `bisect info` gives the same cells, vertices, volume and boundary; refining
# it continues the bisection sequence (2D, 3D, 4D). Bad .pvtu files get one
# line naming the file. (VTK's split may put a tagged boundary facet in
# another piece than its cell, with its points; such a piece is refused as
# the piece's own .vtu would be. The .pvtu a distributed refine writes keeps
# each facet with its cells: tests/mpi/.)
source "$(dirname "$0")/lib.bash"
cd "$WORK"
R=$ROOT/data/regions
"$BISECT" generate kuhn --dim 2 --cells 6 -o k2.vtu -q
"$BISECT" generate kuhn --dim 3 --cells 3 -o k3.vtu -q
"$BISECT" refine k2.vtu --region "$R/circle.json" -n 3 -o a2.vtu -q --quality-csv none
"$BISECT" refine k3.vtu --region "$R/hemisphere.json" -n 2 -o a3.vtu -q --quality-csv none
"$BISECT" generate kuhn --dim 4 --cells 1 -o h.vtu -q
"$BISECT" refine h.vtu --region "$R/moving-sphere.json" -n 6 -o a4.vtu -q --quality-csv none
for d in 2 3 4; do
  /usr/bin/python3 - a$d.vtu p$d.pvtu <<'PY'
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
piece = vtk.vtkExtractUnstructuredGridPiece()  # each piece its share of the cells
piece.SetInputConnection(r.GetOutputPort())
w = vtk.vtkXMLPUnstructuredGridWriter()
w.SetFileName(sys.argv[2]); w.SetInputConnection(piece.GetOutputPort())
w.SetNumberOfPieces(3); w.SetStartPiece(0); w.SetEndPiece(2)
w.Write()
PY
  ls p${d}_*.vtu >/dev/null || fail "VTK wrote no pieces for p$d.pvtu"
  a=$("$BISECT" info a$d.vtu | grep -E '^(dimension|cells|vertices|volume|boundary|tagged)')
  p=$("$BISECT" info p$d.pvtu | grep -E '^(dimension|cells|vertices|volume|boundary|tagged)')
  [[ $a == "$p" ]] || { diff <(echo "$a") <(echo "$p") >&2; fail "${d}D: the .pvtu reads differently"; }
  "$BISECT" refine a$d.vtu --region "$([[ $d == 2 ]] && echo "$R/circle.json" || ([[ $d == 3 ]] && echo "$R/hemisphere.json" || echo "$R/moving-sphere.json"))" \
    -n 2 -o b$d.vtu -q --quality-csv none
  "$BISECT" refine p$d.pvtu --region "$([[ $d == 2 ]] && echo "$R/circle.json" || ([[ $d == 3 ]] && echo "$R/hemisphere.json" || echo "$R/moving-sphere.json"))" \
    -n 2 -o c$d.vtu -q --quality-csv none
  [[ $("$BISECT" info b$d.vtu | grep -E '^(cells|vertices|volume|boundary)') == $("$BISECT" info c$d.vtu | grep -E '^(cells|vertices|volume|boundary)') ]] ||
    fail "${d}D: refining the .pvtu does not continue the sequence"
done
# Bad index files and pieces.
echo '<VTKFile type="UnstructuredGrid"></VTKFile>' >bad1.pvtu
expect_exit 1 "$BISECT" info bad1.pvtu
one_line_naming bad1.pvtu
echo '<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid></PUnstructuredGrid></VTKFile>' >bad2.pvtu
expect_exit 1 "$BISECT" info bad2.pvtu
one_line_naming bad2.pvtu
echo '<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid><Piece Source="missing_0.vtu"/></PUnstructuredGrid></VTKFile>' >bad3.pvtu
expect_exit 1 "$BISECT" info bad3.pvtu
one_line_naming missing_0.vtu
printf '<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid><Piece Source="p2_0.vtu"/><Piece Source="p3_0.vtu"/></PUnstructuredGrid></VTKFile>' >mixed.pvtu
expect_exit 1 "$BISECT" info mixed.pvtu
one_line_naming mixed.pvtu
for src in /dev/zero p2.pvtu "$WORK"; do
  echo "<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid><Piece Source=\"$src\"/></PUnstructuredGrid></VTKFile>" >odd.pvtu
  expect_exit 1 timeout 10 "$BISECT" info odd.pvtu
  one_line_naming odd.pvtu
done
mkfifo fifo.vtu
echo '<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid><Piece Source="fifo.vtu"/></PUnstructuredGrid></VTKFile>' >fifo.pvtu
expect_exit 1 timeout 10 "$BISECT" info fifo.pvtu
one_line_naming fifo.vtu
echo "pvtu: VTK's parallel writer's .pvtu read as the mesh in 2D, 3D, 4D; bad ones refused"
