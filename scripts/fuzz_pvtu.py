#!/usr/bin/python3
"""Mutation fuzzer for .pvtu input (an index file naming .vtu pieces), run
against the real binary: a case mutates the index or one of its two pieces
(byte flips, deletions, insertions of hostile tokens, truncation) and runs
`bisect refine CASE.pvtu --region sphere -o out.vtu`, then `bisect check` on
any output. Outcomes: exit 0 with a conforming mesh, exit 1 with one line
on stderr; anything else (a signal, a hang over 20 s, a non-conforming exit
0, a message of several lines) is a finding, copied to OUT/finding-N/.

usage: scripts/fuzz_pvtu.py --binary build/bisect --cases 4000 --seed 12 [--out DIR]
The seed .pvtu is written by VTK's own vtkXMLPUnstructuredGridWriter
(python3-vtk9) from a Kuhn cube the binary generates, in ASCII.
"""
import argparse
import os
import random
import shutil
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOKENS = [b"-1", b"1e999", b"nan", b"99999999999", b'"', b"<", b">", b"/", b"_0.vtu", b"/dev/zero"]


def mutate(rng, data):
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if not b:
            break
        op, i = rng.random(), rng.randrange(len(b))
        if op < 0.4:
            b[i] = rng.randrange(256)
        elif op < 0.6:
            del b[i:i + rng.randint(1, 40)]
        elif op < 0.8:
            b[i:i] = rng.choice(TOKENS)
        else:
            b = b[:i]
    return bytes(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default=os.path.join(ROOT, "build", "bisect"))
    ap.add_argument("--cases", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=None, help="where findings go (default: a temporary directory)")
    a = ap.parse_args()
    import vtk  # python3-vtk9
    work = tempfile.mkdtemp(prefix="bisect-fuzz-pvtu-")
    out = a.out or work
    os.makedirs(out, exist_ok=True)
    subprocess.run([a.binary, "generate", "kuhn", "--dim", "3", "--cells", "2", "-o",
                    os.path.join(work, "k.vtu"), "-q"], check=True)
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(os.path.join(work, "k.vtu"))
    piece = vtk.vtkExtractUnstructuredGridPiece()
    piece.SetInputConnection(r.GetOutputPort())
    w = vtk.vtkXMLPUnstructuredGridWriter()
    w.SetFileName(os.path.join(work, "seed.pvtu"))
    w.SetInputConnection(piece.GetOutputPort())
    w.SetNumberOfPieces(2)
    w.SetStartPiece(0)
    w.SetEndPiece(1)
    w.SetDataModeToAscii()
    w.Write()
    files = ["seed.pvtu", "seed_0.vtu", "seed_1.vtu"]
    seeds = [open(os.path.join(work, f), "rb").read() for f in files]
    region = os.path.join(ROOT, "data", "regions", "sphere.json")
    rng = random.Random(a.seed)
    counts, findings = {}, 0
    case = os.path.join(work, "case")
    for k in range(a.cases):
        os.makedirs(case, exist_ok=True)
        which = rng.randrange(3)
        for i, f in enumerate(files):
            open(os.path.join(case, f), "wb").write(mutate(rng, seeds[i]) if i == which else seeds[i])
        result = os.path.join(case, "out.vtu")
        try:
            p = subprocess.run([a.binary, "refine", os.path.join(case, "seed.pvtu"), "--region", region,
                                "-o", result, "-f", "-q", "--quality-csv", "none"],
                               capture_output=True, timeout=20)
            outcome = str(p.returncode)
            if p.returncode == 0:
                if subprocess.run([a.binary, "check", result], capture_output=True).returncode != 0:
                    outcome = "non-conforming exit 0"
            elif p.returncode == 1:
                if len(p.stderr.decode(errors="replace").strip().splitlines()) != 1:
                    outcome = "exit 1, not one line"
            elif p.returncode < 0:
                outcome = f"signal {-p.returncode}"
        except subprocess.TimeoutExpired:
            outcome = "hang"
        counts[outcome] = counts.get(outcome, 0) + 1
        if outcome not in ("0", "1"):
            findings += 1
            shutil.copytree(case, os.path.join(out, f"finding-{k}"), dirs_exist_ok=True)
        shutil.rmtree(case)
    print(f"{a.cases} cases (seed {a.seed}): " +
          ", ".join(f"{n} {o}" for o, n in sorted(counts.items())) +
          f"; {findings} findings" + (f" in {out}" if findings else ""))
    if not a.out:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if findings else 0


if __name__ == "__main__":
    raise SystemExit(main())
