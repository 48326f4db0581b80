// The mesh of scenes/user-mesh.toml, as a user would make it: a trapezoid with two cracks, a
// V-shaped polyline and a segment, embedded in the surface. Physical groups by name: "domain"
// (the triangles), "boundary" (∂Ω), "crack1", "crack2" (docs/scenes.md). Regenerate with
//   gmsh trapezoid-two-cracks.geo -2 -format msh41 -nt 1 -o trapezoid-two-cracks.msh
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
h = 0.3;
Point(1) = {-1, -1, 0, h};
Point(2) = {1, -1, 0, h};
Point(3) = {0.6, 1, 0, h};
Point(4) = {-0.6, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
// crack 1: (-0.5, -0.3) -> (0, -0.5) -> (0.4, -0.3)
Point(5) = {-0.5, -0.3, 0, h};
Point(6) = {0, -0.5, 0, h};
Point(7) = {0.4, -0.3, 0, h};
Line(5) = {5, 6};
Line(6) = {6, 7};
// crack 2: (-0.3, 0.4) -> (0.3, 0.4)
Point(8) = {-0.3, 0.4, 0, h};
Point(9) = {0.3, 0.4, 0, h};
Line(7) = {8, 9};
Line{5, 6, 7} In Surface{1};
Physical Surface("domain") = {1};
Physical Curve("boundary") = {1, 2, 3, 4};
Physical Curve("crack1") = {5, 6};
Physical Curve("crack2") = {7};
