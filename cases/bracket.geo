// CAD-like part for cases/poisson_curved_bracket.json, built with Gmsh's OpenCASCADE kernel:
// a 2 x 1 x 0.5 plate, a through hole (r 0.25) at (0.6, 0.5), the two vertical edges at x = 2
// filleted (r 0.25); every other edge is sharp (90 degrees). Dense surface, face tags = CAD faces:
//   gmsh cases/bracket.geo -2 -o cases/data/bracket.msh      (~20k triangles, 0.5 s)
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 0.5};
Cylinder(2) = {0.6, 0.5, -0.1, 0, 0, 0.7, 0.25};
BooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};
e() = Curve In BoundingBox{1.99, -0.01, -0.01, 2.01, 1.01, 0.51};
vertical() = {};
For i In {0 : #e() - 1}
  bb() = BoundingBox Curve{e(i)};
  If (Fabs(bb(5) - bb(2)) > 0.4)
    vertical() += e(i);
  EndIf
EndFor
Fillet{3}{vertical()}{0.25}
s() = Surface{:};
For i In {0 : #s() - 1}
  Physical Surface(s(i)) = {s(i)};
EndFor
Mesh.MeshSizeMin = 0.015;
Mesh.MeshSizeMax = 0.03;
Mesh.Binary = 1;
