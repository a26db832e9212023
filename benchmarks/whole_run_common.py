"""Shared pieces of the whole-run benchmarks (run_fem_whole.py, run_elasticity_whole.py): a Gmsh
box mesh and a timed whole process."""
import os
import subprocess
import sys
import time


def gmsh_box(work, name, size, h, surfaces):
    """Meshes the OpenCASCADE box [0, size] with characteristic length h into WORK/NAME.msh
    (MSH 4.1). `surfaces`: {physical tag: [box face numbers]} (faces 1 x = 0, 2 x = max, 3 y = 0,
    4 y = max, 5 z = 0, 6 z = max). Returns the .msh path."""
    geo, msh = os.path.join(work, name + ".geo"), os.path.join(work, name + ".msh")
    with open(geo, "w") as f:
        f.write('SetFactory("OpenCASCADE");\n'
                f"Box(1) = {{0,0,0,{size[0]},{size[1]},{size[2]}}};\n"
                f"Mesh.CharacteristicLengthMax = {h};\nMesh.CharacteristicLengthMin = {h};\n"
                "Physical Volume(1) = {1};\n")
        for tag, faces in surfaces.items():
            f.write(f"Physical Surface({tag}) = {{{','.join(str(x) for x in faces)}}};\n")
    subprocess.run(["gmsh", geo, "-3", "-o", msh, "-format", "msh41"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return msh


def timed(cmd):
    """(wall seconds, stdout) of one whole process; exits naming the command if it fails."""
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr[-2000:]}")
    return wall, r.stdout
