// A plate with a hole: 40 x 20 x 2 mm, a hole of diameter 5 mm at its
// centre, and grips 3 mm long at each end (the physical volumes "left" and
// "right"; the rest is "body").  gmsh -3 makes its tetrahedra (pd-mesh),
// gmsh -2 its surface (pd-lattice --inside).  The mesh size is the
// variable h (m): gmsh -setnumber h 0.0005.
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.0005;
EndIf
L = 0.04; W = 0.02; T = 0.002; R = 0.0025; G = 0.003;
Box(1) = {0, 0, 0, G, W, T};
Box(2) = {G, 0, 0, L - 2 * G, W, T};
Box(3) = {L - G, 0, 0, G, W, T};
Cylinder(4) = {L / 2, W / 2, 0, 0, 0, T, R, 2 * Pi};
BooleanDifference(5) = { Volume{2}; Delete; }{ Volume{4}; Delete; };
v() = BooleanFragments{ Volume{1, 5, 3}; Delete; }{};
Physical Volume("left", 1) = {v(0)};
Physical Volume("body", 2) = {v(1)};
Physical Volume("right", 3) = {v(2)};
Mesh.CharacteristicLengthMax = h;
