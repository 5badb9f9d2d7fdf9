// The seed disk of examples/lammps-impact (radius 37 mm, 2.5 mm thick,
// from y = -2.5 mm to 0) in gmsh's tetrahedra, about 10^5 of them, for
// make bench's meshed body (share/bench.sh, part "mesh").
SetFactory("OpenCASCADE");
Cylinder(1) = {0, -0.0025, 0, 0, 0.0025, 0, 0.037, 2*Pi};
Mesh.CharacteristicLengthMax = 0.0008;
