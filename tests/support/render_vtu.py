"""Renders a .vtu offscreen with VTK (as ParaView would show its surface,
coloured by the first cell array, edges on) into a PNG and checks the
picture is not blank. Run under `xvfb-run -a`: tests/cli/vtk_readers.sh."""
import sys, vtk
path, png = sys.argv[1], sys.argv[2]
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(path); r.Update()
g = r.GetOutput()
surf = vtk.vtkDataSetSurfaceFilter(); surf.SetInputData(g)
m = vtk.vtkPolyDataMapper(); m.SetInputConnection(surf.GetOutputPort())
name = g.GetCellData().GetArrayName(0)
m.SetScalarModeToUseCellFieldData(); m.SelectColorArray(name); m.ScalarVisibilityOn()
a = vtk.vtkActor(); a.SetMapper(m); a.GetProperty().EdgeVisibilityOn()
ren = vtk.vtkRenderer(); ren.AddActor(a); ren.SetBackground(1, 1, 1); ren.ResetCamera()
w = vtk.vtkRenderWindow(); w.SetOffScreenRendering(1); w.AddRenderer(ren); w.SetSize(400, 300); w.Render()
f = vtk.vtkWindowToImageFilter(); f.SetInput(w); f.Update()
out = vtk.vtkPNGWriter(); out.SetFileName(png); out.SetInputConnection(f.GetOutputPort()); out.Write()
img = f.GetOutput(); sc = img.GetPointData().GetScalars()
n = img.GetNumberOfPoints(); nonwhite = sum(1 for i in range(0, n, 7) if sc.GetTuple(i)[:3] != (255.0, 255.0, 255.0))
print(png, "non-white samples", nonwhite)
assert nonwhite > 50
