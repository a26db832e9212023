#!/usr/bin/python3
"""A second set of closed surfaces nobody here tuned for (issue 21): CAD-like solids written as
Gmsh OpenCASCADE scripts and triangulated by Debian's `gmsh` binary, with the traps a CAD user
brings: fillets beside sharp edges, through-holes, holes far below ε (a plate with 16 holes of
radius 0.005 of its size, 275k faces after curvature refinement), two spheres 0.13 ε apart, a
slot 0.3 ε wide cut into a sphere, a thin torus, a cone's apex, three cylinders fused at a ball,
a 1.4° wedge, an anisotropic fine ellipsoid. Writes OUT/NAME.obj (the triangles of the volume's
boundary, orientation made consistent and outward) and prints their paths, one per line, for
`benchmarks/run_robustness.py --files`. Results: benchmarks/results/robustness_unseen_gmsh.md.

Usage: /usr/bin/python3 benchmarks/unseen_gmsh_shapes.py OUT [NAME ...]
Needs the gmsh binary and python3-meshio, python3-numpy; nothing is downloaded.
"""
import collections
import os
import subprocess
import sys

import meshio
import numpy as np

HEAD = 'SetFactory("OpenCASCADE");\n'
SHAPES = {
    "holes_fillet": """Box(1) = {0,0,0, 4,2,1};
Cylinder(2) = {1,1,-1, 0,0,3, 0.4};
Cylinder(3) = {3,1,-1, 0,0,3, 0.15};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2,3}; Delete; }
f() = Abs(Boundary{Volume{1};});
e() = Unique(Abs(Boundary{Surface{f()};}));
Fillet{1}{e()}{0.08}
Mesh.MeshSizeMax = 0.15;
""",
    "near_spheres": """Sphere(1) = {0,0,0, 1};
Sphere(2) = {2.004,0,0, 1};
Mesh.MeshSizeMax = 0.1;
""",
    "thin_torus": """Torus(1) = {0,0,0, 1, 0.03};
Mesh.MeshSizeMax = 0.02;
""",
    "plate_small_holes": """Box(1) = {0,0,0, 2,2,0.2};
For i In {0:3}
  For j In {0:3}
    Cylinder(10+i*4+j) = {0.3+0.45*i, 0.3+0.45*j, -0.1, 0,0,0.4, 0.01};
  EndFor
EndFor
BooleanDifference{ Volume{1}; Delete; }{ Volume{10:25}; Delete; }
Mesh.MeshSizeMax = 0.1;
Mesh.MeshSizeFromCurvature = 12;
""",
    "cyl_box_union": """Box(1) = {-1,-1,-0.3, 2,2,0.6};
Cylinder(2) = {0,0,-1.5, 0.3,0.2,3, 0.35};
BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Mesh.MeshSizeMax = 0.08;
""",
    "cone": """Cone(1) = {0,0,0, 0,0,2, 0.5, 0};
Mesh.MeshSizeMax = 0.05;
""",
    "tripod": """Cylinder(1) = {0,0,0, 1,0,0, 0.1};
Cylinder(2) = {0,0,0, 0,1,0, 0.1};
Cylinder(3) = {0,0,0, 0,0,1, 0.1};
Sphere(4) = {0,0,0, 0.18};
BooleanUnion{ Volume{1}; Delete; }{ Volume{2,3,4}; Delete; }
Mesh.MeshSizeMax = 0.03;
""",
    "slot_sphere": """Sphere(1) = {0,0,0, 1};
Box(2) = {-2,-0.004,0, 4,0.008,2};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Mesh.MeshSizeMax = 0.08;
""",
    "bracket": """Box(1) = {0,0,0, 3,1,0.2};
Box(2) = {0,0,0, 0.2,1,1.5};
BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Cylinder(3) = {2.3,0.5,-1, 0,0,2, 0.2};
BooleanDifference{ Volume{1}; Delete; }{ Volume{3}; Delete; }
Fillet{1}{7}{0.15}
Mesh.MeshSizeMax = 0.06;
""",
    "wedge": """Point(1) = {0,0,0}; Point(2) = {2,0,0}; Point(3) = {2,0.05,0};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,1};
Curve Loop(1) = {1,2,3}; Plane Surface(1) = {1};
Extrude {0,0,1} { Surface{1}; }
Mesh.MeshSizeMax = 0.1;
""",
    "fine_sphere_aniso": """Sphere(1) = {0,0,0, 1};
Dilate {{0,0,0},{3,1,0.3}} { Volume{1}; }
Mesh.MeshSizeMax = 0.04;
""",
}


def orient(F, V):
    """Faces turned consistently across every edge (breadth first per component), then outward
    (positive signed volume per component)."""
    F = F.copy()
    edge_faces = collections.defaultdict(list)
    for f, t in enumerate(F):
        for k in range(3):
            edge_faces[frozenset((int(t[k]), int(t[(k + 1) % 3])))].append(f)
    seen = np.zeros(len(F), bool)
    for start in range(len(F)):
        if seen[start]:
            continue
        seen[start] = True
        component, queue = [start], collections.deque([start])
        while queue:
            f = queue.popleft()
            for k in range(3):
                a, b = int(F[f][k]), int(F[f][(k + 1) % 3])
                for g in edge_faces[frozenset((a, b))]:
                    if g == f or seen[g]:
                        continue
                    if any(F[g][j] == a and F[g][(j + 1) % 3] == b for j in range(3)):
                        F[g] = F[g][::-1]
                    seen[g] = True
                    component.append(g)
                    queue.append(g)
        T = F[component]
        volume = np.einsum("ij,ij->i", V[T[:, 0]], np.cross(V[T[:, 1]], V[T[:, 2]])).sum()
        if volume < 0:
            F[component] = F[component][:, ::-1]
    return F


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    names = sys.argv[2:] or list(SHAPES)
    os.makedirs(out, exist_ok=True)
    for name in names:
        geo = os.path.join(out, name + ".geo")
        msh = os.path.join(out, name + ".msh")
        with open(geo, "w") as f:
            f.write(HEAD + SHAPES[name])
        subprocess.run(["gmsh", geo, "-2", "-format", "msh2", "-o", msh], check=True,
                       capture_output=True)
        m = meshio.read(msh)
        F = np.vstack([c.data for c in m.cells if c.type == "triangle"])
        used = np.unique(F)
        remap = -np.ones(len(m.points), int)
        remap[used] = np.arange(len(used))
        V = np.asarray(m.points[used], float)
        F = orient(remap[F], V)
        path = os.path.join(out, name + ".obj")
        meshio.write_points_cells(path, V, [("triangle", F)])
        print(path)


if __name__ == "__main__":
    main()
