# The module refines exactly as the command line does.
import json
import subprocess
import time

import meshio
import pybisect
from conftest import DATA


def cell_sets(points, cells):
    return sorted(tuple(sorted(map(tuple, points[c]))) for c in cells)


def test_refine_matches_the_cli(bisect_bin, tmp_path):
    region_file = DATA / "regions" / "hemisphere.json"
    out = tmp_path / "ball-2.vtu"
    t0 = time.perf_counter()
    subprocess.run([bisect_bin, "refine", str(DATA / "ball.msh"), "--region", str(region_file),
                    "-n", "2", "-o", str(out), "--quality-csv", "none", "-q"], check=True)
    cli_seconds = time.perf_counter() - t0
    t0 = time.perf_counter()
    mesh = pybisect.read(DATA / "ball.msh")
    region = json.loads(region_file.read_text())
    for _ in range(2):
        mesh.refine(region=region)
    mesh.check(full=False)
    module_seconds = time.perf_counter() - t0
    cli = meshio.read(out)
    cli_cells = cli.cells_dict["tetra"]
    assert len(cli_cells) == mesh.num_cells
    assert cell_sets(cli.points, cli_cells) == cell_sets(mesh.points, mesh.cells)
    # and the CLI's file, read back, is the module's mesh with the same state
    back = pybisect.read(out)
    assert (back.cells == mesh.cells).all()
    print(f"refine -n 2 ball.msh: cli {cli_seconds:.3f} s, module {module_seconds:.3f} s")


def test_errors_carry_the_cli_message(bisect_bin, tmp_path):
    # The same failure through the binary and through the module: the
    # exception's message is the CLI's stderr line without "bisect: ".
    bad_region = tmp_path / "bad.json"
    bad_region.write_text('{"type": "sphere", "center": [0, 0, 0], "radius": -1}')
    missing = tmp_path / "missing.msh"
    cases = [
        ([str(missing), "--region", str(DATA / "regions" / "sphere.json")],
         lambda: pybisect.read(missing)),
        ([str(DATA / "ball.msh"), "--region", str(bad_region)],
         lambda: pybisect.read(DATA / "ball.msh").refine(region=str(bad_region))),
    ]
    for args, call in cases:
        cli = subprocess.run([bisect_bin, "refine", *args, "-o", str(tmp_path / "out.vtu"), "-q"],
                             capture_output=True, text=True)
        assert cli.returncode == 1
        try:
            call()
        except pybisect.Error as e:
            assert "bisect: " + str(e) == cli.stderr.strip()
        else:
            raise AssertionError("no error")
