#!/usr/bin/python3
"""Closed surfaces nobody here tuned for, from installed Debian packages (issue 21): CGAL's data
meshes (libcgal-dev, /usr/share/doc/libcgal-dev/data.tar.gz) and OCCT's sample STLs (occt-misc,
/usr/share/opencascade/data/stl). Extracts the listed ones into OUT and prints their paths, one
per line, for `benchmarks/run_robustness.py --files`. The dev meshes (../shared/data/dev) that
come from these packages are left out. Nothing is downloaded; a missing package is reported.

Usage: /usr/bin/python3 benchmarks/unseen_surfaces.py OUT
Standard library only.
"""
import os
import shutil
import sys
import tarfile

CGAL = "/usr/share/doc/libcgal-dev/data.tar.gz"
OCCT = "/usr/share/opencascade/data/stl"
# Accepted by `curvefem check` (closed, manifold, oriented), not among the dev meshes.
CGAL_NAMES = ["bear", "blobby", "cactus", "dino", "femur", "hand", "handle", "helmet", "knot1",
              "retinal", "triceratops", "eight", "blob-closed", "couplingdown", "dragknob",
              "itemb", "joint", "part", "pinion", "rotor", "spool", "turbine", "pipe", "tripod",
              "cross", "u"]
OCCT_NAMES = ["sh1", "sh2"]

out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/unseen"
os.makedirs(out, exist_ok=True)
paths = []
if os.path.exists(CGAL):
    with tarfile.open(CGAL) as tar:
        for n in CGAL_NAMES:
            member = tar.getmember(f"data/meshes/{n}.off")
            dest = os.path.join(out, f"cgal_{n}.off")
            with tar.extractfile(member) as src, open(dest, "wb") as dst:
                shutil.copyfileobj(src, dst)
            paths.append(dest)
else:
    print(f"missing {CGAL} (apt-get install libcgal-dev)", file=sys.stderr)
for n in OCCT_NAMES:
    src = os.path.join(OCCT, n + ".stl")
    if os.path.exists(src):
        dest = os.path.join(out, f"occt_{n}.stl")
        shutil.copyfile(src, dest)
        paths.append(dest)
    else:
        print(f"missing {src} (apt-get install occt-misc)", file=sys.stderr)
print("\n".join(paths))
